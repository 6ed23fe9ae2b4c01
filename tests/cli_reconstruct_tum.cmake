# End-to-end: `glassfusion reconstruct` on the first 40 frames of the TUM head sequence writes a
# TUM trajectory and report.json; `glassfusion eval` scores it against the motion-capture truth,
# and `glassfusion bench` runs the OpenCV peers on the same frames.
set(input "${DATASETS}/tum_fr1_xyz_head")
if(NOT EXISTS "${input}")
  message("SKIPPED: ${input} not present")
  return()
endif()
set(out "${CMAKE_CURRENT_BINARY_DIR}/cli_reconstruct_tmp")
file(REMOVE_RECURSE "${out}")
execute_process(COMMAND "${GLASSFUSION}" reconstruct "${input}" --out "${out}" --frames 0:40 --no-fill
                RESULT_VARIABLE rc OUTPUT_VARIABLE stdout ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "reconstruct failed (${rc}): ${err}")
endif()
file(STRINGS "${out}/trajectory.txt" lines REGEX "^[0-9]")
list(LENGTH lines n)
if(NOT n EQUAL 40)
  message(FATAL_ERROR "trajectory has ${n} poses, expected 40")
endif()
file(READ "${out}/report.json" report)
string(JSON frames GET "${report}" frames)
string(JSON track_ms GET "${report}" stages track median_ms)
string(JSON lost GET "${report}" tracking lost_frames)
if(NOT frames EQUAL 40 OR NOT lost EQUAL 0)
  message(FATAL_ERROR "unexpected report: ${report}")
endif()
execute_process(COMMAND "${GLASSFUSION}" eval --gt "${input}/groundtruth.txt" --est "${out}/trajectory.txt"
                RESULT_VARIABLE rc OUTPUT_VARIABLE eval_out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "eval failed (${rc}): ${err}")
endif()
string(JSON ate GET "${eval_out}" ate_rmse_m)
# 40 frames of fr1_xyz: a few centimetres of motion; tracking must stay well under 1.5 cm.
if(ate GREATER 0.015)
  message(FATAL_ERROR "ATE ${ate} m over 40 frames exceeds 1.5 cm")
endif()
execute_process(COMMAND "${GLASSFUSION}" bench "${input}" --frames 0:10
                RESULT_VARIABLE rc OUTPUT_VARIABLE bench_out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT bench_out MATCHES "opencv RgbdICPOdometry" OR NOT bench_out MATCHES "cores")
  message(FATAL_ERROR "bench failed (${rc}): ${err} ${bench_out}")
endif()
# Stereo fill timed on one core as reconstruct pairs and fills keyframes (every 2nd frame here).
execute_process(COMMAND "${GLASSFUSION}" bench "${input}" --frames 0:40 --no-peers --fill-every 2
                RESULT_VARIABLE rc OUTPUT_VARIABLE bench_out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT bench_out MATCHES
   "stereo fill, one core: ([0-9]+) pairs, median ([0-9.]+) ms/pair[^\n]*, ([0-9.]+)% of hole")
  message(FATAL_ERROR "bench --fill-every failed (${rc}): ${err} ${bench_out}")
endif()
set(fill_pairs ${CMAKE_MATCH_1})
set(fill_ms ${CMAKE_MATCH_2})
set(fill_percent ${CMAKE_MATCH_3})
if(fill_pairs LESS 3 OR NOT fill_percent GREATER 5)
  message(FATAL_ERROR "bench stereo fill: ${fill_pairs} pairs, ${fill_percent}% filled: ${bench_out}")
endif()
file(REMOVE_RECURSE "${out}")
message("reconstruct ok: 40 frames, ATE ${ate} m, tracking median ${track_ms} ms; stereo fill "
        "${fill_ms} ms/pair on one core over ${fill_pairs} pairs, ${fill_percent}% filled")
