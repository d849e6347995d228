# fact-planner as a real process over udpm inside scripts/netns-run.sh (test_planner_app.cpp): the
# test integrates the setpoints into odometry, plays detections, frames, swarm rounds and results.
if(TARGET fact-planner AND TARGET fact_app_common)
  add_executable(fact_planner_app_tests test_planner_app.cpp)
  target_compile_definitions(fact_planner_app_tests PRIVATE
    FACT_PLANNER_BINARY="$<TARGET_FILE:fact-planner>"
    FACT_NETNS_RUN="${PROJECT_SOURCE_DIR}/scripts/netns-run.sh")
  target_link_libraries(fact_planner_app_tests PRIVATE fact_app_common fact_planner fact_core GTest::gtest)
  add_dependencies(fact_planner_app_tests fact-planner)
  fact_use_clock_shift(fact_planner_app_tests)
  fact_discover_tests(fact_planner_app_tests 60)
endif()
