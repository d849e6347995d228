# fact_vision (lib/detector): segmentation, range and vectors, tracker on painted frames
# (test_detector_frames.cpp); on fact_sim's rendered frames (test_detector_sim.cpp); and fact-detector
# as a process (--png-dir, udpm inside scripts/netns-run.sh; test_detector_app.cpp).
if(TARGET fact_vision)
  add_executable(fact_detector_tests test_detector_frames.cpp)
  target_link_libraries(fact_detector_tests PRIVATE fact_vision GTest::gtest_main)
  if(TARGET fact_sim)
    target_sources(fact_detector_tests PRIVATE test_detector_sim.cpp)
    target_link_libraries(fact_detector_tests PRIVATE fact_sim)
  endif()
  fact_discover_tests(fact_detector_tests 60)

  if(TARGET fact-detector)
    add_executable(fact_detector_app_tests test_detector_app.cpp)
    target_compile_definitions(fact_detector_app_tests PRIVATE
      FACT_DETECTOR_BINARY="$<TARGET_FILE:fact-detector>"
      FACT_NETNS_RUN="${PROJECT_SOURCE_DIR}/scripts/netns-run.sh")
    target_link_libraries(fact_detector_app_tests PRIVATE fact_app_common fact_vision fact_lcmtypes GTest::gtest)
    add_dependencies(fact_detector_app_tests fact-detector)
    fact_discover_tests(fact_detector_app_tests 60)
  endif()
endif()
