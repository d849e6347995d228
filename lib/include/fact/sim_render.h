// The simulator's CPU renderer (library fact_sim): what one drone's depth camera sees — the room
// (floor, walls, ceiling), the obstacles and every other drone's body — as a gray image, a depth
// image (z along the optical axis in mm, stereo-like noise, 0 = invalid) and an object-id buffer
// (ground truth for tests and benchmarks only; the detector never sees it). Also the ground-truth
// helper that says, for a viewer, where each other drone is and how much of it is visible.
//
// Conventions are fact/camera.h's: optical frame x right / y down / z forward, pixel (0, 0) the
// top-left pixel's centre; body FLU; camera pose p_b = R_body_cam · p_c + t_body_cam; the body's
// world attitude is body_attitude(yaw, pitch, roll) = R_z·R_y·R_x (world-from-body).
#pragma once

#include "fact/camera.h"
#include "fact/frame.h"
#include "fact/sim_world.h"

#include <cstdint>
#include <random>
#include <vector>

namespace fact::sim {

// A drone's true pose in the world: centre position (m) and Z-Y-X Euler attitude (rad).
struct DronePose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double yaw = 0, pitch = 0, roll = 0;
};

// Object ids in RenderedFrame::object_id.
constexpr int16_t kIdRoom = -1;      // floor, walls, ceiling, or nothing
constexpr int16_t kIdObstacle = -2;  // any obstacle
// k ≥ 0: the drone at index k of the pose list given to render().

// One rendered frame, row-major width × height buffers.
struct RenderedFrame {
  CameraIntrinsics intrinsics;
  std::vector<uint8_t> gray;        // 8-bit intensity
  std::vector<uint16_t> depth_mm;   // noisy z (mm), 1 mm steps; 0 = invalid (true z < min_depth or > max_depth)
  std::vector<int16_t> object_id;   // kIdRoom, kIdObstacle or a drone index
  std::vector<float> depth_true;    // noise-free z (m) of the surface hit (0 where nothing is hit)
  // A FrameView on this frame's buffers (valid while the frame lives and is not resized).
  FrameView view(int64_t utime) const;
};

struct RenderOptions {
  DepthNoise noise;          // σ_z = depth_sigma(noise, fx, z) per pixel; validity range
  bool depth_noise = true;   // false: depth_mm is the quantised true z
  double checker_size = 0.5; // m, floor / wall checkerboard square
};

// Renders drone cameras of one world. Holds the per-pixel ray table (optical frame rays
// ((u−cx)/fx, (v−cy)/fy, 1), so the ray parameter t of a hit is its z_c directly), the body
// parts and the noise generator (mt19937_64 seeded with `seed`; the frames depend only on the
// seed and the sequence of render() calls).
class Renderer {
 public:
  Renderer(const World& world, const CameraIntrinsics& k, const CameraExtrinsics& extrinsics = {},
           const RenderOptions& options = {}, uint64_t seed = 1, const DroneBody& body = {});

  // Renders the camera of drones[viewer]; every other drone in `drones` is drawn (as id = index).
  // `out` is resized as needed (reuse it across calls to avoid allocations).
  void render(const std::vector<DronePose>& drones, int viewer, RenderedFrame* out);

  const CameraIntrinsics& intrinsics() const { return k_; }
  const CameraExtrinsics& extrinsics() const { return extrinsics_; }
  const DroneBody& body() const { return body_; }
  const World& world() const { return world_; }

 private:
  World world_;
  CameraIntrinsics k_;
  CameraExtrinsics extrinsics_;
  RenderOptions options_;
  DroneBody body_;
  std::vector<BodyPart> parts_;
  double body_radius_;
  std::vector<Eigen::Vector3f> rays_;   // per pixel, optical frame, z = 1
  std::vector<float> unit_normals_;     // 65536 N(0, 1) samples for the depth noise
  std::mt19937_64 rng_;
};

// Camera pose of a drone: world-from-optical rotation (3×3) and the optical centre (world, m).
Eigen::Matrix3d camera_rotation(const DronePose& pose, const CameraExtrinsics& e);
Eigen::Vector3d camera_center(const DronePose& pose, const CameraExtrinsics& e);

// Ground truth about one target drone as seen by a viewer.
struct TargetTruth {
  int index = -1;                  // index of the target in the pose list
  Eigen::Vector3d p_cam = Eigen::Vector3d::Zero();  // target centre in the viewer's optical frame (m)
  Eigen::Vector3d vector_g = Eigen::Vector3d::Zero();  // viewer centre → target centre, in the viewer's
                                                       // gravity-aligned body frame (m): what the detector should output
  double range = 0;                // |vector_g|, centre to centre (m)
  double camera_range = 0;         // |p_cam|, optical centre to target centre (m)
  bool in_front = false;           // p_cam.z > 0
  Eigen::Vector2d center_px = Eigen::Vector2d::Zero();  // projection of the centre (valid if in_front)
  bool center_in_image = false;    // in_front and center_px within [−0.5, w−0.5) × [−0.5, h−0.5)
  int visible_pixels = 0;          // pixels with object_id == index in the rendered frame
  // Inclusive pixel bounds of those pixels (meaningless when visible_pixels == 0).
  int u_min = 0, v_min = 0, u_max = -1, v_max = -1;
  // The same as an image box whose edges enclose the pixels: u = u_min − 0.5, w = u_max − u_min + 1.
  BoxDetection visible_box;
  bool line_of_sight = false;      // segment centre → centre clear of obstacles and other drones
};

// For drones[viewer] and each other drone (in index order, the viewer skipped). `frame` is the
// viewer's rendered frame (for the visible pixels); pass nullptr to skip those fields.
std::vector<TargetTruth> ground_truth(const World& world, const DroneBody& body,
                                      const CameraIntrinsics& k, const CameraExtrinsics& e,
                                      const std::vector<DronePose>& drones, int viewer,
                                      const RenderedFrame* frame);

}  // namespace fact::sim
