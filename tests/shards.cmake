# Writes the CTest tests of one Catch spec: one test per test_*.cpp file that
# holds a matching case, running that file's matching cases in one process.
# (One process per case spent most of the README command's C++ test time on
# process start, device creation and compiling the same pipelines again.)
#   cmake -DBIN=<vtloc_tests> -DSPEC=<catch spec> -DPREFIX=<name prefix>
#         -DPROPS=<set_tests_properties arguments, '|' for ';'> -DOUT=<file> -P shards.cmake
# Catch's -# tags each case with its file ([#test_conv]); --list-tags honours the
# spec, so each file tag it prints is a file with at least one matching case.
# A ',' in SPEC is Catch's "or": each alternative is listed on its own, and a
# file's test runs only the alternatives that match there (-w NoTests fails a run
# in which any one of them matches nothing).
# Specs here are tags only: a test name's escaped ',' or quotes would split wrongly.
if(SPEC MATCHES "[\\\"]")
  message(FATAL_ERROR "shards.cmake takes tag specs only, not \"${SPEC}\"")
endif()
string(REPLACE "," ";" alternatives "${SPEC}")
set(files "")
foreach(alt IN LISTS alternatives)
  execute_process(COMMAND "${BIN}" "-#" --list-tags "${alt}"
                  OUTPUT_VARIABLE listed RESULT_VARIABLE rc)
  # Catch 2's listings exit with the number of lines they list; a crash is a string.
  if(NOT rc MATCHES "^[0-9]+$")
    message(FATAL_ERROR "${BIN} -# --list-tags \"${alt}\" failed: ${rc}")
  endif()
  string(REGEX MATCHALL "\\[#[A-Za-z0-9_]+\\]" tags "${listed}")
  if(NOT tags)
    message(FATAL_ERROR "the Catch spec \"${alt}\" matches no test case in ${BIN}")
  endif()
  foreach(tag IN LISTS tags)
    string(REGEX REPLACE "^\\[#([A-Za-z0-9_]+)\\]$" "\\1" file "${tag}")
    list(APPEND files "${file}")
    list(APPEND "alts_${file}" "${tag}${alt}")
  endforeach()
endforeach()
list(REMOVE_DUPLICATES files)
list(SORT files)
string(REPLACE "|" ";" props "${PROPS}")
set(text "")
foreach(file IN LISTS files)
  string(REGEX REPLACE "^test_" "" short "${file}")
  set(name "${PREFIX}${short}")
  list(JOIN "alts_${file}" "," spec)
  # -w NoTests: a spec that matches nothing fails rather than passing.
  string(APPEND text "add_test([==[${name}]==] [==[${BIN}]==] \"-#\" [==[${spec}]==] -w NoTests)\n")
  if(props)
    string(APPEND text "set_tests_properties([==[${name}]==] PROPERTIES")
    foreach(p IN LISTS props)
      string(APPEND text " [==[${p}]==]")
    endforeach()
    string(APPEND text ")\n")
  endif()
endforeach()
file(WRITE "${OUT}.tmp" "${text}")
file(RENAME "${OUT}.tmp" "${OUT}")
