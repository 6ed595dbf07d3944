# Builds the eval tests' datasets: a tiny synthetic one with `vtloc synth`
# (a uniform sphere and a non-uniform comb, 20 contacts of which 6 test,
# 128 points: the tiny model's count; single views too), and a copy with one
# test touch's image deleted and the sphere's view.json removed.
#   cmake -DVTLOC=<exe> -DOUT=<dir> -P make_datasets.cmake
# (and the renders of earlier runs, which eval.run.outputs counts)
file(REMOVE_RECURSE "${OUT}/ds" "${OUT}/ds_missing" "${OUT}/render")
execute_process(COMMAND "${VTLOC}" synth --out "${OUT}/ds" --shape sphere --shape comb_fine --contacts 20 --seed 3 --indentation
                        --n-points 128 --view
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS "${OUT}/ds/dataset.json")
  message(FATAL_ERROR "vtloc synth failed (${rc})\n${out}\n${err}")
endif()

file(COPY "${OUT}/ds/" DESTINATION "${OUT}/ds_missing")
# The first test touch of comb_fine: find its image column in touches.csv.
set(dir "${OUT}/ds_missing/objects/comb_fine")
file(STRINGS "${dir}/touches.csv" lines)
list(GET lines 0 header)
string(REPLACE "," ";" header "${header}")
list(FIND header "split" split_col)
list(FIND header "image" image_col)
list(REMOVE_AT lines 0)
set(victim "")
foreach(line IN LISTS lines)
  string(REPLACE "," ";" cells "${line}")
  list(GET cells ${split_col} split)
  if(split STREQUAL "test")
    list(GET cells ${image_col} victim)
    break()
  endif()
endforeach()
if(victim STREQUAL "" OR NOT EXISTS "${dir}/${victim}")
  message(FATAL_ERROR "no test touch image found in ${dir}/touches.csv")
endif()
file(REMOVE "${dir}/${victim}")
message(STATUS "removed ${dir}/${victim}")
file(REMOVE "${OUT}/ds_missing/objects/sphere/view.json")  # for eval.cloud_view_missing
