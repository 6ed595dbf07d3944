# Runs one command of the vtloc CLI (or another shipped tool, e.g. vtloc-bench) and checks what it did:
#   cmake -DEXPECT_RC=<n> [-DEXPECT_STDOUT=<regex>] [-DEXPECT_STDERR=<regex>]
#         [-DEXPECT_FILES=<a|b|...>] [-DALLOW_LINES=1] -P run_cli.cmake -- <program> <args...>
# - the exit status must be EXPECT_RC;
# - a failure (EXPECT_RC != 0) prints exactly one line on stderr, starting with
#   "vtloc", matching EXPECT_STDERR (more lines with ALLOW_LINES, e.g. the
#   usage text); a success prints nothing on stderr, unless EXPECT_STDERR says
#   what it prints (a trace the environment asked for);
# - no validation-layer message, whatever the status (the tests set
#   VTLOC_VALIDATION=1, and the CLI reports each message on stderr);
# - no "internal error": every case here is a user's mistake, which the CLI
#   reports as such (its last resort names exceptions it did not expect).
set(cmd)
set(after_dashes FALSE)
math(EXPR last "${CMAKE_ARGC} - 1")
foreach(i RANGE ${last})
  if(after_dashes)
    list(APPEND cmd "${CMAKE_ARGV${i}}")
  elseif("${CMAKE_ARGV${i}}" STREQUAL "--")
    set(after_dashes TRUE)
  endif()
endforeach()
if(NOT cmd)
  message(FATAL_ERROR "run_cli.cmake: no command after --")
endif()
string(REPLACE "|" ";" expect_files "${EXPECT_FILES}")
foreach(f IN LISTS expect_files)
  file(REMOVE "${f}")
endforeach()

execute_process(COMMAND ${cmd} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
string(JOIN " " shown ${cmd})
set(report "command: ${shown}\nexit status: ${rc}\n--- stdout ---\n${out}--- stderr ---\n${err}")

if(err MATCHES "vtloc[-a-z]*: validation layer:")
  message(FATAL_ERROR "the validation layer reported problems\n${report}")
endif()
if(err MATCHES "internal error")
  message(FATAL_ERROR "a user's mistake reported as an internal error\n${report}")
endif()
if(NOT rc STREQUAL "${EXPECT_RC}")
  message(FATAL_ERROR "expected exit status ${EXPECT_RC}\n${report}")
endif()
string(STRIP "${err}" err_line)
if(EXPECT_RC EQUAL 0)
  if(NOT err_line STREQUAL "" AND NOT DEFINED EXPECT_STDERR)
    message(FATAL_ERROR "a successful run printed on stderr\n${report}")
  endif()
else()
  if(NOT ALLOW_LINES AND (err_line MATCHES "\n" OR NOT err_line MATCHES "^vtloc"))
    message(FATAL_ERROR "expected one line 'vtloc...' on stderr\n${report}")
  endif()
endif()
if(DEFINED EXPECT_STDERR AND NOT err MATCHES "${EXPECT_STDERR}")
  message(FATAL_ERROR "stderr does not match '${EXPECT_STDERR}'\n${report}")
endif()
if(DEFINED EXPECT_STDOUT AND NOT out MATCHES "${EXPECT_STDOUT}")
  message(FATAL_ERROR "stdout does not match '${EXPECT_STDOUT}'\n${report}")
endif()
foreach(f IN LISTS expect_files)
  if(NOT EXISTS "${f}")
    message(FATAL_ERROR "expected the file ${f}\n${report}")
  endif()
  file(SIZE "${f}" size)
  if(size EQUAL 0)
    message(FATAL_ERROR "${f} is empty\n${report}")
  endif()
endforeach()
