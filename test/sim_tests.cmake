# The simulator (lib/sim, fact-world-v1 in fact_io, apps/fact_sim).
#   fact_sim_tests:     world parser, geometry, placement, body, renderer + ground truth,
#                       dynamics, VIO drift, scripts (in process, no LCM)
#   fact_sim_app_tests: fact-sim as a process over udpm://; re-executes itself through
#                       scripts/netns-run.sh, so all traffic stays in a private network namespace.
if(TARGET fact_sim AND TARGET fact_io)
  add_executable(fact_sim_tests test_sim_world.cpp test_sim_render.cpp test_sim_dynamics.cpp)
  target_compile_definitions(fact_sim_tests PRIVATE FACT_WORLDS_DIR="${PROJECT_SOURCE_DIR}/apps/fact_sim/worlds")
  target_link_libraries(fact_sim_tests PRIVATE fact_sim fact_io GTest::gtest_main)
  fact_discover_tests(fact_sim_tests 30)
endif()

if(TARGET fact-sim AND TARGET fact_app_common)
  add_executable(fact_sim_app_tests test_sim_app.cpp)
  target_compile_definitions(fact_sim_app_tests PRIVATE
    FACT_WORLDS_DIR="${PROJECT_SOURCE_DIR}/apps/fact_sim/worlds"
    FACT_SIM_BINARY="$<TARGET_FILE:fact-sim>"
    FACT_NETNS_RUN="${PROJECT_SOURCE_DIR}/scripts/netns-run.sh")
  target_link_libraries(fact_sim_app_tests PRIVATE fact_app_common GTest::gtest)
  add_dependencies(fact_sim_app_tests fact-sim)
  fact_discover_tests(fact_sim_app_tests 30)
endif()

# fact-sim's simulated flight controllers (--mavlink-port) as processes: the loop test setpoints
# (LCM) -> fact-fc-bridge -> MAVLink over UDP 127.0.0.1 -> fact-sim's FC -> dynamics, checked on
# ground truth (tracking error, failsafe hover); raw MAVLink commands, type_mask and rejections;
# --fc-auto-arm; flags. Re-executes itself through scripts/netns-run.sh (LCM udpm).
if(TARGET fact-sim AND TARGET fact-fc-bridge AND TARGET fact_mavlink)
  add_executable(fact_sim_fc_tests test_sim_fc.cpp)
  target_compile_definitions(fact_sim_fc_tests PRIVATE
    FACT_SIM_BINARY="$<TARGET_FILE:fact-sim>"
    FACT_FC_BRIDGE_BINARY="$<TARGET_FILE:fact-fc-bridge>"
    FACT_NETNS_RUN="${PROJECT_SOURCE_DIR}/scripts/netns-run.sh")
  target_link_libraries(fact_sim_fc_tests PRIVATE fact_app_common fact_mavlink GTest::gtest)
  add_dependencies(fact_sim_fc_tests fact-sim fact-fc-bridge)
  fact_discover_tests(fact_sim_fc_tests 60)
endif()

# The simulated flight controller's command handling in process (apps/fact_sim/sim_fc.cpp compiled
# in, no sockets): the disarm ground test and DO_SET_MODE's base mode.
if(TARGET fact-sim AND TARGET fact_mavlink)
  add_executable(fact_sim_fc_command_tests test_sim_fc_commands.cpp ${PROJECT_SOURCE_DIR}/apps/fact_sim/sim_fc.cpp)
  target_include_directories(fact_sim_fc_command_tests PRIVATE ${PROJECT_SOURCE_DIR}/apps/fact_sim)
  target_link_libraries(fact_sim_fc_command_tests PRIVATE fact_app_common fact_sim fact_mavlink GTest::gtest_main)
  fact_discover_tests(fact_sim_fc_command_tests 30)
endif()
