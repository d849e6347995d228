# fact::opencv: the OpenCV modules fact uses (core, imgproc, imgcodecs, dnn), found from Debian's
# per-module packages without the libopencv-dev metapackage. Headers: <opencv2/...> under
# include/opencv4.
if(TARGET fact::opencv)
  return()
endif()
find_path(FACT_OPENCV_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4 REQUIRED)
add_library(fact::opencv INTERFACE IMPORTED GLOBAL)
target_include_directories(fact::opencv SYSTEM INTERFACE ${FACT_OPENCV_INCLUDE_DIR})
foreach(module dnn imgcodecs imgproc core)
  find_library(FACT_OPENCV_${module} NAMES opencv_${module} REQUIRED)
  target_link_libraries(fact::opencv INTERFACE ${FACT_OPENCV_${module}})
endforeach()
