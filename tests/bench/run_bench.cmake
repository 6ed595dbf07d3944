# Runs vtloc-bench once and checks what it did:
#   cmake -DEXPECT_RC=<n> [-DEXPECT_STDERR=<regex>] [-DCHECK="<python> <checker> <args>"]
#         -P run_bench.cmake -- <vtloc-bench> <args...>
# - the exit status must be EXPECT_RC; a failure prints one line on stderr
#   starting with "vtloc-bench:" and matching EXPECT_STDERR, a success prints
#   nothing there (with VTLOC_VALIDATION=1 that includes validation messages);
# - on success, CHECK (the JSON schema checker) must pass.
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
execute_process(COMMAND ${cmd} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
string(JOIN " " shown ${cmd})
set(report "command: ${shown}\nexit status: ${rc}\n--- stdout ---\n${out}--- stderr ---\n${err}")
if(NOT rc STREQUAL "${EXPECT_RC}")
  message(FATAL_ERROR "expected exit status ${EXPECT_RC}\n${report}")
endif()
string(STRIP "${err}" err_line)
if(EXPECT_RC EQUAL 0)
  if(NOT err_line STREQUAL "")
    message(FATAL_ERROR "a successful run printed on stderr\n${report}")
  endif()
  separate_arguments(check UNIX_COMMAND "${CHECK}")
  execute_process(COMMAND ${check} RESULT_VARIABLE crc OUTPUT_VARIABLE cout ERROR_VARIABLE cerr)
  if(NOT crc EQUAL 0)
    message(FATAL_ERROR "the report failed its check:\n${cout}${cerr}\n${report}")
  endif()
  message(STATUS "${cout}")
else()
  if(err_line MATCHES "\n" OR NOT err_line MATCHES "^vtloc-bench: " OR NOT err_line MATCHES "${EXPECT_STDERR}")
    message(FATAL_ERROR "expected one line on stderr matching '${EXPECT_STDERR}'\n${report}")
  endif()
endif()
