# Tests of the pipeline stages (include/semioctree/, src/).
foreach(t test_preprocess test_scan_io test_discretize test_occlusion)
  if(EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/${t}.cpp)
    semioctree_add_test(${t} SOURCES ${t}.cpp LIBS semioctree)
    target_include_directories(${t} PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
  endif()
endforeach()
if(TARGET test_discretize)
  target_link_libraries(test_discretize PRIVATE PNG::PNG)
endif()

# Benchmarks that need the synthetic scanner for their input.
if(TARGET semioctree_sim)
  semioctree_add_bench(bench_discretize SOURCES bench_discretize.cpp LIBS semioctree semioctree_sim)
  target_compile_definitions(bench_discretize PRIVATE SEMIOCTREE_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
endif()
if(TARGET semioctree_sim)
  semioctree_add_test(test_lab_discretization SOURCES test_lab_discretization.cpp LIBS semioctree semioctree_sim)
endif()
