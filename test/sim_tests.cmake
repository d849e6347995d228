# The simulator (lib/sim, fact-world-v1 in fact_io, apps/fact_sim).
#   fact_sim_tests:     world parser, geometry, placement, body, renderer + ground truth,
#                       dynamics, VIO drift, scripts (in process, no LCM)
#   fact_sim_app_tests: fact-sim as a process over udpm://; re-executes itself through
#                       scripts/netns-run.sh, so all traffic stays in a private network namespace.
if(TARGET fact_sim AND TARGET fact_io)
  add_executable(fact_sim_tests test_sim_world.cpp test_sim_render.cpp test_sim_dynamics.cpp)
  target_compile_definitions(fact_sim_tests PRIVATE FACT_WORLDS_DIR="${PROJECT_SOURCE_DIR}/apps/fact_sim/worlds")
  target_link_libraries(fact_sim_tests PRIVATE fact_sim fact_io GTest::gtest_main)
  gtest_discover_tests(fact_sim_tests DISCOVERY_TIMEOUT 30 PROPERTIES TIMEOUT 30)
endif()

if(TARGET fact-sim AND TARGET fact_app_common)
  add_executable(fact_sim_app_tests test_sim_app.cpp)
  target_compile_definitions(fact_sim_app_tests PRIVATE
    FACT_SIM_BINARY="$<TARGET_FILE:fact-sim>"
    FACT_NETNS_RUN="${PROJECT_SOURCE_DIR}/scripts/netns-run.sh")
  target_link_libraries(fact_sim_app_tests PRIVATE fact_app_common GTest::gtest)
  add_dependencies(fact_sim_app_tests fact-sim)
  gtest_discover_tests(fact_sim_app_tests DISCOVERY_TIMEOUT 30 PROPERTIES TIMEOUT 30)
endif()
