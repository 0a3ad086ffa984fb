# Tests and benchmark of the synthetic scanner (sim/). Included from tests/CMakeLists.txt.
semioctree_add_test(test_scene SOURCES ${PROJECT_SOURCE_DIR}/tests/test_scene.cpp
  LIBS semioctree_sim nlohmann_json::nlohmann_json octomap octomath)
semioctree_add_test(test_raycaster SOURCES ${PROJECT_SOURCE_DIR}/tests/test_raycaster.cpp LIBS semioctree_sim)
semioctree_add_test(test_scanner SOURCES ${PROJECT_SOURCE_DIR}/tests/test_scanner.cpp LIBS semioctree_sim)
semioctree_add_test(test_robot SOURCES ${PROJECT_SOURCE_DIR}/tests/test_robot.cpp LIBS semioctree_sim)
semioctree_add_test(test_ground_truth SOURCES ${PROJECT_SOURCE_DIR}/tests/test_ground_truth.cpp LIBS semioctree_sim)
semioctree_add_test(test_scene_generator SOURCES ${PROJECT_SOURCE_DIR}/tests/test_scene_generator.cpp
  LIBS semioctree_sim)
# The CLI tests in test_scene and test_scanner run the built tool.
if(TARGET semioctree_cli)
  add_dependencies(test_scene semioctree_cli)
  add_dependencies(test_scanner semioctree_cli)
  add_dependencies(test_scene_generator semioctree_cli)
endif()
semioctree_add_bench(bench_raycast SOURCES ${PROJECT_SOURCE_DIR}/tests/bench_raycast.cpp LIBS semioctree_sim)
# Shared test helpers (tests/support/).
foreach(t test_scene test_scanner test_scene_generator)
  target_include_directories(${t} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
endforeach()
# Coverage (sim/src/coverage/): one test per module; test scenes in tests/support/coverage_scenes.h.
foreach(module visibility reference cache measure misses plan)
  semioctree_add_test(test_coverage_${module}
    SOURCES ${PROJECT_SOURCE_DIR}/tests/test_coverage_${module}.cpp LIBS semioctree_sim)
  target_include_directories(test_coverage_${module} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
endforeach()
