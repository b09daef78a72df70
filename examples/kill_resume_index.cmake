# A program's own experiment end to end: PROGRAM (a list: the program and its first arguments)
# runs it whole into WORK_DIR/whole; runs it again into WORK_DIR/part, killed (SIGKILL, through
# the run layer's fault point) just after its KILL_AT-th checkpoint; resumes WORK_DIR/part, which
# must end with the final losses of the whole run; and writes the index of WORK_DIR, which must
# list both folders. RUN_OPTIONS are the options of both runs. Any failing step fails.
cmake_minimum_required(VERSION 3.25)
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

# Runs PROGRAM with the arguments after `what`; its status in step_status, its output (stdout)
# in step_output, and stderr shown.
function(run_program what)
  execute_process(COMMAND ${PROGRAM} ${ARGN} RESULT_VARIABLE status OUTPUT_VARIABLE output
                  ERROR_VARIABLE errors)
  message("${what}: ${status}\n${output}${errors}")
  set(step_status "${status}" PARENT_SCOPE)
  set(step_output "${output}" PARENT_SCOPE)
endfunction()

# The lines "LABEL final test loss X" of an output.
function(final_lines output variable)
  string(REGEX MATCHALL "[^\n]* final test loss [^\n]*" lines "${output}")
  set(${variable} "${lines}" PARENT_SCOPE)
endfunction()

run_program("whole run" run "${WORK_DIR}/whole" ${RUN_OPTIONS})
if(NOT step_status EQUAL 0)
  message(FATAL_ERROR "the whole run failed")
endif()
final_lines("${step_output}" whole)
if(NOT whole)
  message(FATAL_ERROR "the whole run printed no final test loss")
endif()

set(ENV{PHYSGRAD_FAULT} "kill@checkpoint:${KILL_AT}")
run_program("killed run" run "${WORK_DIR}/part" ${RUN_OPTIONS})
unset(ENV{PHYSGRAD_FAULT})
if(NOT step_status MATCHES "[Kk]illed|-9|137")
  message(FATAL_ERROR "the run was not killed at checkpoint ${KILL_AT}: ${step_status}")
endif()
if(NOT EXISTS "${WORK_DIR}/part/checkpoint.pgc" OR EXISTS "${WORK_DIR}/part/summary.json")
  message(FATAL_ERROR "the killed run's folder does not hold a checkpoint and no result")
endif()

run_program("resumed run" resume "${WORK_DIR}/part")
if(NOT step_status EQUAL 0)
  message(FATAL_ERROR "the resumed run failed")
endif()
final_lines("${step_output}" resumed)
if(NOT resumed STREQUAL whole)
  message(FATAL_ERROR "the resumed run ended with\n${resumed}\nthe whole run with\n${whole}")
endif()
if(EXISTS "${WORK_DIR}/part/checkpoint.pgc" OR NOT EXISTS "${WORK_DIR}/part/summary.json")
  message(FATAL_ERROR "the resumed run's folder still holds its checkpoint or no result")
endif()

run_program("index" report "${WORK_DIR}")
if(NOT step_status EQUAL 0)
  message(FATAL_ERROR "the index failed")
endif()
file(READ "${WORK_DIR}/index.html" index)
foreach(folder whole part)
  if(NOT index MATCHES "href=\"(\\./)?${folder}/report.html\"")
    message(FATAL_ERROR "${WORK_DIR}/index.html does not link ${folder}/report.html")
  endif()
endforeach()
