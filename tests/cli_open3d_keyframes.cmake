# End-to-end: a user loads a run's keyframes into Open3D with the documented conventions
# (undistorted/: pinhole colour and depth, camera_intrinsic.json, trajectory.log) and gets points
# where the map has them (tests/open3d_keyframes.py). TUM's camera has lens distortion, so reading
# the images as pinhole ones is only right if they were undistorted.
set(input "${DATASETS}/tum_fr1_xyz_head")
if(NOT EXISTS "${input}")
  message("SKIPPED: ${input} not present")
  return()
endif()
include("${CMAKE_CURRENT_LIST_DIR}/find_python.cmake")
execute_process(COMMAND "${PYTHON}" -c "import open3d" RESULT_VARIABLE has_open3d OUTPUT_QUIET
                ERROR_QUIET)
if(NOT PYTHON OR NOT has_open3d EQUAL 0)
  message("SKIPPED: python3-open3d not installed")
  return()
endif()
set(out "${CMAKE_CURRENT_BINARY_DIR}/cli_open3d_keyframes_tmp")
file(REMOVE_RECURSE "${out}")
execute_process(COMMAND "${GLASSFUSION}" reconstruct "${input}" --out "${out}" --frames 0:30
                RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "reconstruct failed (${rc}): ${err}")
endif()
file(READ "${out}/undistorted/camera.json" camera)
string(JSON k1 GET "${camera}" distortion 0)
if(NOT k1 EQUAL 0)
  message(FATAL_ERROR "undistorted/camera.json has distortion: ${camera}")
endif()
execute_process(COMMAND "${PYTHON}" "${CMAKE_CURRENT_LIST_DIR}/open3d_keyframes.py" "${out}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE result ERROR_VARIABLE err)
message("keyframes in Open3D against the map: ${result}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "Open3D's view of the keyframes disagrees with the map (${rc}): ${result} ${err}")
endif()
file(REMOVE_RECURSE "${out}")
