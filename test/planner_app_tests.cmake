# fact-planner as a real process over udpm inside scripts/netns-run.sh (test_planner_app.cpp): the
# test integrates the setpoints into odometry, plays detections, frames, swarm rounds and results.
if(TARGET fact-planner AND TARGET fact_app_common)
  add_executable(fact_planner_app_tests test_planner_app.cpp)
  target_compile_definitions(fact_planner_app_tests PRIVATE
    FACT_PLANNER_BINARY="$<TARGET_FILE:fact-planner>"
    FACT_NETNS_RUN="${PROJECT_SOURCE_DIR}/scripts/netns-run.sh")
  target_link_libraries(fact_planner_app_tests PRIVATE fact_app_common fact_planner fact_core GTest::gtest)
  add_dependencies(fact_planner_app_tests fact-planner)
  # The wall-clock step test preloads clock_shift.c into fact-planner (native builds only: under
  # the cross build's emulator the preload would reach the emulator too).
  if(NOT CMAKE_CROSSCOMPILING)
    add_library(fact_clock_shift SHARED clock_shift.c)
    target_link_libraries(fact_clock_shift PRIVATE ${CMAKE_DL_LIBS})
    add_dependencies(fact_planner_app_tests fact_clock_shift)
    target_compile_definitions(fact_planner_app_tests PRIVATE FACT_CLOCK_SHIFT_LIBRARY="$<TARGET_FILE:fact_clock_shift>")
  endif()
  fact_discover_tests(fact_planner_app_tests 60)
endif()
