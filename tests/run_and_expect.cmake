# Helpers shared by the end-to-end scripts that check exit codes and error lines.

# Runs a command; sets rc, out, err and last (the last line of stderr: progress lines come first).
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE code OUTPUT_VARIABLE stdout ERROR_VARIABLE err)
  string(STRIP "${err}" err)
  string(REGEX REPLACE ".*\n" "" last_line "${err}")
  set(rc "${code}" PARENT_SCOPE)
  set(out "${stdout}" PARENT_SCOPE)
  set(err "${err}" PARENT_SCOPE)
  set(last "${last_line}" PARENT_SCOPE)
endfunction()

# Fails unless the last run() exited with expected_rc and its last line matches regex.
function(expect what expected_rc regex)
  if(NOT rc EQUAL expected_rc)
    message(FATAL_ERROR "${what}: expected exit code ${expected_rc}, got ${rc}: ${err}")
  endif()
  if(NOT last MATCHES "${regex}")
    message(FATAL_ERROR "${what}: last line '${last}' does not match '${regex}'")
  endif()
endfunction()

# run() where a zero exit is expected.
macro(run_ok)
  run(${ARGN})
  expect("${ARGN}" 0 "")
endmacro()
