# End-to-end: nothing that is not glassfusion's is ever deleted (DESIGN.md). On a small synthetic
# capture: --force pointed at the capture itself, at its parent, inside it, or at a folder of the
# user's that holds a camera.json deletes nothing and says why (exit 2); --force over an earlier
# run keeps the user's files beside it; a second run into a folder another run holds (its lock
# taken by flock(1), then a real run in the background) fails at once; batch gives captures with
# the same folder name distinct outputs, and reruns a capture whose frames changed since.
set(tmp "${CMAKE_CURRENT_BINARY_DIR}/cli_safe_outputs_tmp")
file(REMOVE_RECURSE "${tmp}")
file(MAKE_DIRECTORY "${tmp}")

include("${CMAKE_CURRENT_LIST_DIR}/run_and_expect.cmake")

# Every file under `dir` with its content's hash, as one string: equal before and after means
# nothing was deleted, added or changed.
function(snapshot dir var)
  file(GLOB_RECURSE files LIST_DIRECTORIES true "${dir}/*")
  list(SORT files)
  set(s "")
  foreach(f ${files})
    if(IS_DIRECTORY "${f}")
      string(APPEND s "${f}/\n")
    else()
      file(SHA1 "${f}" h)
      string(APPEND s "${f} ${h}\n")
    endif()
  endforeach()
  set(${var} "${s}" PARENT_SCOPE)
endfunction()

function(expect_unchanged what dir before)
  snapshot("${dir}" after)
  if(NOT after STREQUAL before)
    message(FATAL_ERROR "${what}: ${dir} changed:\nbefore:\n${before}\nafter:\n${after}")
  endif()
endfunction()

run("${GLASSFUSION}" synth --scene glass-table --frames 8 --seed 5 --out "${tmp}/x/cap")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "synth failed (${rc}): ${err}")
endif()
file(WRITE "${tmp}/x/cap/NOTES.txt" "the user's notes on this capture\n")
file(WRITE "${tmp}/x/thesis.tex" "the user's thesis\n")
snapshot("${tmp}/x" x_before)

# 1. --force at the capture itself, at its parent, and inside it: refused, nothing touched.
foreach(command reconstruct compare)
  run("${GLASSFUSION}" ${command} "${tmp}/x/cap" --out "${tmp}/x/cap" --force)
  expect("${command} --out the capture --force" 2 "^error: .*/x/cap: .*is the input")
  expect_unchanged("${command} --out the capture --force" "${tmp}/x" "${x_before}")
  run("${GLASSFUSION}" ${command} "${tmp}/x/cap" --out "${tmp}/x" --force)
  expect("${command} --out the capture's parent --force" 2 "^error: .*/x: .*contains the input")
  expect_unchanged("${command} --out the capture's parent --force" "${tmp}/x" "${x_before}")
  run("${GLASSFUSION}" ${command} "${tmp}/x/cap" --out "${tmp}/x/cap/run" --force)
  expect("${command} --out inside the capture" 2 "^error: .*/x/cap/run: .*lies inside the input")
  expect_unchanged("${command} --out inside the capture" "${tmp}/x" "${x_before}")
endforeach()

# 2. A folder of the user's with a camera.json (as every capture has) and a thesis: not a run.
file(WRITE "${tmp}/proj/camera.json" "{}\n")
file(WRITE "${tmp}/proj/thesis.tex" "chapter 1\n")
snapshot("${tmp}/proj" proj_before)
foreach(command reconstruct compare)
  run("${GLASSFUSION}" ${command} "${tmp}/x/cap" --out "${tmp}/proj" --force)
  expect("${command} --force into the user's folder" 2 "^error: .*/proj: .*holds no run")
  expect_unchanged("${command} --force into the user's folder" "${tmp}/proj" "${proj_before}")
endforeach()

# 3. --force over an earlier run removes what that run wrote and keeps the user's files beside it.
run("${GLASSFUSION}" reconstruct "${tmp}/x/cap" --out "${tmp}/run")
expect("first run" 0 "")
if(NOT EXISTS "${tmp}/run/.glassfusion-run" OR NOT EXISTS "${tmp}/run/keyframes")
  message(FATAL_ERROR "a run folder without its marker .glassfusion-run or its keyframes/")
endif()
file(WRITE "${tmp}/run/my_notes.txt" "mine\n")
file(WRITE "${tmp}/run/keyframes/my_pick.txt" "mine too\n")
run("${GLASSFUSION}" reconstruct "${tmp}/x/cap" --out "${tmp}/run" --force --no-fill)
expect("--force over an earlier run" 0 "")
if(NOT EXISTS "${tmp}/run/my_notes.txt" OR NOT EXISTS "${tmp}/run/keyframes/my_pick.txt")
  message(FATAL_ERROR "--force deleted the user's files beside the earlier run")
