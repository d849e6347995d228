// Frame checks, and the range and vectors of a target from its box (fact/detector.h).
#include "fact/detector.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace fact {

std::string frame_error(const FrameView& frame) {
  if (std::string e = intrinsics_error(frame.intrinsics); !e.empty()) return "intrinsics: " + e;
  if (frame.gray == nullptr) return "gray: null buffer";
  if (frame.depth_mm == nullptr) return "depth_mm: null buffer";
  const size_t n = static_cast<size_t>(frame.intrinsics.width) * static_cast<size_t>(frame.intrinsics.height);
  for (size_t i = 0; i < n; ++i)
    if (frame.depth_mm[i] != 0) return "";
  return "depth_mm: all " + std::to_string(n) + " pixels are 0 (no valid depth)";
}

double near_surface_depth(const FrameView& frame, const BoxDetection& box, const RangeOptions& options) {
  const CameraIntrinsics& k = frame.intrinsics;
  // Pixels whose centres lie in [u, u + w) × [v, v + h) (pixel centres are integers).
  const int u0 = std::max(0, static_cast<int>(std::ceil(box.u)));
  const int v0 = std::max(0, static_cast<int>(std::ceil(box.v)));
  const int u1 = std::min(k.width, static_cast<int>(std::ceil(box.u + box.w)));
  const int v1 = std::min(k.height, static_cast<int>(std::ceil(box.v + box.h)));
  const double lo_mm = options.min_depth * 1000.0, hi_mm = options.max_depth * 1000.0;
  thread_local std::vector<uint16_t> depths;  // reused: no allocation per box once warm
  depths.clear();
  for (int v = v0; v < v1; ++v) {
    const uint16_t* row = frame.depth_mm + static_cast<size_t>(v) * k.width;
    for (int u = u0; u < u1; ++u)
      if (row[u] != 0 && row[u] >= lo_mm && row[u] <= hi_mm) depths.push_back(row[u]);
  }
  if (depths.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double fraction = std::clamp(options.smallest_percent, 1e-9, 100.0) / 100.0;
  const size_t m = std::max<size_t>(1, static_cast<size_t>(std::lround(fraction * depths.size())));
  if (m < depths.size()) std::nth_element(depths.begin(), depths.begin() + (m - 1), depths.end());
  double sum = 0;
  for (size_t i = 0; i < m; ++i) sum += depths[i];
  return sum / static_cast<double>(m) / 1000.0;
}

TargetVector target_vector(const FrameView& frame, const BoxDetection& box, const CameraExtrinsics& extrinsics,
                           double roll, double pitch, const RangeOptions& options) {
  TargetVector t;
  t.surface_z = near_surface_depth(frame, box, options);
  if (!std::isfinite(t.surface_z)) return t;
  const double uc = box.u + box.w * 0.5, vc = box.v + box.h * 0.5;
  t.ray_c = pixel_ray(frame.intrinsics, uc, vc);
  const double range_cam = t.surface_z / t.ray_c.z() + options.target_radius;  // from the optical centre (m)
  t.point_c = t.ray_c * range_cam;
  t.vector_b = extrinsics.R_body_cam * t.point_c + extrinsics.t_body_cam;
  t.vector_g = gravity_from_body(roll, pitch) * t.vector_b;
  t.range = t.vector_g.norm();
  t.valid = std::isfinite(t.range);  // never a NaN or infinite vector, whatever the box
  return t;
}

}  // namespace fact
