# COLMAP round trip with the real `colmap` command (Debian's 3.8, CPU only) on a synthetic scene:
# reconstruct -> colmap-export -> colmap feature_extractor / exhaustive_matcher /
# point_triangulator / bundle_adjuster / model_converter -> colmap-import. The refined keyframe
# poses must stay within a few millimetres of the ground truth. patch_match_stereo needs CUDA, so
# a depth map in its .bin format is written from the scene's ground truth, and colmap-import must
# fill keyframe holes from it; a truncated depth map must give a one-line error naming the file.
find_program(COLMAP colmap)
if(NOT COLMAP)
  message("SKIPPED: colmap not installed")
  return()
endif()
include("${CMAKE_CURRENT_LIST_DIR}/find_python.cmake")
set(work "${CMAKE_CURRENT_BINARY_DIR}/cli_colmap_tmp")
file(REMOVE_RECURSE "${work}")
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${ARGN} failed (${rc}): ${out} ${err}")
  endif()
  set(out "${out}" PARENT_SCOPE)
endfunction()
run("${GLASSFUSION}" synth --scene glass-table --frames 12 --seed 5 --out "${work}/scene")
run("${GLASSFUSION}" reconstruct "${work}/scene" --out "${work}/run")
run("${GLASSFUSION}" colmap-export "${work}/run" --out "${work}/ws")
file(STRINGS "${work}/ws/sparse/0/cameras.txt" camera REGEX "^1 ")
string(REPLACE " " ";" fields "${camera}")
list(SUBLIST fields 4 -1 params)
string(REPLACE ";" "," params "${params}")
# One extraction thread: COLMAP numbers images in the order they finish, and the exported model's
# ids follow the sorted names.
run("${COLMAP}" feature_extractor --database_path "${work}/ws/database.db"
    --image_path "${work}/ws/images" --ImageReader.single_camera 1
    --ImageReader.camera_model FULL_OPENCV --ImageReader.camera_params "${params}"
    --SiftExtraction.use_gpu 0 --SiftExtraction.num_threads 1)
run("${COLMAP}" exhaustive_matcher --database_path "${work}/ws/database.db" --SiftMatching.use_gpu 0)
file(MAKE_DIRECTORY "${work}/ws/triangulated" "${work}/ws/adjusted" "${work}/ws/refined")
run("${COLMAP}" point_triangulator --database_path "${work}/ws/database.db"
    --image_path "${work}/ws/images" --input_path "${work}/ws/sparse/0"
    --output_path "${work}/ws/triangulated")
run("${COLMAP}" bundle_adjuster --input_path "${work}/ws/triangulated"
    --output_path "${work}/ws/adjusted" --BundleAdjustment.refine_focal_length 0
    --BundleAdjustment.refine_principal_point 0 --BundleAdjustment.refine_extra_params 0)
run("${COLMAP}" model_converter --input_path "${work}/ws/adjusted"
    --output_path "${work}/ws/refined" --output_type TXT)
run("${GLASSFUSION}" colmap-import "${work}/ws" --into "${work}/run")
file(READ "${work}/run/report.json" report)
string(JSON keyframes GET "${report}" keyframes)
file(STRINGS "${work}/run/trajectory_colmap.txt" poses REGEX "^[0-9]")
list(LENGTH poses n)
if(NOT n EQUAL keyframes)
  message(FATAL_ERROR "trajectory_colmap.txt has ${n} poses for ${keyframes} keyframes")
endif()
run("${GLASSFUSION}" eval --gt "${work}/scene/groundtruth.txt" --est "${work}/run/trajectory_colmap.txt")
string(JSON ate GET "${out}" ate_rmse_m)
if(ate GREATER 0.005)
  message(FATAL_ERROR "COLMAP-refined keyframe poses: ATE ${ate} m > 5 mm")
endif()

# Depth maps as an additional fill source (patch_match_stereo's format, from ground truth).
file(GLOB images RELATIVE "${work}/ws/images" "${work}/ws/images/*.png")
list(GET images 1 name)
string(REGEX REPLACE "^[0-9]+_(.*)\\.png$" "\\1" ts "${name}")
file(MAKE_DIRECTORY "${work}/ws/stereo/depth_maps")
# (No semicolons in the script: CMake would split the argument there.)
run("${PYTHON}" -c "
import cv2, numpy as np
d = cv2.imread('${work}/scene/gt/visible_depth/${ts}.png', -1).astype(np.float32) / 5000.0
with open('${work}/ws/stereo/depth_maps/${name}.geometric.bin', 'wb') as f:
    f.write(b'%d&%d&1&' % (d.shape[1], d.shape[0]))
    f.write(d.astype('<f4').tobytes())
")
run("${GLASSFUSION}" colmap-import "${work}/ws" --into "${work}/run")
file(READ "${work}/run/colmap_import.json" summary)
string(JSON used GET "${summary}" depth_maps 0 used)
string(JSON filled GET "${summary}" filled_pixels)
if(NOT used OR filled LESS 100)
  message(FATAL_ERROR "depth map not used as a fill source: ${summary}")
endif()
# Truncated depth map: one line naming the file, exit code 2.
file(WRITE "${work}/ws/stereo/depth_maps/${name}.geometric.bin" "640&480&1&abc")
execute_process(COMMAND "${GLASSFUSION}" colmap-import "${work}/ws" --into "${work}/run"
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "geometric.bin: truncated")
  message(FATAL_ERROR "truncated depth map: exit ${rc}, '${err}'")
endif()
file(REMOVE_RECURSE "${work}")
message("colmap round trip ok: ${n} keyframes, refined ATE ${ate} m, ${filled} pixels filled from a depth map")
