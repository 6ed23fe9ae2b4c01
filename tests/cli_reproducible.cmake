# End-to-end: a recorded capture gives the same bytes on every run. Two default reconstructions
# (fill, fusion, loop closure, completion from the map) of a synthetic glass-table capture, and of
# the first 30 frames of TUM fr1_xyz (when ../shared/datasets is here), must write identical
# map.ply, trajectory.txt, camera.json, every keyframe image and every undistorted/ file, and a
# report.json that differs in timings only.
set(tmp "${CMAKE_CURRENT_BINARY_DIR}/cli_reproducible_tmp")
file(REMOVE_RECURSE "${tmp}")
file(MAKE_DIRECTORY "${tmp}")
include("${CMAKE_CURRENT_LIST_DIR}/find_python.cmake")

# Runs `reconstruct INPUT` into DIR with the extra arguments; fails the test unless it exits 0.
function(reconstruct input dir)
  execute_process(COMMAND "${GLASSFUSION}" reconstruct "${input}" --out "${dir}" ${ARGN}
                  RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "reconstruct ${input} failed (${rc}): ${err}")
  endif()
endfunction()

# Every file of run folder `a` but the reports has the same bytes in `b`, and b has no other.
function(expect_same_files a b)
  file(GLOB_RECURSE files RELATIVE "${a}" "${a}/*")
  file(GLOB_RECURSE files_b RELATIVE "${b}" "${b}/*")
  list(LENGTH files n)
  list(LENGTH files_b n_b)
  if(NOT n EQUAL n_b)
    message(FATAL_ERROR "${a} holds ${n} files, ${b} ${n_b}")
  endif()
  set(compared 0)
  foreach(f ${files})
    if(f MATCHES "^report\\.(json|html)$" OR f MATCHES "^\\.glassfusion")
      continue()
    endif()
    execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files "${a}/${f}" "${b}/${f}"
                    RESULT_VARIABLE different)
    if(different)
      message(FATAL_ERROR "${f} differs between two runs of the same capture (${a}, ${b})")
    endif()
    math(EXPR compared "${compared} + 1")
  endforeach()
  if(compared LESS 10)
    message(FATAL_ERROR "${a}: only ${compared} files to compare")
  endif()
  message("${compared} files identical in ${a} and ${b}")
endfunction()

# report.json of both runs without the keys that measure time.
function(expect_same_report a b)
  if(NOT PYTHON)
    message("python3 not found: the reports are not compared")
    return()
  endif()
  execute_process(COMMAND "${PYTHON}" -c "
import json, sys
def strip(j):
    if isinstance(j, dict):
        return {k: strip(v) for k, v in j.items() if k not in ('seconds', 'fps', 'ms', 'stages',
                'hardware_concurrency') and not k.endswith('_ms')}
    if isinstance(j, list):
        return [strip(v) for v in j]
    return j
a, b = (strip(json.load(open(p))) for p in sys.argv[1:3])
if a != b:
    sys.exit('the reports differ beyond their timings')
if not a['complete']:
    sys.exit('the run is not complete')
" "${a}/report.json" "${b}/report.json" RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${a}, ${b}: ${err}")
  endif()
endfunction()

execute_process(COMMAND "${GLASSFUSION}" synth --scene glass-table --frames 24 --seed 11
                        --out "${tmp}/scene" RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "synth failed (${rc}): ${err}")
endif()
reconstruct("${tmp}/scene" "${tmp}/synth_1")
reconstruct("${tmp}/scene" "${tmp}/synth_2")
expect_same_files("${tmp}/synth_1" "${tmp}/synth_2")
expect_same_report("${tmp}/synth_1" "${tmp}/synth_2")

set(tum "${DATASETS}/tum_fr1_xyz_head")
if(EXISTS "${tum}")
  reconstruct("${tum}" "${tmp}/tum_1" --frames 0:30)
  reconstruct("${tum}" "${tmp}/tum_2" --frames 0:30)
  expect_same_files("${tmp}/tum_1" "${tmp}/tum_2")
  expect_same_report("${tmp}/tum_1" "${tmp}/tum_2")
else()
  message("${tum} not present: only the synthetic capture was compared")
endif()
file(REMOVE_RECURSE "${tmp}")
