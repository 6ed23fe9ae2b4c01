# End-to-end: `glassfusion batch` on one machine over a folder of three captures (two small
# synthetic ones with ground truth, one broken): the good ones complete with their ATE and
# completeness gain in summary.csv, the broken one is retried once and reported without stopping
# the others (exit 2), and a second run skips what is done.
set(work "${CMAKE_CURRENT_BINARY_DIR}/cli_batch_tmp")
file(REMOVE_RECURSE "${work}")
file(MAKE_DIRECTORY "${work}/caps/broken")
file(WRITE "${work}/caps/broken/rgb.txt" "not a capture\n")
foreach(seed 41 42)
  execute_process(COMMAND "${GLASSFUSION}" synth --scene glass-table --frames 8 --seed ${seed}
                          --out "${work}/caps/glass${seed}" RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "synth failed (${rc})")
  endif()
endforeach()
execute_process(COMMAND "${GLASSFUSION}" batch "${work}/caps" --out "${work}/out" --jobs 2
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(NOT rc EQUAL 2 OR NOT out MATCHES "3 captures: 2 done \\(0 of them earlier\\), 1 failed")
  message(FATAL_ERROR "batch: exit ${rc} (want 2: one capture failed), ${out} ${err}")
endif()
file(STRINGS "${work}/out/summary.csv" rows)
foreach(seed 41 42)
  list(FILTER rows EXCLUDE REGEX "^glass${seed},done,8,[0-9.]+,0\\.00[0-9]+,[0-9]+,[0-9]+,0\\.[0-9]+,")
endforeach()
list(FILTER rows EXCLUDE REGEX "^broken,failed,.*a TUM folder needs both rgb.txt and depth.txt")
list(FILTER rows EXCLUDE REGEX "^name,status,frames")
if(rows)
  message(FATAL_ERROR "unexpected summary.csv rows: ${rows}")
endif()
file(READ "${work}/out/batch/broken.json" broken)
string(JSON attempts GET "${broken}" attempts)
if(NOT attempts EQUAL 2 OR NOT EXISTS "${work}/out/summary.html"
   OR NOT EXISTS "${work}/out/glass41/report.html")
  message(FATAL_ERROR "broken capture tried ${attempts} times (want 2), or no summary.html/report")
endif()
# Resume: the complete captures are skipped.
execute_process(COMMAND "${GLASSFUSION}" batch "${work}/caps" --out "${work}/out"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_QUIET)
if(NOT out MATCHES "2 done \\(2 of them earlier\\), 1 failed")
  message(FATAL_ERROR "second batch run did not skip the done captures: ${out}")
endif()
# A manifest file; a bad line is refused with its number.
file(WRITE "${work}/list.txt" "# captures\ncaps/glass41\ncaps/glass42 --confg x.json\n")
execute_process(COMMAND "${GLASSFUSION}" batch "${work}/list.txt" --out "${work}/out2"
                RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
if(NOT rc EQUAL 2 OR NOT err MATCHES "list.txt: line 3")
  message(FATAL_ERROR "bad manifest line: exit ${rc}, ${err}")
endif()
file(REMOVE_RECURSE "${work}")
