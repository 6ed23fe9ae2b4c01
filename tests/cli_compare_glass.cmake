# End-to-end: `glassfusion compare` on a short synthetic glass capture (seed 11): the command
# writes both run folders, compare.json and report.html; `eval --map` scores the same map as
# compare.json does; map.ply and `reconstruct --mesh`'s mesh.ply read back in Open3D
# (python3-open3d; skipped when absent). What the fill adds to the map is checked in-process on
# 30 frames (runs/compare_test.cc).
set(tmp "${CMAKE_CURRENT_BINARY_DIR}/cli_compare_glass_tmp")
file(REMOVE_RECURSE "${tmp}")
execute_process(COMMAND "${GLASSFUSION}" synth --scene glass-table --frames 12 --seed 11 --out
                        "${tmp}/scene" RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "synth failed (${rc}): ${err}")
endif()
execute_process(COMMAND "${GLASSFUSION}" compare "${tmp}/scene" --out "${tmp}/cmp"
                RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_VARIABLE out)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "compare failed (${rc}): ${err}")
endif()
foreach(f compare.json report.html with_fill/map.ply with_fill/trajectory.txt with_fill/report.json
          without_fill/map.ply without_fill/trajectory.txt without_fill/report.json)
  if(NOT EXISTS "${tmp}/cmp/${f}")
    message(FATAL_ERROR "compare wrote no ${f}")
  endif()
endforeach()
file(READ "${tmp}/cmp/compare.json" compare)
string(JSON count GET "${compare}" with_fill surfels count)
# eval --map --gt-mesh scores the same map the same way.
execute_process(COMMAND "${GLASSFUSION}" eval --gt "${tmp}/scene/groundtruth.txt" --est
                        "${tmp}/cmp/with_fill/trajectory.txt" --map "${tmp}/cmp/with_fill/map.ply"
                        --gt-mesh "${tmp}/scene/scene.ply"
                RESULT_VARIABLE rc OUTPUT_VARIABLE eval ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "eval --map failed (${rc}): ${err}")
endif()
string(JSON eval_glossy GET "${eval}" completeness per_material glossy within_2cm)
string(JSON compare_glossy GET "${compare}" with_fill completeness per_material glossy within_2cm)
if(NOT eval_glossy EQUAL compare_glossy)
  message(FATAL_ERROR "eval --map gives ${eval_glossy} for glossy, compare ${compare_glossy}")
endif()
include("${CMAKE_CURRENT_LIST_DIR}/find_python.cmake")
if(PYTHON)
  execute_process(COMMAND "${PYTHON}" -c "import open3d" RESULT_VARIABLE has_open3d
                  OUTPUT_QUIET ERROR_QUIET)
  if(has_open3d EQUAL 0)
    execute_process(COMMAND "${PYTHON}" -c
                    "import sys, open3d; p = open3d.io.read_point_cloud(sys.argv[1]); print(len(p.points), p.has_normals(), p.has_colors())"
                    "${tmp}/cmp/with_fill/map.ply" RESULT_VARIABLE rc OUTPUT_VARIABLE o3d)
    string(STRIP "${o3d}" o3d)
    if(NOT rc EQUAL 0 OR NOT o3d STREQUAL "${count} True True")
      message(FATAL_ERROR "Open3D read '${o3d}' from map.ply, expected '${count} True True'")
    endif()
    # reconstruct --mesh: mesh.ply, a triangle mesh Open3D reads.
    execute_process(COMMAND "${GLASSFUSION}" reconstruct "${tmp}/scene" --out "${tmp}/mesh"
                            --frames 0:10 --mesh RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
    execute_process(COMMAND "${PYTHON}" -c
                    "import sys, open3d; m = open3d.io.read_triangle_mesh(sys.argv[1]); print(len(m.triangles) > 1000)"
                    "${tmp}/mesh/mesh.ply" OUTPUT_VARIABLE o3d_mesh)
    string(STRIP "${o3d_mesh}" o3d_mesh)
    if(NOT rc EQUAL 0 OR NOT o3d_mesh STREQUAL "True")
      message(FATAL_ERROR "reconstruct --mesh (${rc}, ${err}): Open3D read '${o3d_mesh}'")
    endif()
  else()
    message("python3-open3d not installed: map.ply not read back with Open3D")
  endif()
endif()
file(REMOVE_RECURSE "${tmp}")
message("compare ok")
