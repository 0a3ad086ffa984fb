# Door and window detection (src/openings.cpp); the lab acceptance scans with sim/.
if(TARGET semioctree_sim)
  semioctree_add_test(test_openings SOURCES test_openings.cpp LIBS semioctree semioctree_sim)
  target_include_directories(test_openings PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
endif()
