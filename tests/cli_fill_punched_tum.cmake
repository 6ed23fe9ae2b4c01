# End-to-end stereo fill on real frames, scored by the independent tools in ../shared/tools:
# punch-holes.py removes the depth of world-anchored textured patches from the first 40 frames of
# the TUM head sequence (keeping it as truth), `glassfusion reconstruct` fills keyframe holes, and
# fill-eval.py scores keyframes/<ts>.depth_filled.png against the removed depth. Also checks the
# run folder's keyframe files and report.json's fill object.
include("${CMAKE_CURRENT_LIST_DIR}/punch_tum.cmake")
punch_tum(tum_fr1_xyz_head cli_fill_tmp punched)
execute_process(COMMAND "${GLASSFUSION}" reconstruct "${work}/punched" --out "${work}/run"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "reconstruct failed (${rc}): ${err}")
endif()
file(READ "${work}/run/report.json" report)
string(JSON keyframes GET "${report}" keyframes)
string(JSON written GET "${report}" fill keyframes_filled)
string(JSON holes GET "${report}" fill hole_pixels)
string(JSON filled GET "${report}" fill filled_pixels)
string(JSON fill_rate GET "${report}" fill fill_rate)
string(JSON stereo_error GET "${report}" fill stereo_error_median_m)
string(JSON carried GET "${report}" fill carried_pixels)
string(JSON model_pixels GET "${report}" fill model_completion pixels)
if(NOT written EQUAL keyframes OR holes LESS 1 OR filled LESS 1 OR carried LESS 1)
  message(FATAL_ERROR "fill report: ${keyframes} keyframes, ${written} written, ${filled} of ${holes}, ${carried} carried")
endif()
# Every pair here is forward (the camera moves along its axis): the first keyframe's entry names
# the plane sweep, and a third view other than its partner.
string(JSON first GET "${report}" fill per_keyframe 0)
string(JSON method GET "${first}" method)
string(JSON partner GET "${first}" partner)
string(JSON third GET "${first}" third)
if(NOT method STREQUAL "plane sweep" OR third STREQUAL partner OR third STREQUAL "")
  message(FATAL_ERROR "fill report, first keyframe: method '${method}', partner ${partner}, third ${third}")
endif()
file(GLOB masks "${work}/run/keyframes/*.hole_mask.png")
file(GLOB depths "${work}/run/keyframes/*.depth_filled.png")
file(GLOB overlays "${work}/run/keyframes/*.fill_overlay.png")
list(LENGTH masks n_masks)
list(LENGTH depths n_depths)
list(LENGTH overlays n_overlays)
if(NOT n_masks EQUAL keyframes OR NOT n_depths EQUAL keyframes OR NOT n_overlays EQUAL keyframes)
  message(FATAL_ERROR "keyframes/: ${n_masks} masks, ${n_depths} depths, ${n_overlays} overlays for ${keyframes} keyframes")
endif()
# Measured pixels are never changed: every sensor pixel of the punched input is in depth_filled.
execute_process(COMMAND "${PYTHON}" -c "
import cv2, glob, os, sys
bad = 0
for p in glob.glob('${work}/run/keyframes/*.depth_filled.png'):
    ts = os.path.basename(p)[:-len('.depth_filled.png')]
    src = cv2.imread('${work}/punched/depth/' + ts + '.png', -1).astype(float) / 5.0
    out = cv2.imread(p, -1).astype(float)
    m = src > 0
    bad += int((abs(out[m] - src[m]) > 0.6).sum())
sys.exit(1 if bad else 0)"
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "depth_filled changed measured pixels: ${err}")
endif()
# fill_confidence.png: zero on sensor pixels, set on the keyframe's own filled ones and on those
# the map completed, and it predicts the error: the removed pixels filled with confidence >= 0.75
# are within 3% more often than the rest. The pixels the map completed (model_fill.png) are
# holes, and filled.
execute_process(COMMAND "${PYTHON}" -c "
import cv2, glob, os, sys
n = [0, 0, 0, 0]; on_sensor = 0; unset = 0; completed = 0
for p in glob.glob('${work}/run/keyframes/*.fill_confidence.png'):
    ts = os.path.basename(p)[:-len('.fill_confidence.png')]
    c = cv2.imread(p, -1).astype(float) / 255.0
    src = cv2.imread('${work}/punched/depth/' + ts + '.png', -1)
    out = cv2.imread('${work}/run/keyframes/' + ts + '.depth_filled.png', -1).astype(float)
    t = cv2.imread('${work}/punched/truth/' + ts + '.png', -1).astype(float) / 5.0
    mp = '${work}/run/keyframes/' + ts + '.model_fill.png'
    model = cv2.imread(mp, -1) > 0 if os.path.exists(mp) else src < 0
    on_sensor += int(((src > 0) & (c > 0)).sum()) + int((model & ((src > 0) | (out == 0))).sum())
    filled = (src == 0) & (out > 0) & ~model  # the keyframe's own fill (the map's has none)
    unset += int((filled & (c == 0)).sum()) + int((model & (c == 0)).sum())
    hit = filled & (t > 0)
    good = hit & (abs(out - t) <= 0.03 * t)
    high = c >= 0.75
    n[0] += int((hit & high).sum()); n[1] += int((good & high).sum())
    n[2] += int((hit & ~high).sum()); n[3] += int((good & ~high).sum())
    completed += int(model.sum())
print(on_sensor, unset, n, completed)
ok = on_sensor == 0 and unset == 0 and n[0] > 1000 and n[2] > 1000 and n[1] / n[0] > n[3] / n[2]
ok = ok and completed == ${model_pixels} and completed > 0
sys.exit(0 if ok else 1)"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "fill_confidence.png (sensor pixels set, filled pixels unset, [high filled, "
                      "high good, low filled, low good], model_fill.png pixels against the "
                      "report's ${model_pixels}): ${out} ${err}")
endif()
message("fill confidence (sensor pixels set, filled unset, [high filled, high good, low filled, "
        "low good]): ${out}")
execute_process(COMMAND "${PYTHON}" "${tools}/fill-eval.py" "${work}/punched" "${work}/run"
                RESULT_VARIABLE rc OUTPUT_VARIABLE score ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "fill-eval.py failed (${rc}): ${err} ${score}")
endif()
# Bounds below today's figures (fill 0.96, good 0.84, median 1.1%, p90 3.2% on these 40 frames;
# 0.88 and 0.78 without the fills carried from earlier keyframes); they guard against regressions
# and hold the goal: good_rate >= 0.70 with p90 <= 5%.
check_fill_score("${score}" "fill on punched TUM frames" 0.90 0.80 0.015 0.05)
file(REMOVE_RECURSE "${work}")
message("fill ok: ${score}")
