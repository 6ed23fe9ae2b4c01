# End-to-end: bad input ends in one line "error: <file>: <problem>" and exit code 2, no crash.
set(tmp "${CMAKE_CURRENT_BINARY_DIR}/cli_bad_input_tmp")
file(REMOVE_RECURSE "${tmp}")
file(MAKE_DIRECTORY "${tmp}/rgb" "${tmp}/depth")

function(expect_error expected_regex)
  execute_process(COMMAND "${GLASSFUSION}" ${ARGN}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  string(STRIP "${err}" err)
  if(NOT rc EQUAL 2)
    message(FATAL_ERROR "glassfusion ${ARGN}: expected exit code 2, got ${rc}: ${err}")
  endif()
  if(NOT err MATCHES "${expected_regex}")
    message(FATAL_ERROR "glassfusion ${ARGN}: message '${err}' does not match '${expected_regex}'")
  endif()
  string(FIND "${err}" "\n" newline)
  if(NOT newline EQUAL -1)
    message(FATAL_ERROR "glassfusion ${ARGN}: error is not one line: '${err}'")
  endif()
endfunction()

expect_error("^error: /nonexistent/input: no such file or folder$" info /nonexistent/input)
# A TUM folder whose depth.txt lists a file that is not there.
file(WRITE "${tmp}/rgb.txt" "1.0 rgb/1.png\n")
file(WRITE "${tmp}/depth.txt" "1.0 depth/1.png\n")
file(WRITE "${tmp}/camera.json"
     "{\"width\": 8, \"height\": 6, \"fx\": 10, \"fy\": 10, \"cx\": 3.5, \"cy\": 2.5, \"depth_scale\": 5000}")
expect_error("^error: .*depth/1.png: file not found$" info "${tmp}")
# A corrupt camera.json.
file(WRITE "${tmp}/camera.json" "{ broken")
expect_error("^error: .*camera.json: not valid JSON" info "${tmp}")
# A depth "PNG" that is not an image.
file(WRITE "${tmp}/camera.json"
     "{\"width\": 8, \"height\": 6, \"fx\": 10, \"fy\": 10, \"cx\": 3.5, \"cy\": 2.5, \"depth_scale\": 5000}")
file(WRITE "${tmp}/depth/1.png" "garbage")
expect_error("^error: .*depth/1.png: cannot decode depth image" info "${tmp}")
# reconstruct --config: a missing file, and a setting that does not exist; neither leaves a run
# folder behind.
expect_error("^error: .*no_such_config.json: file not found$" reconstruct "${tmp}" --out
             "${tmp}/run" --config "${tmp}/no_such_config.json")
file(WRITE "${tmp}/config.json" "{\"fill\": {\"stereo\": {\"blok_size\": 5}}}")
expect_error("^error: .*config.json: unknown setting 'fill.stereo.blok_size'$" reconstruct
             "${tmp}" --out "${tmp}/run" --config "${tmp}/config.json")
if(EXISTS "${tmp}/run")
  message(FATAL_ERROR "a refused --config left ${tmp}/run behind")
endif()
# demo --config: refused before the demo writes anything.
expect_error("^error: .*config.json: unknown setting 'fill.stereo.blok_size'$" demo --out
             "${tmp}/demo" --config "${tmp}/config.json")
if(EXISTS "${tmp}/demo")
  message(FATAL_ERROR "a refused demo --config left ${tmp}/demo behind")
endif()

# A real TUM folder written by capture, then damaged in three ways.
execute_process(COMMAND "${GLASSFUSION}" capture --device dummy --out "${tmp}/good" --frames 3
                RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
if(rc EQUAL 0)
  # 1. Re-recording it with corrupt depth images: error, and no output folder. (Every image is
  # corrupted: under load the Dummy's colour and depth drift apart and TUM association may drop
  # any one frame.)
  file(GLOB depths "${tmp}/good/depth/*.png")
  list(GET depths 0 first)
  execute_process(COMMAND "${CMAKE_COMMAND}" -E copy "${first}" "${tmp}/good16.png")
  foreach(depth IN LISTS depths)
    file(WRITE "${depth}" "not a png")
  endforeach()
  expect_error("^error: .*depth/.*png: cannot decode depth image" capture --device "${tmp}/good"
               --out "${tmp}/copy")
  if(EXISTS "${tmp}/copy")
    message(FATAL_ERROR "a failed capture left ${tmp}/copy behind")
  endif()
  file(GLOB partial "${tmp}/copy.partial-*")
  if(partial)
    message(FATAL_ERROR "a failed capture left ${partial} behind")
  endif()
  # 2. A depth image of the wrong size.
  foreach(depth IN LISTS depths)
    execute_process(COMMAND "${CMAKE_COMMAND}" -E copy "${tmp}/good16.png" "${depth}")
  endforeach()
  file(WRITE "${tmp}/good/camera.json"
       "{\"width\": 640, \"height\": 480, \"fx\": 525, \"fy\": 525, \"cx\": 319.5, \"cy\": 239.5, \"depth_scale\": 5000}")
  expect_error("^error: .*depth/.*png: depth image is 320x240 but the camera is 640x480$"
               info "${tmp}/good")
else()
  message("OpenNI2 Dummy capture unavailable; capture cases not checked")
endif()
file(REMOVE_RECURSE "${tmp}")
message("bad input handled")
