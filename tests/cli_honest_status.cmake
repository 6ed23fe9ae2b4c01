# End-to-end: "complete" tells the truth whenever a run ends. A reconstruction is stopped by
# SIGINT, SIGTERM and SIGKILL the moment its map.ply appears (the keyframes are then being
# completed from the map, the last phase): SIGINT and SIGTERM exit 130 and 143 with a report
# that says "complete": false and the phase; after SIGKILL, report.json (if any) never says
# complete. A run refused for lost tracking exits 2 with "complete": false.
set(tmp "${CMAKE_CURRENT_BINARY_DIR}/cli_honest_status_tmp")
file(REMOVE_RECURSE "${tmp}")
file(MAKE_DIRECTORY "${tmp}")
find_program(BASH bash)
if(NOT BASH)
  message("SKIPPED: bash not found")
  return()
endif()

execute_process(COMMAND "${GLASSFUSION}" synth --scene glass-table --frames 40 --seed 3
                        --out "${tmp}/scene" RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "synth failed (${rc}): ${err}")
endif()

# Starts a reconstruction into DIR, sends SIGNAL as soon as DIR/map.ply exists; sets rc (the
# run's exit status) and finished (1 when it ended before the map appeared or the signal came).
function(stop_at_map signal dir)
  execute_process(COMMAND "${BASH}" -c "
\"$0\" reconstruct \"$1\" --out \"$2\" 2>\"$2.log\" >/dev/null &
pid=$!
while [ ! -e \"$2/map.ply\" ] && kill -0 $pid 2>/dev/null; do sleep 0.005; done
kill -$3 $pid 2>/dev/null
wait $pid
echo $?" "${GLASSFUSION}" "${tmp}/scene" "${dir}" "${signal}"
                  OUTPUT_VARIABLE out OUTPUT_STRIP_TRAILING_WHITESPACE)
  set(rc "${out}" PARENT_SCOPE)
endfunction()

# DIR/report.json's complete (ON/OFF, or NOTFOUND when there is no report) and stopped_during.
function(read_report dir)
  set(complete NOTFOUND PARENT_SCOPE)
  if(EXISTS "${dir}/report.json")
    file(READ "${dir}/report.json" report)
    string(JSON is_complete GET "${report}" complete)
    set(complete "${is_complete}" PARENT_SCOPE)
    string(JSON during ERROR_VARIABLE none GET "${report}" stopped_during)
    set(during "${during}" PARENT_SCOPE)
  endif()
endfunction()

foreach(case "INT;130" "TERM;143")
  list(GET case 0 signal)
  list(GET case 1 expected)
  stop_at_map(${signal} "${tmp}/run_${signal}")
  read_report("${tmp}/run_${signal}")
  if(rc EQUAL 0)
    # The run ended before the signal reached it: then it must say complete.
    if(NOT complete)
      message(FATAL_ERROR "SIG${signal}: exit 0 but complete is ${complete}")
    endif()
    message("SIG${signal} came after the run had ended (exit 0, complete)")
  elseif(NOT rc EQUAL expected)
    file(READ "${tmp}/run_${signal}.log" log)
    message(FATAL_ERROR "SIG${signal} during the completion: exit ${rc}, expected ${expected}: ${log}")
  elseif(NOT complete STREQUAL "OFF")
    message(FATAL_ERROR "SIG${signal} during the completion: exit ${rc} but complete is ${complete}")
  else()
    message("SIG${signal} at map.ply: exit ${rc}, complete false, stopped during ${during}")
  endif()
endforeach()

stop_at_map(KILL "${tmp}/run_KILL")
read_report("${tmp}/run_KILL")
if(rc EQUAL 137 AND complete)
  message(FATAL_ERROR "SIGKILL after map.ply left a report that says complete")
endif()
message("SIGKILL at map.ply: exit ${rc}, report complete: ${complete}")

file(REMOVE_RECURSE "${tmp}")
