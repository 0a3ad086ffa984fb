# ctest script: install the build into a temporary prefix, configure and build
# tests/install_consumer against it with find_package(semioctree), run it; the
# same with the octomap_ext component only while the pipeline's dependencies
# cannot be found; an unknown component must fail; build examples/ on its own
# against the same prefix.
# Variables: BUILD_DIR, SOURCE_DIR, WORK_DIR, WITH_SIM (the survey example is built and run).

# Runs a command; on failure stops with `what`, the exit code and the command's output.
function(run_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

# Configures and builds the project in `source` against the installed prefix;
# further arguments go to the configure step.
function(build_against_prefix what source binary)
  run_step("configuring ${what}" ${CMAKE_COMMAND} -S ${source} -B ${binary}
           -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_BUILD_TYPE=Release ${ARGN})
  run_step("building ${what}" ${CMAKE_COMMAND} --build ${binary})
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
run_step("cmake --install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix)
build_against_prefix("the consumer" ${SOURCE_DIR}/tests/install_consumer ${WORK_DIR}/build)
run_step("the consumer" ${WORK_DIR}/build/consumer ${WORK_DIR}/tree.ot)
message(STATUS "${step_output}")
run_step("the reader (OctoMap's factory only)" ${WORK_DIR}/build/reader ${WORK_DIR}/tree.ot)
message(STATUS "${step_output}")
# The OctoMap extension alone must not need the pipeline's dependencies.
build_against_prefix("the reader with the octomap_ext component only"
                     ${SOURCE_DIR}/tests/install_consumer ${WORK_DIR}/build-octomap-ext
                     -DONLY_OCTOMAP_EXT=ON -DCMAKE_DISABLE_FIND_PACKAGE_PCL=ON
                     -DCMAKE_DISABLE_FIND_PACKAGE_Eigen3=ON
                     -DCMAKE_DISABLE_FIND_PACKAGE_dynamicEDT3D=ON
                     -DCMAKE_DISABLE_FIND_PACKAGE_nlohmann_json=ON -DCMAKE_DISABLE_FIND_PACKAGE_PkgConfig=ON)
run_step("the reader (octomap_ext component only)" ${WORK_DIR}/build-octomap-ext/reader
         ${WORK_DIR}/tree.ot)
message(STATUS "${step_output}")
# An unknown component: configuring fails and says which components there are.
file(WRITE ${WORK_DIR}/bogus/CMakeLists.txt
     "cmake_minimum_required(VERSION 3.16)\nproject(bogus NONE)\n"
     "find_package(semioctree REQUIRED COMPONENTS octomap_ext bogus)\n")
execute_process(COMMAND ${CMAKE_COMMAND} -S ${WORK_DIR}/bogus -B ${WORK_DIR}/bogus/build
                        -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT err MATCHES "no component 'bogus' \\(it has octomap_ext,[ \n]+pipeline,[ \n]+sim[ \n]+and[ \n]+sim_platform\\)")
  message(FATAL_ERROR "an unknown component was not refused clearly (${rc}):\n${out}\n${err}")
endif()
build_against_prefix("examples/ on its own" ${SOURCE_DIR}/examples ${WORK_DIR}/examples)
# The survey example, built against the installed package, surveys the small box room
# with the library alone (two scans at most, to keep the test short).
if(WITH_SIM)
  if(NOT EXISTS ${WORK_DIR}/examples/survey_scene)
    message(FATAL_ERROR "examples/survey_scene was not built against the installed package")
  endif()
  run_step("examples/survey_scene" ${WORK_DIR}/examples/survey_scene
           ${SOURCE_DIR}/sim/scenes/box-room.scene.json 2)
  message(STATUS "${step_output}")
  if(NOT step_output MATCHES "scan 0 at .*stopped because")
    message(FATAL_ERROR "examples/survey_scene did not report its scans:\n${step_output}")
  endif()
endif()
