# CTest `package.consumer`: installs the build into a fresh prefix, builds
# apps/example_consumer against it with find_package(vtloc), runs it on the
# shipped example with the validation layer on, and runs the installed CLI's
# demo (which must find the installed models/ and examples/).
#   cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK=... -P package_test.cmake
function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    string(JOIN " " shown ${ARGN})
    message(FATAL_ERROR "${what} failed (${rc}): ${shown}\n${out}\n${err}")
  endif()
  set(out "${out}" PARENT_SCOPE)
  set(err "${err}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE "${WORK}")
set(prefix "${WORK}/prefix")
run("install" ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${prefix}")
run("configure the consumer" ${CMAKE_COMMAND} -S "${SOURCE_DIR}/apps/example_consumer" -B "${WORK}/build"
    -DCMAKE_BUILD_TYPE=Release "-DCMAKE_PREFIX_PATH=${prefix}")
run("build the consumer" ${CMAKE_COMMAND} --build "${WORK}/build" -j2)

set(share "${prefix}/share/vtloc")
run("run the consumer" "${WORK}/build/vtloc_example_consumer" "${share}/models/vtloc-r18-half-random.safetensors"
    "${share}/examples/mug.glb" "${share}/examples/touch_01.png" "${WORK}/heatmap.ply")
message(STATUS "consumer:\n${out}")
if(NOT out MATCHES "contact \\(" OR NOT EXISTS "${WORK}/heatmap.ply" OR NOT err STREQUAL "")
  message(FATAL_ERROR "unexpected consumer output:\n${out}\n${err}")
endif()

run("installed vtloc demo" "${prefix}/bin/vtloc" demo --out "${WORK}/demo")
string(FIND "${out}" "${share}/models/" at)
string(FIND "${out}" "${share}/examples/potato_tour" at_ex)
if(at EQUAL -1 OR at_ex EQUAL -1 OR NOT EXISTS "${WORK}/demo/belief.png")
  message(FATAL_ERROR "the installed demo did not use the installed files:\n${out}")
endif()
