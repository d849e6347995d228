#include "fact/camera.h"

#include <cmath>

namespace fact {

CameraIntrinsics d430_424x240() { return CameraIntrinsics{424, 240, 213.0, 213.0, 212.0, 120.0}; }
CameraIntrinsics d430_640x480() { return CameraIntrinsics{640, 480, 387.0, 387.0, 321.0, 243.0}; }

double depth_sigma(const DepthNoise& n, double fx, double z) {
  return z * z * n.disparity_rms / (fx * n.baseline);
}

std::string intrinsics_error(const CameraIntrinsics& k) {
  auto bad = [](const char* field, double v) { return std::string(field) + " = " + std::to_string(v); };
  if (k.width <= 0 || k.width > 8192) return bad("width", k.width) + " (must be 1 … 8192)";
  if (k.height <= 0 || k.height > 8192) return bad("height", k.height) + " (must be 1 … 8192)";
  // Focal lengths 1 … 1e6 px; the principal point within one image size of the image (cx = 1e6
  // put a 3 m drone 7.7 km away, 1e300 made the ray NaN).
  if (!(k.fx >= 1 && k.fx <= 1e6)) return bad("fx", k.fx) + " (must be 1 … 1e6 px)";
  if (!(k.fy >= 1 && k.fy <= 1e6)) return bad("fy", k.fy) + " (must be 1 … 1e6 px)";
  if (!(k.cx >= -k.width && k.cx <= 2.0 * k.width))
    return bad("cx", k.cx) + " (must be within -width … 2·width = " + std::to_string(-k.width) + " … " +
           std::to_string(2 * k.width) + " px)";
  if (!(k.cy >= -k.height && k.cy <= 2.0 * k.height))
    return bad("cy", k.cy) + " (must be within -height … 2·height = " + std::to_string(-k.height) + " … " +
           std::to_string(2 * k.height) + " px)";
  return "";
}

CameraExtrinsics::CameraExtrinsics() {
  // Optical x (right) = body −y, optical y (down) = body −z, optical z (forward) = body +x.
  R_body_cam << 0, 0, 1,  //
      -1, 0, 0,           //
      0, -1, 0;
  t_body_cam = Eigen::Vector3d(0.10, 0.0, 0.0);
}

Eigen::Vector3d pixel_ray(const CameraIntrinsics& k, double u, double v) {
  return Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0).normalized();
}

Eigen::Vector2d project(const CameraIntrinsics& k, const Eigen::Vector3d& p_c) {
  return Eigen::Vector2d(k.fx * p_c.x() / p_c.z() + k.cx, k.fy * p_c.y() / p_c.z() + k.cy);
}

Eigen::Matrix3d gravity_from_body(double roll, double pitch) {
  return (Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Matrix3d body_attitude(double yaw, double pitch, double roll) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

}  // namespace fact
