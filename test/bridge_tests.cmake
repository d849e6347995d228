# firmware_bridge/: fact_mavlink unit tests, and fact-fc-bridge as a process (behaviour over udpm
# inside scripts/netns-run.sh; the independent node-mavlink 2.3.0 decode of its bytes).
if(TARGET fact_mavlink)
  add_executable(fact_mavlink_tests test_mavlink.cpp)
  target_link_libraries(fact_mavlink_tests PRIVATE fact_mavlink Eigen3::Eigen GTest::gtest_main)
  fact_discover_tests(fact_mavlink_tests 30)
endif()

if(TARGET fact-fc-bridge)
  find_package(CLI11 REQUIRED)
  # fact_fc_bridge_peer: the LCM publisher (setpoints, odometry) and fake flight controller
  # (HEARTBEAT over UDP on 127.0.0.1) that the node-mavlink decode test drives the bridge with.
  add_executable(fact_fc_bridge_peer fc_bridge_peer.cpp)
  target_link_libraries(fact_fc_bridge_peer PRIVATE fact_mavlink fact_app_common CLI11::CLI11)
  add_dependencies(fact_fc_bridge_peer fact-fc-bridge)

  # Behaviour: streaming starts and stops with fresh setpoints and FC heartbeats, NaN and
  # geofence setpoints never reach the wire, malformed MAVLink counted by reason, fc_state, flags.
  add_executable(fact_fc_bridge_tests test_fc_bridge.cpp)
  target_compile_definitions(fact_fc_bridge_tests PRIVATE
    FACT_FC_BRIDGE_BINARY="$<TARGET_FILE:fact-fc-bridge>"
    FACT_NETNS_RUN="${PROJECT_SOURCE_DIR}/scripts/netns-run.sh")
  target_link_libraries(fact_fc_bridge_tests PRIVATE fact_app_common fact_mavlink fact_lcmtypes GTest::gtest)
  add_dependencies(fact_fc_bridge_tests fact-fc-bridge)
  fact_use_clock_shift(fact_fc_bridge_tests)
  fact_discover_tests(fact_fc_bridge_tests 30)

  # Independent decoder: node-mavlink 2.3.0 (npm, installed into the build folder by the script)
  # decodes every message type the bridge sends. Skips (77) only without npm or the registry.
  add_test(NAME fc_bridge_node_mavlink
    COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/test_fc_bridge_node_mavlink.sh ${PROJECT_SOURCE_DIR}
      $<TARGET_FILE:fact-fc-bridge>${FACT_RUN_SUFFIX} $<TARGET_FILE:fact_fc_bridge_peer>${FACT_RUN_SUFFIX}
      ${CMAKE_CURRENT_BINARY_DIR}/fc_bridge_node)
  set_tests_properties(fc_bridge_node_mavlink PROPERTIES TIMEOUT 120 SKIP_RETURN_CODE 77)
endif()
