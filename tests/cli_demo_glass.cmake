# `glassfusion demo` end to end on the built-in glass scene (no datasets needed): the report is
# written with the comparison of both maps, the stereo fill reaches the glossy, dark and glass
# holes, almost no filled clear-glass pixel that the map does not mark as glass takes the glass's
# own depth instead of the background seen through it (the goal is none; at most 1%: the sensor
# itself reads the glass surface on about a fifth of the clear-glass pixels around those holes;
# where the map marks glass, its transparent surfels give the glass's depth on purpose), and headless
# Chromium renders report.html with every image loaded, its plots, its tables and its 3D view.
set(work "${CMAKE_CURRENT_BINARY_DIR}/cli_demo_glass_tmp")
file(REMOVE_RECURSE "${work}")
execute_process(COMMAND "${GLASSFUSION}" demo --out "${work}" --data "${work}/no-datasets"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "demo failed (${rc}): ${err}")
endif()
foreach(f report.html overview.png compare/report.html compare/compare.json
          compare/with_fill/map.ply compare/without_fill/map.ply compare/with_fill_camera.png)
  if(NOT EXISTS "${work}/${f}")
    message(FATAL_ERROR "demo wrote no ${f}")
  endif()
endforeach()
file(READ "${work}/report.json" report)
string(JSON with GET "${report}" compare with_fill completeness per_material glossy within_2cm)
string(JSON without GET "${report}" compare without_fill completeness per_material glossy within_2cm)
if(NOT with GREATER without)
  message(FATAL_ERROR "the demo's glossy completeness: ${with} with the fill, ${without} without")
endif()
foreach(material glossy dark textured_glass clear_glass)
  string(JSON rate GET "${report}" fill_by_material ${material} fill_rate)
  string(JSON good GET "${report}" fill_by_material ${material} good_rate)
  message("${material}: filled ${rate}, good ${good}")
  if(rate LESS 0.63 OR good LESS 0.6)
    message(FATAL_ERROR "${material} holes: filled ${rate}, good ${good} (want >= 0.63, >= 0.6)")
  endif()
endforeach()
string(JSON filled GET "${report}" fill_by_material clear_glass filled_pixels)
string(JSON at_glass GET "${report}" clear_glass_filled_at_glass_depth)
message("clear glass filled at the glass's depth: ${at_glass} of ${filled}")
math(EXPR bound "${filled} / 100")
if(at_glass GREATER bound)
  message(FATAL_ERROR "clear glass filled at the glass's depth: ${at_glass} of ${filled} (want <= 1%)")
endif()
# The report as a person sees it: headless Chromium loads it; the page marks how many of its
# images loaded (data-images="L/N").
find_program(CHROMIUM NAMES chromium chromium-browser google-chrome)
if(NOT CHROMIUM)
  message("chromium not installed (`make deps` installs it): report.html not rendered")
else()
  execute_process(COMMAND "${CHROMIUM}" --headless --no-sandbox --disable-gpu --no-first-run
                          "--user-data-dir=${work}/chromium-profile" --virtual-time-budget=10000
                          --dump-dom "file://${work}/report.html"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE dom ERROR_QUIET TIMEOUT 120)
  if(NOT rc EQUAL 0 OR NOT dom MATCHES "data-images=\"([0-9]+)/([0-9]+)\"")
    message(FATAL_ERROR "chromium (${rc}) did not render report.html")
  endif()
  set(loaded ${CMAKE_MATCH_1})
  set(images ${CMAKE_MATCH_2})
  string(REGEX MATCHALL "<svg" plots "${dom}")
  string(REGEX MATCHALL "<table" tables "${dom}")
  list(LENGTH plots n_plots)
  list(LENGTH tables n_tables)
  message("chromium: ${loaded} of ${images} images loaded, ${n_plots} plots, ${n_tables} tables")
  # Overview, 4 renderings of the two maps, 3 fill overlays; histogram, surfel count, trajectory.
  if(NOT loaded EQUAL images OR images LESS 8 OR n_plots LESS 3 OR n_tables LESS 5)
    message(FATAL_ERROR "report.html in chromium: ${loaded}/${images} images, ${n_plots} plots, "
                        "${n_tables} tables (want all of >= 8 images, >= 3 plots, >= 5 tables)")
  endif()
endif()
# The 3D view of both maps (viewer/): drawn in headless Chromium with software WebGL, the stereo
# fill's colour in the with-fill pane only, a source toggle changing the picture, a keyframe's
# overlay shown on a click, both panes turning together.
find_program(NODE node)
if(CHROMIUM AND NODE AND EXISTS "${work}/gf_viewer.js")
  execute_process(COMMAND "${NODE}" "${CMAKE_CURRENT_LIST_DIR}/../viewer/test/viewer_test.mjs"
                          "${work}/report.html"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 180)
  message("${out}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "the report's 3D view in chromium (${rc}): ${out}${err}")
  endif()
elseif(NOT EXISTS "${work}/gf_viewer.js")
  message("no 3D view in the report (built without node and npm)")
endif()
file(REMOVE_RECURSE "${work}")
