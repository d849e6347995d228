# scripts/run-drone.sh's pre-flight checklist (fact-preflight) against fact-sim as the hardware. In
# cross builds the apps run under the emulator through their .qemu runners (FACT_RUN_SUFFIX).
if(TARGET fact-preflight AND TARGET fact-sim AND TARGET fact-fc-bridge AND TARGET fact-vio-relay)
  add_test(NAME run_drone_preflight
    COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/test_run_drone.sh ${PROJECT_SOURCE_DIR} ${CMAKE_BINARY_DIR} ${FACT_RUN_SUFFIX})
  set_tests_properties(run_drone_preflight PROPERTIES TIMEOUT 120 SKIP_RETURN_CODE 77)
endif()
