# scripts/run-drone.sh's pre-flight checklist (fact-preflight) against fact-sim as the hardware. In
# cross builds the apps run under the emulator through their .qemu runners (FACT_RUN_SUFFIX).
if(TARGET fact-preflight AND TARGET fact-sim AND TARGET fact-fc-bridge AND TARGET fact-vio-relay)
  add_test(NAME run_drone_preflight
    COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/test_run_drone.sh ${PROJECT_SOURCE_DIR} ${CMAKE_BINARY_DIR} ${FACT_RUN_SUFFIX})
  set_tests_properties(run_drone_preflight PROPERTIES TIMEOUT 120 SKIP_RETURN_CODE 77)
endif()

# fact-preflight alone, fed crafted fc_state_t, frame_t and odometry_t over udpm:// (in a private
# network namespace, as every udpm test): each item fails, naming the field and value, on what the
# apps would refuse.
if(TARGET fact-preflight)
  add_executable(fact_preflight_tests test_preflight.cpp)
  target_compile_definitions(fact_preflight_tests PRIVATE
    FACT_PREFLIGHT_BINARY="$<TARGET_FILE:fact-preflight>"
    FACT_NETNS_RUN="${PROJECT_SOURCE_DIR}/scripts/netns-run.sh")
  target_link_libraries(fact_preflight_tests PRIVATE fact_app_common fact_lcmtypes GTest::gtest)
  add_dependencies(fact_preflight_tests fact-preflight)
  fact_discover_tests(fact_preflight_tests 60)
endif()
