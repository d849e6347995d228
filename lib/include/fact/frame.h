// A gray + depth image pair as the detector sees it, and a detection box: the plain data shared
// by the renderer, the detector backends, the tracker and the benchmark. No OpenCV, no LCM.
#pragma once

#include "fact/camera.h"

#include <cstdint>

namespace fact {

// A view of one frame; the pixels are owned elsewhere (row-major, width × height each).
struct FrameView {
  int64_t utime = 0;                // capture time (µs)
  CameraIntrinsics intrinsics;
  const uint8_t* gray = nullptr;    // 8-bit intensity
  const uint16_t* depth_mm = nullptr;  // z along the optical axis in mm; 0 = invalid
};

// An axis-aligned image box (pixels; u, v of the top-left corner) with a detector score in [0, 1].
struct BoxDetection {
  float u = 0, v = 0, w = 0, h = 0;
  float score = 0;
};

}  // namespace fact
