# ctest script: install the build into a temporary prefix, configure and build
# tests/install_consumer against it with find_package(semioctree), run it; build
# examples/ on its own against the same prefix.
# Variables: BUILD_DIR, SOURCE_DIR, WORK_DIR.

# Runs a command; on failure stops with `what`, the exit code and the command's output.
function(run_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

# Configures and builds the project in `source` against the installed prefix.
function(build_against_prefix what source binary)
  run_step("configuring ${what}" ${CMAKE_COMMAND} -S ${source} -B ${binary}
           -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_BUILD_TYPE=Release)
  run_step("building ${what}" ${CMAKE_COMMAND} --build ${binary})
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
run_step("cmake --install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix)
build_against_prefix("the consumer" ${SOURCE_DIR}/tests/install_consumer ${WORK_DIR}/build)
run_step("the consumer" ${WORK_DIR}/build/consumer ${WORK_DIR}/tree.ot)
message(STATUS "${step_output}")
run_step("the reader (OctoMap's factory only)" ${WORK_DIR}/build/reader ${WORK_DIR}/tree.ot)
message(STATUS "${step_output}")
build_against_prefix("examples/ on its own" ${SOURCE_DIR}/examples ${WORK_DIR}/examples)
