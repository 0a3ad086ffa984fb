# Door and window detection (src/openings.cpp); the lab acceptance scans with sim/, matched
# with the truth by sim_platform/ (opening_match.h).
if(TARGET semioctree_sim_platform)
  semioctree_add_test(test_openings SOURCES test_openings.cpp LIBS semioctree_sim_platform)
  target_include_directories(test_openings PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
endif()
