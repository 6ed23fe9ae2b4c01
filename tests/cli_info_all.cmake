# End-to-end: `glassfusion info` reads every folder of ../shared/datasets with the expected frame
# counts and hole fractions (measured independently with numpy on the PNG/PGM files).
if(NOT EXISTS "${DATASETS}")
  message("SKIPPED: ${DATASETS} not present")
  return()
endif()
# folder | source | frames (colour/depth pairs) | depth frames listed | hole fraction low | high
# (TUM head: 150 depth frames, 144 with a colour frame within 20 ms, as associate.py pairs them.)
set(cases
  "tum_fr1_xyz_head|tum|144|150|0.245|0.255"
  "icl_livingroom1_micro|redwood|211|211|0.0200|0.0215"
  "icl_livingroom1_noisy5|redwood|5|5|0.122|0.132"
  "kinect_v1_raw|kinect_raw|1|1|0.0717|0.0728")
foreach(case IN LISTS cases)
  string(REPLACE "|" ";" f "${case}")
  list(GET f 0 name)
  list(GET f 1 kind)
  list(GET f 2 frames)
  list(GET f 3 depth_frames)
  list(GET f 4 lo)
  list(GET f 5 hi)
  if(NOT EXISTS "${DATASETS}/${name}")
    message("missing ${name}, not checked")
    continue()
  endif()
  execute_process(COMMAND "${GLASSFUSION}" info "${DATASETS}/${name}"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "info ${name} failed (${rc}): ${err}")
  endif()
  string(JSON got_kind GET "${out}" source)
  string(JSON got_frames GET "${out}" frames)
  string(JSON holes GET "${out}" hole_fraction)
  string(JSON got_depth GET "${out}" depth_frames)
  string(JSON width GET "${out}" width)
  if(NOT got_kind STREQUAL kind OR NOT got_frames EQUAL frames OR NOT got_depth EQUAL depth_frames
     OR NOT width EQUAL 640 OR holes LESS lo OR holes GREATER hi)
    message(FATAL_ERROR "${name}: got ${got_kind} ${got_frames} frames holes ${holes}; expected "
                        "${kind} ${frames} frames holes in [${lo}, ${hi}]")
  endif()
  message("${name}: ${got_kind}, ${got_frames} frames, hole fraction ${holes}")
endforeach()
