# fact-bench-e2e --summarize (bench/e2e_bench.cpp): batches of e2e_runs.csv merged and summarised,
# run as a process on CSV files the test writes. The runs themselves are the benchmark, not a test.
if(TARGET fact-bench-e2e)
  add_executable(fact_e2e_bench_tests test_e2e_bench_summary.cpp)
  target_compile_definitions(fact_e2e_bench_tests PRIVATE FACT_BENCH_E2E_BINARY="$<TARGET_FILE:fact-bench-e2e>${FACT_RUN_SUFFIX}")
  target_link_libraries(fact_e2e_bench_tests PRIVATE GTest::gtest_main)
  add_dependencies(fact_e2e_bench_tests fact-bench-e2e)
  fact_discover_tests(fact_e2e_bench_tests 60)
endif()
