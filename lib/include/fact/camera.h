// The depth camera model shared by the simulator's renderer and the detector, so both agree on
// every convention. Plain data and small functions; no I/O.
//
// Frames:
//  - Optical frame (c): x right, y down, z forward along the optical axis (OpenCV convention).
//    Pixel (u, v) = (fx·x/z + cx, fy·y/z + cy); u to the right, v down, (0, 0) the top-left
//    pixel's centre.
//  - Body frame (b): FLU, x forward (heading), y left, z up, origin at the drone's centre.
//  - Gravity-aligned body frame (g): the body frame with roll and pitch removed (yaw kept):
//    x along the heading projected on the horizontal plane, z up. Detection vectors live here.
//  - Depth images hold z_c (the distance along the optical axis), not the range along the ray.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>

namespace fact {

// Pinhole intrinsics of a width × height image (pixels).
struct CameraIntrinsics {
  int width = 424;
  int height = 240;
  double fx = 213.0, fy = 213.0;  // focal lengths (px)
  double cx = 212.0, cy = 120.0;  // principal point (px)
};

// D430-like stereo depth camera presets (about 87° × 58° at 424×240; 640×480 as the issue gives:
// fx = fy = 387, cx = 321, cy = 243, about 79° × 64°).
CameraIntrinsics d430_424x240();
CameraIntrinsics d430_640x480();

// Stereo depth noise: σ_z = z² · disparity_rms / (fx · baseline) (m), from sub-pixel disparity
// noise; valid depths are within [min_depth, max_depth] (others read 0 = invalid).
struct DepthNoise {
  double baseline = 0.050;       // m (B)
  double disparity_rms = 0.08;   // px
  double min_depth = 0.2;        // m
  double max_depth = 10.0;       // m
};
double depth_sigma(const DepthNoise& n, double fx, double z);  // m

// "" when usable, else what is wrong with which field and value (sizes 1 … 8192, focal lengths
// 1 … 1e6 px, principal point within one image size of the image: -width … 2·width).
std::string intrinsics_error(const CameraIntrinsics& k);

// Where the camera sits on the body: p_b = R_body_cam · p_c + t_body_cam.
//   R_body_cam (3×3): columns are the optical axes x_c, y_c, z_c expressed in the body frame.
//   t_body_cam (3):   the optical centre in the body frame (m).
// Default: looking straight ahead, optical centre 0.10 m ahead of the drone's centre.
struct CameraExtrinsics {
  Eigen::Matrix3d R_body_cam;
  Eigen::Vector3d t_body_cam;
  CameraExtrinsics();
};

// Unit ray (optical frame, 3) through pixel (u, v).
Eigen::Vector3d pixel_ray(const CameraIntrinsics& k, double u, double v);
// Pixel of an optical-frame point with z > 0 (2).
Eigen::Vector2d project(const CameraIntrinsics& k, const Eigen::Vector3d& p_c);

// Rotation from the body frame to the gravity-aligned body frame (3×3): R_g_b = R_y(pitch)·R_x(roll)
// for a body whose world attitude is R_z(yaw)·R_y(pitch)·R_x(roll) (Z-Y-X Euler, FLU).
Eigen::Matrix3d gravity_from_body(double roll, double pitch);

// World-from-body rotation for Z-Y-X Euler angles (3×3).
Eigen::Matrix3d body_attitude(double yaw, double pitch, double roll);

}  // namespace fact
