# Next-Best-View candidates, scores and the stop percentage (src/nbv/, docs/nbv.md).
semioctree_add_test(test_nbv_scoring SOURCES test_nbv_scoring.cpp LIBS semioctree)
target_include_directories(test_nbv_scoring PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
semioctree_add_test(test_nbv_candidates SOURCES test_nbv_candidates.cpp LIBS semioctree)
target_include_directories(test_nbv_candidates PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
semioctree_add_test(test_nbv SOURCES test_nbv.cpp LIBS semioctree)
target_include_directories(test_nbv PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
# The lab tests need the synthetic scanner for their input.
if(TARGET semioctree_sim)
  target_link_libraries(test_nbv PRIVATE semioctree_sim)
  target_compile_definitions(test_nbv PRIVATE SEMIOCTREE_HAVE_SIM=1)
  semioctree_add_bench(bench_nbv SOURCES bench_nbv.cpp LIBS semioctree semioctree_sim)
endif()
