# fact-bench-planner (planner_bench.cpp): the planner's safety in 1000 randomized simulated
# planning episodes (4–8 drones, obstacles; each drone's own rendered depth frames → own local map
# → plan_step; all trajectories flown at once and checked against the simulator's truth), and the
# planner step / map update times. scripts/bench-planner.sh runs it.
if(TARGET fact_sim AND TARGET fact_planner)
  add_executable(fact-bench-planner ${CMAKE_CURRENT_LIST_DIR}/planner_bench.cpp)
  target_link_libraries(fact-bench-planner PRIVATE fact_planner fact_sim fact_io fact_core CLI11::CLI11)
  target_include_directories(fact-bench-planner PRIVATE ${PROJECT_SOURCE_DIR}/apps)  # common/cli_checks.h
endif()
