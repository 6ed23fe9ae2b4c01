# End-to-end on real frames with vertical camera motion, which no capture we have holds: the
# first 40 frames of the TUM mid sequence (the camera moves sideways), punched by punch-holes.py,
# then turned a quarter turn about the optical axis by rotate_capture.py (portrait 480x640 images,
# camera.json and ground truth to match): the same physical camera on its side, now moving
# vertically in its images. `glassfusion reconstruct` (fill, fusion, loop closure) runs on both;
# the rotated run must serve its pairs by SGBM on transposed images and score about as the
# upright one does (tracking, fill-eval.py), since the scene and the motion are the same.
# On these 40 frames SGBM alone fills about a tenth of the removed pixels, upright or not (few
# keyframes to carry fills from, a third of the pairs refused by the validation), and the sweep
# after it the rest; so SGBM's vertical geometry is checked by fill/rectified_sgbm_test
# (FillsAMostlyVerticalPair), and this test checks a whole run on portrait images against the
# same run upright.
include("${CMAKE_CURRENT_LIST_DIR}/punch_tum.cmake")
punch_tum(tum_fr1_xyz_mid cli_fill_vertical_tmp upright)
execute_process(COMMAND "${PYTHON}" "${CMAKE_CURRENT_LIST_DIR}/rotate_capture.py" "${work}/upright"
                        "${work}/rotated"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "rotate_capture.py failed (${rc}): ${err}")
endif()

# Runs reconstruct on capture NAME and sets <NAME>_ate, <NAME>_score (fill-eval.py's line),
# <NAME>_good (its good rate) and <NAME>_report (report.json).
function(run_capture name)
  set(capture "${work}/${name}")
  execute_process(COMMAND "${GLASSFUSION}" reconstruct "${capture}" --out "${capture}_run"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "reconstruct ${name} failed (${rc}): ${err}")
  endif()
  execute_process(COMMAND "${GLASSFUSION}" eval --gt "${capture}/groundtruth.txt"
                          --est "${capture}_run/trajectory.txt"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE eval_out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "eval ${name} failed (${rc}): ${err}")
  endif()
  string(JSON ate GET "${eval_out}" ate_rmse_m)
  execute_process(COMMAND "${PYTHON}" "${tools}/fill-eval.py" "${capture}" "${capture}_run"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE score ERROR_VARIABLE err)
  if(NOT rc EQUAL 0 OR NOT score MATCHES "good_rate=([0-9.]+)")
    message(FATAL_ERROR "fill-eval.py on ${name} failed (${rc}): ${err} ${score}")
  endif()
  string(STRIP "${score}" score)
  file(READ "${capture}_run/report.json" report)
  set(${name}_ate ${ate} PARENT_SCOPE)
  set(${name}_score "${score}" PARENT_SCOPE)
  set(${name}_good ${CMAKE_MATCH_1} PARENT_SCOPE)
  set(${name}_report "${report}" PARENT_SCOPE)
endfunction()

run_capture(upright)
run_capture(rotated)

# The rotated run: complete, every frame tracked, most pairs served by SGBM on transposed images
# (the upright run's by none), a map with fill in it.
string(JSON complete GET "${rotated_report}" complete)
string(JSON lost GET "${rotated_report}" tracking lost_frames)
string(JSON vertical GET "${rotated_report}" fill sgbm_vertical)
string(JSON paired GET "${rotated_report}" fill keyframes_paired)
string(JSON surfels GET "${rotated_report}" surfels count)
string(JSON filled_surfels GET "${rotated_report}" surfels by_source stereo_fill)
string(JSON upright_vertical GET "${upright_report}" fill sgbm_vertical)
math(EXPR half "${paired} / 2")
if(NOT complete OR NOT lost EQUAL 0 OR paired LESS 10 OR vertical LESS half OR
   NOT upright_vertical EQUAL 0 OR surfels LESS 20000 OR filled_surfels LESS 1)
  message(FATAL_ERROR "rotated run: complete ${complete}, ${lost} lost, ${vertical} of ${paired} "
                      "pairs vertical (upright run: ${upright_vertical}), ${surfels} surfels, "
                      "${filled_surfels} from the fill")
endif()
# Today: ATE 5.1 / 5.0 mm rotated / upright; fill 0.63 / good 0.42 / median 1.8% / p90 6.5%
# rotated against 0.71 / 0.51 / 1.5% / 6.1% upright (these first 40 frames are the hardest of mid:
# few keyframes to carry fills from; 3 of the rotated run's 14 pairs fall on the forward side of
# the epipole test, none of the upright's, and each pair moves the good rate by about 0.03). The
# bounds catch a broken vertical path, not a point of fill.
if(rotated_ate GREATER 0.012 OR upright_ate GREATER 0.012)
  message(FATAL_ERROR "ATE rotated ${rotated_ate} m, upright ${upright_ate} m: over 1.2 cm")
endif()
check_fill_score("${rotated_score}" "fill of the rotated (vertical-motion) capture" 0.50 0.35 0.025
                 0.08)
execute_process(COMMAND "${PYTHON}" -c
                        "import sys; sys.exit(abs(${rotated_good} - ${upright_good}) > 0.10 or abs(${rotated_ate} - ${upright_ate}) > 0.003)"
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "rotated and upright runs differ: good ${rotated_good} against "
                      "${upright_good}, ATE ${rotated_ate} against ${upright_ate} m")
endif()
file(REMOVE_RECURSE "${work}")
message("vertical motion ok: rotated ${rotated_score}, ATE ${rotated_ate} m; upright "
        "${upright_score}, ATE ${upright_ate} m")
