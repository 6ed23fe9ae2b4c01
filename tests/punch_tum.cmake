# punch_tum(FOLDER WORK NAME): the start of the end-to-end fill tests on punched real frames. Sets
# `input` (DATASETS/FOLDER), `tools` (../shared/tools) and `work` (WORK under the test's binary
# folder, emptied), includes find_python and check_fill_score, and writes WORK/NAME: the first 40
# frames of FOLDER with punch-holes.py's patches removed (the removed depth in NAME/truth/). A
# macro, so that a missing folder or tool skips the calling test (its return()).
macro(punch_tum folder work_name punched_name)
  set(input "${DATASETS}/${folder}")
  get_filename_component(tools "${DATASETS}/../tools" ABSOLUTE)
  if(NOT EXISTS "${input}" OR NOT EXISTS "${tools}/punch-holes.py")
    message("SKIPPED: ${input} or ${tools} not present")
    return()
  endif()
  include("${CMAKE_CURRENT_LIST_DIR}/find_python.cmake")
  include("${CMAKE_CURRENT_LIST_DIR}/check_fill_score.cmake")
  set(work "${CMAKE_CURRENT_BINARY_DIR}/${work_name}")
  file(REMOVE_RECURSE "${work}")
  execute_process(COMMAND "${PYTHON}" "${tools}/punch-holes.py" "${input}" "${work}/${punched_name}"
                          0 40
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "punch-holes.py failed (${rc}): ${err}")
  endif()
endmacro()
