# Bad input through the command line: one table of inputs and the errors they give.
semioctree_add_test(test_bad_input SOURCES test_bad_input.cpp
                    LIBS semioctree nlohmann_json::nlohmann_json)
target_include_directories(test_bad_input PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
add_dependencies(test_bad_input semioctree_cli)
if(TARGET semioctree_sim)
  target_compile_definitions(test_bad_input PRIVATE SEMIOCTREE_TEST_SIM)
endif()