endif()
file(GLOB left "${tmp}/run/keyframes/*.png")
if(left)
  message(FATAL_ERROR "--force left the earlier run's keyframes: ${left}")
endif()
expect_unchanged("the runs above" "${tmp}/x" "${x_before}")

# 4. A second run into a folder another run is writing fails at once (exit 2), deleting nothing.
find_program(FLOCK flock)
if(FLOCK)
  snapshot("${tmp}/run" run_before)
  run("${FLOCK}" -n "${tmp}/run/.glassfusion-run.lock" "${GLASSFUSION}" reconstruct
      "${tmp}/x/cap" --out "${tmp}/run" --force)
  expect("a run into a locked folder" 2
         "^error: .*/run: another glassfusion run is writing here \\(pid [0-9]+\\)")
  expect_unchanged("a run into a locked folder" "${tmp}/run" "${run_before}")
  file(MAKE_DIRECTORY "${tmp}/batch_locked")
  run("${FLOCK}" -n "${tmp}/batch_locked/.glassfusion-run.lock" "${GLASSFUSION}" batch
      "${tmp}/x" --out "${tmp}/batch_locked")
  expect("a batch into a locked folder" 2
         "^error: .*/batch_locked: another glassfusion run is writing here")
else()
  message("flock(1) not found: the lock is checked with a real run only")
endif()
# A real run in the background: the second starts once the first has marked its folder.
execute_process(
  COMMAND sh -c "\"$0\" reconstruct \"$1\" --out \"$2\" >/dev/null 2>&1 & first=$!
                 while [ ! -e \"$2/.glassfusion-run\" ]; do sleep 0.02; done
                 \"$0\" reconstruct \"$1\" --out \"$2\" --force
                 second=$?; wait $first; echo \"first=$? second=$second\""
          "${GLASSFUSION}" "${tmp}/x/cap" "${tmp}/live"
  OUTPUT_VARIABLE both ERROR_VARIABLE err)
if(NOT both MATCHES "first=0 second=2" OR NOT err MATCHES "another glassfusion run is writing here")
  message(FATAL_ERROR "two runs into one folder: ${both} ${err}")
endif()

# 5. batch: x/cap, y/cap and z/cap_2 get three distinct folders; each holds its own capture's run.
file(COPY "${tmp}/x/cap/" DESTINATION "${tmp}/y/cap")
file(COPY "${tmp}/x/cap/" DESTINATION "${tmp}/z/cap_2")
file(WRITE "${tmp}/list.txt" "x/cap\ny/cap\nz/cap_2\n")
run("${GLASSFUSION}" batch "${tmp}/list.txt" --out "${tmp}/batch" --jobs 2)
expect("batch over same-named captures" 0 "")
if(NOT out MATCHES "3 captures: 3 done \\(0 of them earlier\\), 0 failed")
  message(FATAL_ERROR "batch over same-named captures: ${out}")
endif()
file(STRINGS "${tmp}/batch/summary.csv" names REGEX "^cap")
list(TRANSFORM names REPLACE ",.*" "")
if(NOT names STREQUAL "cap;cap_2;cap_2_2")
  message(FATAL_ERROR "batch names: ${names} (want cap;cap_2;cap_2_2)")
endif()
foreach(pair "cap=x/cap" "cap_2=y/cap" "cap_2_2=z/cap_2")
  string(REPLACE "=" ";" pair "${pair}")
  list(GET pair 0 name)
  list(GET pair 1 input)
  file(READ "${tmp}/batch/${name}/compare.json" compare)
  string(JSON got GET "${compare}" input)
  if(NOT got MATCHES "/${input}$")
    message(FATAL_ERROR "batch/${name} holds the run of ${got}, not of ${input}")
  endif()
endforeach()

# 6. Resume: nothing changed, nothing rerun; a frame of y/cap edited, that capture is rerun.
run("${GLASSFUSION}" batch "${tmp}/list.txt" --out "${tmp}/batch")
if(NOT rc EQUAL 0 OR NOT out MATCHES "3 done \\(3 of them earlier\\)")
  message(FATAL_ERROR "batch resume without changes: ${rc} ${out} ${err}")
endif()
file(GLOB depth_frames "${tmp}/y/cap/depth/*.png")
list(SORT depth_frames)
list(GET depth_frames 0 first_frame)
list(GET depth_frames 1 second_frame)
file(REMOVE "${first_frame}")
file(COPY_FILE "${second_frame}" "${first_frame}")
run("${GLASSFUSION}" batch "${tmp}/list.txt" --out "${tmp}/batch")
if(NOT rc EQUAL 0 OR NOT out MATCHES "3 done \\(2 of them earlier\\)")
  message(FATAL_ERROR "batch after editing a frame of y/cap did not rerun it: ${rc} ${out} ${err}")
endif()

file(REMOVE_RECURSE "${tmp}")
message("safe outputs: every refusal deleted nothing and said why; locks and batch names held")
