// The planner's local obstacle map (library fact_planner), built only from the drone's OWN depth
// frames — never from a world file. Each frame's valid depths (inside [min_range, max_range], the
// pixels of detected drones removed) become points in the drone's odometry frame f_i; points
// below the floor height are ignored; the rest are counted in a voxel grid. A voxel hit at least
// `hit_threshold` times is occupied (single noisy returns are rejected). Occupied voxels are merged
// greedily into axis-aligned boxes: the convex obstacle pieces the planner's safety checks use.
// The grid follows the drone: when a frame's pose comes closer than the frame's reach (max_range
// along the camera's widest ray, plus the camera's offset) + resolution to the grid's horizontal
// edge, the grid is re-centred on the drone (shifted by whole voxels; what falls outside is
// forgotten), so every point the frame can map lies inside it when the grid is wider than twice
// that reach (fact-planner sizes it so). Beyond bounds() nothing is
// known: the planner keeps its moves inside (review, session 32: a grid fixed at ±12 m of the
// takeoff spot dropped every obstacle beyond, and the planner moved through them).
//
// Frames: f_i is FLU, z up, metres, origin at the drone's takeoff spot on the floor (z = 0 is the
// floor). Camera conventions are fact/camera.h's: p_b = R_body_cam · p_c + t_body_cam,
// p_f = body_attitude(yaw, pitch, roll) · p_b + position.
#pragma once

#include "fact/camera.h"
#include "fact/frame.h"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace fact {

// The drone's pose in f_i when a frame was taken (from its own odometry): centre position (m) and
// Z-Y-X Euler attitude (rad).
struct MapPose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double yaw = 0, pitch = 0, roll = 0;
};

// An axis-aligned box in f_i (m): an obstacle piece. lo ≤ hi componentwise.
struct ObstacleBox {
  Eigen::Vector3d lo = Eigen::Vector3d::Zero();
  Eigen::Vector3d hi = Eigen::Vector3d::Zero();
};

// Euclidean distance from p to the box (0 inside).
double box_distance(const ObstacleBox& b, const Eigen::Vector3d& p);

struct LocalMapParams {
  double resolution = 0.2;       // m, voxel edge
  double half_extent_xy = 12.0;  // m, the grid covers x, y within half_extent_xy of its centre (first
                                 // the takeoff spot, then the drone: see the header)
  double z_min = -1.0;           // m, grid bottom in f_i
  double z_max = 5.0;            // m, grid top in f_i
  double min_range = 0.25;       // m, optical z below this is ignored
  double max_range = 5.0;        // m, optical z beyond this is ignored (noise grows as z²)
  double floor_height = 0.25;    // m, points with z_f below this are the floor: ignored
  int hit_threshold = 3;         // hits for a voxel to be occupied
  int pixel_step = 2;            // use every pixel_step-th row and column
  // Pixels inside each detected drone box, grown by this many pixels on every side plus this
  // fraction of the box's size, are removed (the drone is not an obstacle of the map).
  int box_dilation_px = 3;
  double box_dilation_fraction = 0.25;
};

// "" when usable, else which field and value is wrong.
std::string local_map_params_error(const LocalMapParams& p);

// The grid's voxel count for p (the x, y and z extents over the resolution); usable params keep it
// at most kMaxMapVoxels (memory: 2 bytes a voxel).
double local_map_voxels(const LocalMapParams& p);
constexpr double kMaxMapVoxels = 5e7;

// What one add_frame call did.
struct FrameIntegration {
  int points = 0;          // points counted into voxels
  int removed_drone = 0;   // valid pixels removed because they lie in a detected drone's box
  int out_of_range = 0;    // invalid depth, outside [min_range, max_range], or outside the grid
  int floor = 0;           // below floor_height
  bool recentred = false;  // the grid was re-centred on the drone before this frame
  int forgotten = 0;       // occupied voxels that fell outside the re-centred grid
};

class LocalMap {
 public:
  explicit LocalMap(const LocalMapParams& params = {});

  // Counts one frame. `drone_boxes`: the detector's boxes in this frame. "" or what is wrong
  // (frame_error-like checks: buffers, intrinsics; a non-finite pose names the field).
  std::string add_frame(const FrameView& frame, const CameraExtrinsics& extrinsics, const MapPose& pose,
                        const std::vector<BoxDetection>& drone_boxes, FrameIntegration* stats = nullptr);

  // Occupied voxels merged greedily into axis-aligned boxes (x runs first, then y, then z).
  std::vector<ObstacleBox> pieces() const;
  int occupied_voxels() const;
  bool occupied(const Eigen::Vector3d& p_f) const;  // the voxel holding p_f is occupied
  // The region the grid covers now (f_i): obstacles are known only inside it.
  ObstacleBox bounds() const;
  void clear();
  const LocalMapParams& params() const { return params_; }

 private:
  LocalMapParams params_;
  int nx_ = 0, ny_ = 0, nz_ = 0;
  Eigen::Vector3d origin_;        // f_i position of the grid's lowest corner
  std::vector<uint16_t> hits_;    // nx·ny·nz hit counts, index (iz·ny + iy)·nx + ix
  Eigen::Vector3i touched_lo_, touched_hi_;  // voxel index bounds of every hit so far (lo > hi: none)
  std::vector<float> ray_x_, ray_y_;  // per column / row: (u − cx)/fx, (v − cy)/fy
  CameraIntrinsics rays_for_;
  std::vector<uint8_t> mask_;     // per pixel: 1 inside a dilated drone box (scratch)

  // Re-centres the grid on p (f_i) when p is nearer than reach + resolution (m) to its horizontal
  // edge; the occupied voxels forgotten, or −1 when it stayed.
  int follow(const Eigen::Vector3d& p, double reach);
};

}  // namespace fact
