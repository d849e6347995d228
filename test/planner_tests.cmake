# The planner (lib/planner): trajectories and yaw ramps (test_trajectory.cpp), the rules, push-out,
# collision fallbacks and bad input (test_planner.cpp), the local map on frames rendered by fact_sim
# (test_local_map.cpp; fact_sim only produces the frames and checks the outcome).
if(TARGET fact_planner)
  add_executable(fact_planner_tests test_trajectory.cpp test_planner.cpp)
  target_link_libraries(fact_planner_tests PRIVATE fact_planner GTest::gtest_main)
  if(TARGET fact_sim)
    target_sources(fact_planner_tests PRIVATE test_local_map.cpp)
    target_link_libraries(fact_planner_tests PRIVATE fact_sim)
  endif()
  fact_discover_tests(fact_planner_tests 30)
endif()
