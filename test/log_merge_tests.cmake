# fact-log-merge and fact-log-compare (apps/fact_log_merge, apps/fact_log_compare), run as processes.
if(TARGET fact-log-merge)
  add_executable(fact_log_merge_tests test_log_merge.cpp)
  target_compile_definitions(fact_log_merge_tests PRIVATE FACT_LOG_MERGE_BINARY="$<TARGET_FILE:fact-log-merge>${FACT_RUN_SUFFIX}")
  target_link_libraries(fact_log_merge_tests PRIVATE fact_lcmtypes GTest::gtest_main)
  add_dependencies(fact_log_merge_tests fact-log-merge)
  fact_discover_tests(fact_log_merge_tests 60)
endif()

# fact-log-compare (apps/fact_log_compare): a replay against its recorded run, run as a process.
if(TARGET fact-log-compare)
  add_executable(fact_log_compare_tests test_log_compare.cpp)
  target_compile_definitions(fact_log_compare_tests PRIVATE FACT_LOG_COMPARE_BINARY="$<TARGET_FILE:fact-log-compare>${FACT_RUN_SUFFIX}")
  target_link_libraries(fact_log_compare_tests PRIVATE fact_lcmtypes GTest::gtest_main)
  add_dependencies(fact_log_compare_tests fact-log-compare)
  fact_discover_tests(fact_log_compare_tests 60)
endif()
