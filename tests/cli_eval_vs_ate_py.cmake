# End-to-end: `glassfusion eval` agrees with the independent ../shared/tools/ate.py on a real peer
# trajectory (Open3D's estimate on ICL-NUIM livingroom1, 1.2 cm ATE per the datasets README).
set(icl "${DATASETS}/icl_livingroom1_micro")
set(ate_py "${DATASETS}/../tools/ate.py")
if(NOT EXISTS "${icl}/open3d_estimate.log" OR NOT EXISTS "${ate_py}")
  message("SKIPPED: ICL micro or ate.py not present")
  return()
endif()
execute_process(COMMAND "${GLASSFUSION}" eval --gt "${icl}/groundtruth.log"
                        --est "${icl}/open3d_estimate.log"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "eval failed (${rc}): ${err}")
endif()
string(JSON ours GET "${out}" ate_rmse_m)
string(JSON pairs GET "${out}" pairs)
include("${CMAKE_CURRENT_LIST_DIR}/find_python.cmake")
execute_process(COMMAND "${PYTHON}" "${ate_py}" "${icl}/groundtruth.log" "${icl}/open3d_estimate.log"
                RESULT_VARIABLE rc OUTPUT_VARIABLE theirs_out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "ate.py failed (${rc}): ${err}")
endif()
string(REGEX MATCH "ate_rmse_m=([0-9.]+) pairs=([0-9]+)" _ "${theirs_out}")
set(theirs "${CMAKE_MATCH_1}")
math(EXPR diff_ok "0")
if(NOT pairs EQUAL CMAKE_MATCH_2)
  message(FATAL_ERROR "pairs differ: ours ${pairs}, ate.py ${CMAKE_MATCH_2}")
endif()
# ate.py prints 4 decimals.
execute_process(COMMAND "${PYTHON}" -c "import sys; sys.exit(0 if abs(${ours} - ${theirs}) <= 6e-5 else 1)"
                RESULT_VARIABLE same)
if(NOT same EQUAL 0)
  message(FATAL_ERROR "ATE differs: ours ${ours}, ate.py ${theirs}")
endif()
message("eval agrees with ate.py: ${ours} m over ${pairs} pairs")
