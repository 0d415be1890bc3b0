# ctest helper: run ${PD_FEM} with the ';'-separated arguments ${ARGS},
# require a non-zero exit code and output (stdout + stderr) matching the
# regular expression ${EXPECT}.
#
# If TAMPER_REFERENCE is given, the reference summary ${TAMPER_REFERENCE} is
# copied to ${TAMPERED} with quantities.${TAMPER_QUANTITY}.value replaced by
# ${TAMPER_VALUE} first (to show that --check does fail on a changed value).
if(DEFINED TAMPER_REFERENCE)
  file(READ ${TAMPER_REFERENCE} json)
  string(JSON json SET "${json}" quantities ${TAMPER_QUANTITY} value ${TAMPER_VALUE})
  file(WRITE ${TAMPERED} "${json}")
endif()
execute_process(COMMAND ${PD_FEM} ${ARGS}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "exit code: ${rc}\nstdout:\n${out}\nstderr:\n${err}")
if(rc EQUAL 0)
  message(FATAL_ERROR "pd-fem ${ARGS} succeeded, a failure was expected")
endif()
if(NOT "${out}${err}" MATCHES "${EXPECT}")
  message(FATAL_ERROR "output does not match '${EXPECT}'")
endif()
