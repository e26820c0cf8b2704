# cmake -DCOMMAND="exe;args" -DEXPECTED_EXIT=N -DEXPECTED_REGEX=re -P expect_output.cmake
# Runs COMMAND and fails unless it exits with EXPECTED_EXIT and its stdout+stderr match
# EXPECTED_REGEX.
execute_process(COMMAND ${COMMAND} RESULT_VARIABLE exit_code OUTPUT_VARIABLE out ERROR_VARIABLE err)
set(all "${out}${err}")
if(NOT exit_code STREQUAL EXPECTED_EXIT)
  message(FATAL_ERROR "expected exit ${EXPECTED_EXIT}, got ${exit_code}; output:\n${all}")
endif()
if(NOT all MATCHES "${EXPECTED_REGEX}")
  message(FATAL_ERROR "output does not match '${EXPECTED_REGEX}':\n${all}")
endif()
