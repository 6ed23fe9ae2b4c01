# check_fill_score(SCORE WHAT MIN_RATE MIN_GOOD MAX_MEDIAN MAX_P90): SCORE is a fill scorer's line
# ("fill_rate=.. good_rate=.. median_rel_err=.. p90_rel_err=.."); fails the test, naming WHAT,
# when a figure is outside its bound or the line does not parse.
function(check_fill_score score what min_rate min_good max_median max_p90)
  if(NOT score MATCHES "fill_rate=([0-9.]+) good_rate=([0-9.]+) median_rel_err=([0-9.]+) p90_rel_err=([0-9.]+)")
    message(FATAL_ERROR "${what}: no fill score in '${score}'")
  endif()
  if(CMAKE_MATCH_1 LESS min_rate OR CMAKE_MATCH_2 LESS min_good OR
     CMAKE_MATCH_3 GREATER max_median OR CMAKE_MATCH_4 GREATER max_p90)
    message(FATAL_ERROR "${what} regressed: ${score}")
  endif()
endfunction()
