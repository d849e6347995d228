# fact-run-report (apps/fact_run_report): the evaluation math and the app on synthetic LCM logs.
if(TARGET fact-run-report)
  find_package(nlohmann_json 3 REQUIRED)
  add_executable(fact_run_report_tests test_run_report.cpp)
  target_compile_definitions(fact_run_report_tests PRIVATE FACT_RUN_REPORT_BINARY="$<TARGET_FILE:fact-run-report>${FACT_RUN_SUFFIX}")
  target_link_libraries(fact_run_report_tests PRIVATE fact_run_report_eval fact_lcmtypes nlohmann_json::nlohmann_json
                        GTest::gtest_main)
  add_dependencies(fact_run_report_tests fact-run-report)
  fact_discover_tests(fact_run_report_tests 60)
endif()
