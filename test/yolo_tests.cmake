# YOLO backend (lib/detector/yolo.cpp, fact/yolo.h): a tiny synthetic ONNX model is written at test
# time by make_tiny_yolo.py with Debian's /usr/bin/python3 + python3-onnx (the model tests skip
# when onnx cannot be imported); decoding, letterbox mapping, NMS and load errors are checked.
if(TARGET fact_vision)
  add_executable(fact_yolo_tests test_yolo.cpp)
  target_compile_definitions(fact_yolo_tests PRIVATE
    FACT_MAKE_TINY_YOLO="${CMAKE_CURRENT_SOURCE_DIR}/make_tiny_yolo.py")
  target_link_libraries(fact_yolo_tests PRIVATE fact_vision GTest::gtest_main)
  fact_discover_tests(fact_yolo_tests 30)
endif()
