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
     "{\"width\": 64, \"height\": 48, \"fx\": 50, \"fy\": 50, \"cx\": 31.5, \"cy\": 23.5, \"depth_scale\": 5000}")
expect_error("^error: .*depth/1.png: file not found$" info "${tmp}")
# A corrupt camera.json.
file(WRITE "${tmp}/camera.json" "{ broken")
expect_error("^error: .*camera.json: not valid JSON" info "${tmp}")
# A depth "PNG" that is not an image.
file(WRITE "${tmp}/camera.json"
     "{\"width\": 64, \"height\": 48, \"fx\": 50, \"fy\": 50, \"cx\": 31.5, \"cy\": 23.5, \"depth_scale\": 5000}")
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

# A good TUM folder (two synthetic frames, 640x480), then damaged one way at a time.
set(good "${tmp}/synth")
execute_process(COMMAND "${GLASSFUSION}" synth --scene glass-table --frames 2 --seed 1 --out
                        "${good}" RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "synth failed (${rc}): ${err}")
endif()
file(READ "${good}/camera.json" good_camera)
set(cap "${tmp}/cap")
function(fresh_capture)
  file(REMOVE_RECURSE "${cap}")
  file(COPY "${good}/" DESTINATION "${cap}")
endfunction()
# A fresh copy whose camera.json gives `fields` again after its own (nlohmann keeps the last of
# duplicate keys).
function(camera_with fields)
  fresh_capture()
  string(REGEX REPLACE "}[ \t\r\n]*$" ", ${fields}}" text "${good_camera}")
  file(WRITE "${cap}/camera.json" "${text}")
endfunction()

# 1. Cameras no lens could be, named by their field.
function(camera_case fields regex)
  camera_with("${fields}")
  expect_error("^error: .*cap/camera.json: ${regex}" info "${cap}")
endfunction()
camera_case("\"fx\": 1e30, \"fy\": 1e30"
            "fx 1e\\+30 gives a 0.0 degree field of view; expected 20-170$")
camera_case("\"cx\": 5000" "cx 5000 lies outside the image \\(-0.5 to 639.5 pixels\\)$")
camera_case("\"distortion\": [-10, 0, 0, 0, 0]"
            "distortion \\[-10, 0, 0, 0, 0\\]: its radial part stops growing at normalised radius")
camera_case("\"width\": 30000, \"height\": 30000"
            "width 30000 is larger than any image \\(at most 4096\\)$")
camera_case("\"width\": 1, \"height\": 1, \"cx\": 0, \"cy\": 0, \"fx\": 1, \"fy\": 1"
            "width 1 and height 1 make an image smaller than the least GlassFusion works on")
# A plausible camera that is not the images' one: refused from the first frame's headers, before
# anything of the camera's size is allocated; reconstruct leaves no run folder.
camera_with("\"width\": 2000, \"height\": 1500, \"cx\": 999.5, \"cy\": 749.5, \"fx\": 1600, \"fy\": 1600")
expect_error("^error: .*cap/depth/.*png: depth image is 640x480 but the camera is 2000x1500$"
             reconstruct "${cap}" --out "${tmp}/run")
if(EXISTS "${tmp}/run")
  message(FATAL_ERROR "a refused camera left ${tmp}/run behind")
endif()

# 2. Settings beyond their bounds, named by their place in the tree; a number beyond a double.
fresh_capture()
function(config_case json regex)
  file(WRITE "${tmp}/bounds.json" "${json}")
  expect_error("^error: .*bounds.json: ${regex}" reconstruct "${cap}" --out "${tmp}/run"
               --config "${tmp}/bounds.json")
endfunction()
config_case("{\"fusion\": {\"normal_filter_px\": 30000}}"
            "fusion.normal_filter_px 30000 is larger than any half-size image \\(at most 2048\\)$")
config_case("{\"fusion\": {\"normal_filter_px\": 1000000000}}"
            "fusion.normal_filter_px 1000000000 is larger than any half-size image")
config_case("{\"fill\": {\"pairs\": {\"refine\": {\"photometric_iterations\": [100000, 7, 7, 10]}}}}"
            "fill.pairs.refine.photometric_iterations\\[0\\] 100000 is more iterations than a frame's time allows")
config_case("{\"fusion\": {\"max_surfels\": 2000000000}}"
            "fusion.max_surfels 2000000000 takes more than the map's 16 GiB")
config_case("{\"tracker\": {\"max_jump_m\": 1e400}}" "not valid JSON")
if(EXISTS "${tmp}/run")
  message(FATAL_ERROR "a refused --config left ${tmp}/run behind")
endif()

# 3. Images under 32x24 (plain Netpbm text, which OpenCV decodes whatever the file's name).
fresh_capture()
file(GLOB depths "${cap}/depth/*.png")
file(GLOB colours "${cap}/rgb/*.png")
foreach(depth IN LISTS depths)
  file(WRITE "${depth}" "P2 1 1 65535\n5000\n")
endforeach()
foreach(colour IN LISTS colours)
  file(WRITE "${colour}" "P3 1 1 255\n10 20 30\n")
