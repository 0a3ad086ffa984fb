# Tests and benchmark of the OctoMap extension (octomap_ext/).
foreach(t test_semioctree test_traversal test_file_io test_export test_packed_key_map
          test_import)
  semioctree_add_test(${t} SOURCES ${t}.cpp LIBS octomap_ext)
  target_include_directories(${t} PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
endforeach()
# Its default map is the classified lab, scanned with the synthetic scanner.
if(TARGET semioctree_sim)
  semioctree_add_bench(bench_traversal SOURCES bench_traversal.cpp LIBS semioctree_sim_platform)
endif()

# The command-line tool (runs the built binary).
semioctree_add_test(test_cli SOURCES test_cli.cpp LIBS semioctree nlohmann_json::nlohmann_json)
target_include_directories(test_cli PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
target_compile_definitions(test_cli PRIVATE SEMIOCTREE_VERSION="${PROJECT_VERSION}")
add_dependencies(test_cli semioctree_cli)

# The installed CMake package works for an outside project.
set(SEMIOCTREE_INSTALL_TEST_SIM OFF)  # the survey example needs the simulator
if(TARGET semioctree_sim_platform)
  set(SEMIOCTREE_INSTALL_TEST_SIM ON)
endif()
add_test(NAME install_package
         COMMAND ${CMAKE_COMMAND} -DBUILD_DIR=${PROJECT_BINARY_DIR} -DSOURCE_DIR=${PROJECT_SOURCE_DIR}
                 -DWITH_SIM=${SEMIOCTREE_INSTALL_TEST_SIM}
                 -DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR}/install_package
                 -P ${CMAKE_CURRENT_SOURCE_DIR}/install_consumer/run.cmake)
set_tests_properties(install_package PROPERTIES TIMEOUT 600 COST 150)
