# Included by ctest (TEST_INCLUDE_FILES): one test verify.NAME per run of `pd verify --list
# --json`, with the LABELS, TIMEOUT and OMP_NUM_THREADS of its case.yaml, as gtest_discover_tests
# does for GoogleTest cases. Set before including: PD_EXECUTABLE (the pd to run) and
# PD_VERIFY_OUT (the folder the runs write to). The case folders are pd's: $PD_CASES_DIR if set,
# else the source tree's.
execute_process(COMMAND "${PD_EXECUTABLE}" verify --list --json
                OUTPUT_VARIABLE pd_cases_json ERROR_VARIABLE pd_cases_error
                RESULT_VARIABLE pd_cases_result)
if(NOT pd_cases_result EQUAL 0)
  # Like gtest_discover_tests' NOT_BUILT: a test that fails and says why, not a silent nothing.
  string(REPLACE "\n" " " pd_cases_error "${pd_cases_error}")
  add_test(verify.LIST_FAILED "${CMAKE_COMMAND}" -E echo
           "pd verify --list --json failed (${pd_cases_result}): ${pd_cases_error}")
  set_tests_properties(verify.LIST_FAILED PROPERTIES LABELS "verification" WILL_FAIL TRUE)
  return()
endif()
string(JSON pd_case_count LENGTH "${pd_cases_json}")
if(pd_case_count GREATER 0)
  math(EXPR pd_case_last "${pd_case_count} - 1")
  foreach(i RANGE ${pd_case_last})
    string(JSON pd_name GET "${pd_cases_json}" ${i} name)
    string(JSON pd_label GET "${pd_cases_json}" ${i} label)
    string(JSON pd_timeout GET "${pd_cases_json}" ${i} timeout)
    string(JSON pd_threads_type TYPE "${pd_cases_json}" ${i} threads)
    if(pd_label STREQUAL "none")
      continue()   # a run without a ctest test (the report runs it)
    endif()
    add_test(verify.${pd_name} "${PD_EXECUTABLE}" verify ${pd_name} -o "${PD_VERIFY_OUT}")
    set_tests_properties(verify.${pd_name} PROPERTIES LABELS "${pd_label}" TIMEOUT ${pd_timeout})
    if(pd_threads_type STREQUAL "NUMBER")
      string(JSON pd_threads GET "${pd_cases_json}" ${i} threads)
      set_tests_properties(verify.${pd_name} PROPERTIES ENVIRONMENT OMP_NUM_THREADS=${pd_threads})
    endif()
  endforeach()
endif()