endforeach()
expect_error("^error: .*cap/depth/.*png: depth image is 1x1, smaller than the least GlassFusion works on \\(32x24\\)$"
             info "${cap}")
file(WRITE "${cap}/camera.json"
     "{\"width\": 1, \"height\": 1, \"fx\": 1, \"fy\": 1, \"cx\": 0, \"cy\": 0, \"depth_scale\": 5000}")
expect_error("^error: .*cap/camera.json: width 1 and height 1 make an image smaller" reconstruct
             "${cap}" --out "${tmp}/run")

# 4. Timestamps that are no finite number name the file and the line; an index without its
#    partner is a broken TUM folder, not a Redwood one (rgb/ and depth/ paired by position).
fresh_capture()
file(READ "${cap}/depth.txt" depth_index)
string(REGEX REPLACE "\n[0-9.]+ depth/" "\nnan depth/" nan_index "${depth_index}")
file(WRITE "${cap}/depth.txt" "${nan_index}")
expect_error("^error: .*cap/depth.txt: line [0-9]+: bad timestamp \"nan\" \\(expected a finite number of seconds\\)$"
             info "${cap}")
file(WRITE "${cap}/depth.txt" "${depth_index}")
file(REMOVE "${cap}/rgb.txt")
expect_error("^error: .*cap/rgb.txt: file not found \\(a TUM folder needs both rgb.txt and depth.txt\\)$"
             info "${cap}")
file(MAKE_DIRECTORY "${cap}/rgb.txt")
expect_error("^error: .*cap/rgb.txt: is a folder, not a file" info "${cap}")
file(REMOVE_RECURSE "${cap}/rgb.txt")
file(CREATE_LINK "${cap}/no_such_index.txt" "${cap}/rgb.txt" SYMBOLIC)
expect_error("^error: .*cap/rgb.txt: is a link to nothing" info "${cap}")

# 5. --frames that name no frames (an empty argument cannot pass through expect_error's ARGN).
fresh_capture()
foreach(range "" ":")
  execute_process(COMMAND "${GLASSFUSION}" reconstruct "${cap}" --out "${tmp}/run" --frames
                          "${range}" RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
  string(STRIP "${err}" err)
  if(NOT rc EQUAL 2 OR NOT err STREQUAL "error: --frames: \"${range}\" names no frames: give N, A:B or A:")
    message(FATAL_ERROR "--frames '${range}': expected exit 2 and one line, got ${rc}: '${err}'")
  endif()
endforeach()

# 6. A folder whose name is not UTF-8 (Latin-1 "caf\xe9"): info and reconstruct write valid JSON.
execute_process(COMMAND sh -c "cp -r \"$1\" \"$2\"$(printf '\\351')" sh "${good}" "${tmp}/caf"
                RESULT_VARIABLE rc)
file(GLOB latin1 LIST_DIRECTORIES true "${tmp}/caf?")
if(NOT rc EQUAL 0 OR NOT latin1)
  message(FATAL_ERROR "could not make a folder named in Latin-1")
endif()
execute_process(COMMAND "${GLASSFUSION}" info "${latin1}" RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "info on a Latin-1 folder name: exit ${rc}: ${err}")
endif()
string(JSON input ERROR_VARIABLE json_error GET "${out}" input)
if(json_error OR NOT input MATCHES "/caf.+$")
  message(FATAL_ERROR "info on a Latin-1 folder name wrote no valid JSON: ${json_error} ${out}")
endif()
execute_process(COMMAND "${GLASSFUSION}" reconstruct "${latin1}" --out "${tmp}/latin1_run"
                        --no-fill --no-fusion --no-loop-closure --allow-lost
                RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS "${tmp}/latin1_run/report.json")
  message(FATAL_ERROR "reconstruct of a Latin-1 folder name: exit ${rc}: ${err}")
endif()
file(READ "${tmp}/latin1_run/report.json" report)
string(JSON path ERROR_VARIABLE json_error GET "${report}" input path)
if(json_error OR NOT path MATCHES "/caf.+$")
  message(FATAL_ERROR "report.json of a Latin-1 folder name: ${json_error}")
endif()
# fill-frame: a depth file that is not there, and a FileStorage file without a depth image.
expect_error("^error: .*no_depth.exr: no such file$" fill-frame --color "${tmp}/rgb/1.png"
             --depth "${tmp}/no_depth.exr" --camera "${tmp}/camera.json" --out "${tmp}/ff")
file(WRITE "${tmp}/depth.yml" "%YAML:1.0\nname: 3\n")
expect_error("^error: .*depth.yml: holds no float depth image \\(metres\\)$" fill-frame
             --color "${tmp}/rgb/1.png" --depth "${tmp}/depth.yml" --camera "${tmp}/camera.json"
             --out "${tmp}/ff")
if(EXISTS "${tmp}/ff")
  message(FATAL_ERROR "a refused fill-frame left ${tmp}/ff behind")
endif()
file(REMOVE_RECURSE "${tmp}")
message("bad input handled")
