# The installed package from an outside project: installs BUILD_DIR into a fresh prefix under
# WORK_DIR, runs the installed physgrad command, then configures, builds and runs PROJECT_DIR
# against the library (and its own-experiment program, a run and an index, against
# physgrad::run). Any failing step fails.
# Set by the test: BUILD_DIR, PROJECT_DIR, WORK_DIR, CXX_COMPILER, CXX_FLAGS (may be empty).
cmake_minimum_required(VERSION 3.25)
file(REMOVE_RECURSE "${WORK_DIR}")
set(prefix "${WORK_DIR}/prefix")

# Runs the command after `what`; on success its output is in step_output.
function(run_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE status OUTPUT_VARIABLE output
                  ERROR_VARIABLE output)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "${what} failed (${status}):\n${output}")
  endif()
  set(step_output "${output}" PARENT_SCOPE)
endfunction()

run_step("install" "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${prefix}")
if(NOT EXISTS "${prefix}/include/physgrad/physics/simulator.hpp")
  message(FATAL_ERROR "install: the headers are missing from ${prefix}/include")
endif()
foreach(file libphysgrad.a libphysgrad_report.a libphysgrad_run.a
             physgradConfig.cmake physgradConfigVersion.cmake physgradTargets.cmake)
  file(GLOB_RECURSE found "${prefix}/*/${file}")
  if(NOT found)
    message(FATAL_ERROR "install: ${file} is missing from ${prefix}")
  endif()
endforeach()
# The installed headers hold no test hook (the run layer's fault points stay in src/run).
file(GLOB_RECURSE installed_headers "${prefix}/include/physgrad/*.hpp")
foreach(header ${installed_headers})
  file(STRINGS "${header}" hooks REGEX "fault_point|PHYSGRAD_FAULT")
  if(hooks)
    message(FATAL_ERROR "install: ${header} declares a test hook: ${hooks}")
  endif()
endforeach()
# Only the public headers are installed: none of cmake/private_headers.txt, and every header an
# installed one includes is installed too.
file(STRINGS "${PROJECT_DIR}/../../cmake/private_headers.txt" private_headers REGEX "^[^#]")
foreach(header ${private_headers})
  if(EXISTS "${prefix}/include/physgrad/${header}")
    message(FATAL_ERROR "install: the private header physgrad/${header} is installed")
  endif()
endforeach()
foreach(header ${installed_headers})
  file(STRINGS "${header}" includes REGEX "^#include \"physgrad/")
  foreach(line ${includes})
    string(REGEX REPLACE "^#include \"([^\"]+)\".*" "\\1" included "${line}")
    if(NOT EXISTS "${prefix}/include/${included}")
      message(FATAL_ERROR "install: ${header} includes ${included}, which is not installed")
    endif()
  endforeach()
endforeach()
# The command-line tool is installed and runs from there.
run_step("installed physgrad" "${prefix}/bin/physgrad" list)
if(NOT step_output MATCHES "scaled-toy")
  message(FATAL_ERROR "installed physgrad list: unexpected output:\n${step_output}")
endif()

run_step("configure" "${CMAKE_COMMAND}" -S "${PROJECT_DIR}" -B "${WORK_DIR}/build"
         "-DCMAKE_PREFIX_PATH=${prefix}" "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}"
         "-DCMAKE_CXX_FLAGS=${CXX_FLAGS}" -DCMAKE_BUILD_TYPE=Release)
if(NOT step_output MATCHES "physgrad 0\\.1\\.0 from ${prefix}/")
  message(FATAL_ERROR "configure: physgrad was not found in ${prefix}:\n${step_output}")
endif()
run_step("build" "${CMAKE_COMMAND}" --build "${WORK_DIR}/build")
run_step("run" "${WORK_DIR}/build/physgrad_outside")
message("${step_output}")
if(NOT step_output MATCHES "pg converged in 26 iterations")
  message(FATAL_ERROR "run: unexpected output")
endif()
# The experiment framework from the installed physgrad::run: a run folder and its index.
run_step("own experiment" "${WORK_DIR}/build/physgrad_outside_run" run "${WORK_DIR}/runs/a"
         --iters 20)
if(NOT step_output MATCHES "HIG \\(λ=0.01\\) final test loss")
  message(FATAL_ERROR "own experiment: unexpected output:\n${step_output}")
endif()
run_step("own experiment's index" "${WORK_DIR}/build/physgrad_outside_run" report
         "${WORK_DIR}/runs")
if(NOT EXISTS "${WORK_DIR}/runs/index.html")
  message(FATAL_ERROR "own experiment's index: no ${WORK_DIR}/runs/index.html")
endif()
