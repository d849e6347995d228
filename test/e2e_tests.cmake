# The main job end to end (scripts/run-sim.sh): 3 simulated drones on the small world, each with
# its full app set in a private network namespace, --fast; the certified result is judged against
# ground truth by fact-run-report. Serial: it times nothing, but it is the heaviest test.
set(FACT_E2E_TARGETS fact-sim fact-detector fact-vio-relay fact-gossip fact-solver fact-planner fact-fc-bridge
    fact-run-report fact-log-compare fact-log-merge)
set(FACT_E2E_READY TRUE)
foreach(t IN LISTS FACT_E2E_TARGETS)
  if(NOT TARGET ${t})
    set(FACT_E2E_READY FALSE)
  endif()
endforeach()
# Not in cross builds: run-sim.sh and replay.sh start the build tree's apps by path (no .qemu
# runners), and under qemu one run would render and detect over 1000 640x480 frames and run 19
# emulated processes on the build machine (the emulator runs the floating-point code about 40x
# slower); see BENCHMARKS.md, "ARM64 cross build". What it exercises on arm64 is covered there by
# each app's own tests under qemu, fact-solve arm64 = x86-64 to 1e-9 and fact-gossip arm64 <-> x86-64.
if(FACT_E2E_READY AND NOT CMAKE_CROSSCOMPILING)
  add_test(NAME e2e_run_sim_3_drones
    COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/test_e2e_run_sim.sh ${PROJECT_SOURCE_DIR} ${CMAKE_BINARY_DIR}
            ${CMAKE_BINARY_DIR}/e2e-run-sim)
  set_tests_properties(e2e_run_sim_3_drones PROPERTIES TIMEOUT 400 RUN_SERIAL TRUE SKIP_RETURN_CODE 77)
  # run-sim.sh's exit codes on runs that do not end certified (no result, an app killed, its
  # internal namespace marker set by hand): three short runs of 2 drones.
  add_test(NAME run_sim_exit_codes
    COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/test_run_sim_exit_codes.sh ${PROJECT_SOURCE_DIR} ${CMAKE_BINARY_DIR}
            ${CMAKE_BINARY_DIR}/run-sim-exit-codes)
  set_tests_properties(run_sim_exit_codes PROPERTIES TIMEOUT 300 RUN_SERIAL TRUE SKIP_RETURN_CODE 77)
endif()
