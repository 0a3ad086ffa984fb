# Tests of the pipeline stages (include/semioctree/, src/).
foreach(t test_preprocess test_scan_io test_discretize test_occlusion test_update test_outputs
          test_figures)
  if(EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/${t}.cpp)
    semioctree_add_test(${t} SOURCES ${t}.cpp LIBS semioctree)
    target_include_directories(${t} PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
  endif()
endforeach()
if(TARGET test_occlusion)  # src/polynomial_atan2.h, which the returns are binned with
  target_include_directories(test_occlusion PRIVATE ${PROJECT_SOURCE_DIR})
endif()
if(TARGET test_discretize)
  find_package(PNG REQUIRED)  # reads the slices back, pixel by pixel
  target_link_libraries(test_discretize PRIVATE PNG::PNG)
endif()

# Benchmarks that need the synthetic scanner for their input.
if(TARGET semioctree_sim)
  semioctree_add_bench(bench_discretize SOURCES bench_discretize.cpp LIBS semioctree semioctree_sim)
endif()
if(TARGET semioctree_sim)
  semioctree_add_test(test_lab_discretization SOURCES test_lab_discretization.cpp LIBS semioctree semioctree_sim)
  target_include_directories(test_lab_discretization PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
endif()
if(TARGET semioctree_sim)
  semioctree_add_bench(bench_occlusion SOURCES bench_occlusion.cpp LIBS semioctree_sim_platform)
endif()
# RANSAC's plane segmentation with laned inlier counts (src/plane_segmentation.h).
semioctree_add_test(test_plane_segmentation SOURCES test_plane_segmentation.cpp LIBS semioctree)
target_include_directories(test_plane_segmentation PRIVATE ${PROJECT_SOURCE_DIR})
# The dense-array homogeneous grid, a baseline of the benchmarks (support/dense_grid.h; it
# shares the worker pool and the scanner's limits of src/).
semioctree_add_test(test_dense_grid SOURCES test_dense_grid.cpp LIBS semioctree)
target_include_directories(test_dense_grid PRIVATE ${CMAKE_CURRENT_SOURCE_DIR} ${PROJECT_SOURCE_DIR})
# The survey and nbv commands end to end (the survey needs the synthetic scanner).
if(TARGET semioctree_sim)
  semioctree_add_test(test_survey SOURCES test_survey.cpp LIBS nlohmann_json::nlohmann_json COST 120)
  target_include_directories(test_survey PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
  add_dependencies(test_survey semioctree_cli)
endif()
# The survey report: the page from a survey.json, and a survey's page in headless Chromium.
if(TARGET semioctree_sim)
  find_package(PNG REQUIRED)  # reads Chromium's screenshot back
  semioctree_add_test(test_report SOURCES test_report.cpp
                      LIBS semioctree nlohmann_json::nlohmann_json PNG::PNG)
  target_include_directories(test_report PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
  add_dependencies(test_report semioctree_cli)
endif()
if(TARGET test_figures)
  target_link_libraries(test_figures PRIVATE nlohmann_json::nlohmann_json)
endif()
# The survey stage from the library, with the simulated platform.
if(TARGET semioctree_sim_platform)
  semioctree_add_test(test_opening_match SOURCES test_opening_match.cpp LIBS semioctree_sim_platform)
  semioctree_add_test(test_survey_stage SOURCES test_survey_stage.cpp
                      LIBS semioctree_sim_platform nlohmann_json::nlohmann_json)
  target_include_directories(test_survey_stage PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
endif()
# Surveys of generated scenes (eval_generated, a benchmark-style program printing JSON), and
# a subset of them as a test with the acceptance thresholds (docs/generated-scenes.md).
# Built with the benchmarks only: the sanitizer build of CI, which has none, skips the test.
if(TARGET semioctree_sim_platform AND SEMIOCTREE_BUILD_BENCHMARKS)
  # The CLI's planning options, compiled once for the three programs that take them.
  add_library(semioctree_planning_options STATIC ${PROJECT_SOURCE_DIR}/src/cli/planning_options.cpp)
  target_link_libraries(semioctree_planning_options PUBLIC semioctree_sim_platform CLI11::CLI11)
  target_include_directories(semioctree_planning_options PUBLIC ${PROJECT_SOURCE_DIR}/src/cli)
endif()
if(TARGET semioctree_sim_platform)
  semioctree_add_bench(eval_generated SOURCES eval_generated.cpp
                       LIBS semioctree_planning_options nlohmann_json::nlohmann_json)
  if(TARGET eval_generated)
    # Rooms 1-8 with the acceptance thresholds (docs/generated-scenes.md); OFF skips them
    # (ctest lists the test as disabled) on a machine where minutes per scene are too many.
    option(SEMIOCTREE_TEST_GENERATED_SCENES
           "Run the generated-scenes acceptance test (rooms 1-8, a few minutes)" ON)
    add_test(NAME generated_scenes
             COMMAND eval_generated --kind room --seeds 1-8 --check
                     --cache ${CMAKE_BINARY_DIR}/coverage-cache)
    set_tests_properties(generated_scenes PROPERTIES LABELS slow TIMEOUT 3600 COST 330)
    # A floor of a corridor and three rooms whose doors are seen only obliquely from the
    # corridor (docs/generated-scenes.md, "Floors"): the survey must enter every room.
    add_test(NAME generated_floor
             COMMAND eval_generated --kind floor --seeds 12 --max-scans 40 --check
                     --min-coverage 95 --mean-coverage 95
                     --cache ${CMAKE_BINARY_DIR}/coverage-cache)
    set_tests_properties(generated_floor PROPERTIES LABELS slow TIMEOUT 1800 COST 100)
    if(NOT SEMIOCTREE_TEST_GENERATED_SCENES)
      set_tests_properties(generated_scenes generated_floor PROPERTIES DISABLED TRUE)
    endif()
  endif()
  # Benchmarks that run the survey stage with the CLI's planning defaults:
  # bench_floor, a survey at floor scale (60 × 45 m: NBV seconds, reference seconds, peak
  # memory); bench_update, the whole update of the map by each scan of a lab survey
  # against OctoMap's insert of the same scans.
  foreach(bench bench_floor bench_update)
    semioctree_add_bench(${bench} SOURCES ${bench}.cpp
                         LIBS semioctree_planning_options nlohmann_json::nlohmann_json)
  endforeach()
endif()
