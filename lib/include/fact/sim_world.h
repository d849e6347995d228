// The simulated world (library fact_sim): a room with convex obstacles, the drones' takeoff spots
// and their VIO drift parameters, and the drone body model. Plain data and small functions, no I/O
// (the fact-world-v1 JSON format is parsed by fact/world_io.h in fact_io).
//
// World frame (w): FLU-like, z up, metres. The room is the axis-aligned box
//   x ∈ [−sx/2, sx/2], y ∈ [−sy/2, sy/2], z ∈ [0, sz]   (z = 0 is the floor).
// Drone i's odometry frame f_i has its origin at the takeoff spot and yaw = the start yaw.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <string>
#include <vector>

namespace fact::sim {

// A ray p(t) = origin + t·direction, t ≥ 0 (direction need not be unit; t scales with it).
struct Ray {
  Eigen::Vector3d origin;
  Eigen::Vector3d direction;
};

// The nearest intersection found along a ray: parameter t and the outward unit normal there.
struct Hit {
  double t = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};

// A convex solid as the intersection of half-spaces n·x ≤ d (each plane a 4-vector (n, d) with
// n a unit outward normal), plus the axis-aligned bounding box of its vertices (for culling).
struct ConvexSolid {
  std::vector<Eigen::Vector4d> planes;
  Eigen::Vector3d box_min = Eigen::Vector3d::Zero(), box_max = Eigen::Vector3d::Zero();
};

// A vertical cylinder standing on `base` (its bottom centre), radius r, height h (m).
struct Cylinder {
  Eigen::Vector3d base = Eigen::Vector3d::Zero();
  double radius = 0, height = 0;
};

enum class ObstacleKind { box, cylinder, polytope };

// One obstacle as the world file gives it, plus the solid the renderer intersects.
//   box:      center (3), size (3, full edge lengths along its own axes), yaw (rad about z)
//   cylinder: cylinder (base, radius, height)
//   polytope: vertices (the convex hull of these points)
// `solid` holds the half-spaces of a box or polytope (empty for a cylinder).
struct Obstacle {
  ObstacleKind kind = ObstacleKind::box;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  double yaw = 0;
  Cylinder cylinder;
  std::vector<Eigen::Vector3d> vertices;
  ConvexSolid solid;
};

// Constructors; the *_error functions say what is wrong ("" if fine): size ≤ 0, radius ≤ 0,
// non-finite values, a polytope whose points span no volume (fewer than 4 non-coplanar points).
Obstacle make_box(const Eigen::Vector3d& center, const Eigen::Vector3d& size, double yaw);
Obstacle make_cylinder(const Eigen::Vector3d& base, double radius, double height);
// Computes the hull's planes; on failure returns an obstacle with no planes and sets *error.
Obstacle make_polytope(const std::vector<Eigen::Vector3d>& vertices, std::string* error);

// Axis-aligned bounding box of an obstacle (world, m).
void obstacle_bounds(const Obstacle& o, Eigen::Vector3d* lo, Eigen::Vector3d* hi);
// Nearest hit of the ray with the obstacle's surface for t ∈ (t_min, t_max); false if none.
// A ray starting inside a solid hits its exit face.
bool intersect(const Obstacle& o, const Ray& ray, double t_min, double t_max, Hit* hit);
// Euclidean distance from p to the obstacle (0 inside). Exact for boxes and cylinders; for
// polytopes the largest plane distance (a lower bound that is exact near faces).
double distance(const Obstacle& o, const Eigen::Vector3d& p);

// A drone's takeoff spot: its world position (the origin of f_i) and yaw (the yaw of f_i).
struct DroneStart {
  int id = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double yaw = 0;
};

// How the drones are placed (world file "drones"). With random_start, place_random_starts()
// draws `count` spots uniformly on the floor (z = 0), at least min_separation apart
// (horizontally) and `clearance` away from every obstacle and wall, yaw uniform in [−π, π).
struct DroneConfig {
  int count = 4;
  std::vector<int> ids;         // empty: 0 … count−1
  bool random_start = true;
  uint64_t seed = 7;
  bool seed_given = false;      // the world file named a seed (else the app's --seed is used)
  double height_min = 1.0, height_max = 2.5;  // m, flight heights for the scripted takeoff
  double min_separation = 1.0;  // m
  double clearance = 0.4;       // m
};

// VIO drift: random-walk σ per √s of the position (each axis, m) and of the yaw (rad).
struct VioDrift {
  double position = 0.01;
  double yaw = 0.002;
};

struct World {
  Eigen::Vector3d room_size = Eigen::Vector3d(10, 10, 4);  // sx, sy, sz (m)
  std::vector<Obstacle> obstacles;
  DroneConfig drone_config;
  std::vector<DroneStart> starts;  // filled from the file or by place_random_starts
  VioDrift vio;
};

// Room bounds: lo = (−sx/2, −sy/2, 0), hi = (sx/2, sy/2, sz).
Eigen::Vector3d room_min(const World& w);
Eigen::Vector3d room_max(const World& w);

// The drone ids in use (drone_config.ids, or 0 … count−1).
std::vector<int> drone_ids(const DroneConfig& c);

// Fills w.starts for a random_start config, deterministic by `seed`. Returns "" or why it could
// not (e.g. "could not place drone 5 of 6 after 20000 tries: room too small for min_separation
// 1 m and clearance 0.4 m").
std::string place_random_starts(World* w, uint64_t seed);

// Whether a start set is usable: ids unique and ≥ 0, spots inside the room, finite yaw, each
// spot at least the drone's bounding radius from every obstacle and two radii from the others,
// and the hover heights under the ceiling less the radius. "" if so, else which and why.
std::string starts_error(const World& w);

// The built-in default world: room 10 × 10 × 4 m, one box, one cylinder and one polytope,
// `drones` drones at random starts placed with `seed`. Equivalent to worlds/default.json.
World default_world(int drones, uint64_t seed);

// ----------------------------------------------------------------------------------------------
// The drone body: a central box (hub), four arms along the body diagonals to four rotor discs.
// All parts are given in the body frame (FLU, origin at the drone's centre, m).
struct DroneBody {
  Eigen::Vector3d hub_size = Eigen::Vector3d(0.12, 0.12, 0.06);  // full edge lengths
  double rotor_distance = 0.14;  // m, drone centre → rotor axis, along the diagonals (±45°, ±135°)
  double arm_width = 0.025;      // m, arm cross-section (horizontal)
  double arm_height = 0.015;     // m, arm cross-section (vertical)
  double rotor_radius = 0.065;   // m
  double rotor_height = 0.02;    // m
  double rotor_z = 0.02;         // m, height of the rotor discs' centre above the drone's centre
};

// One part: a box (center, size, yaw about body z) or a vertical cylinder (center = the middle
// of its axis, radius, height), in the body frame.
struct BodyPart {
  bool is_cylinder = false;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  // box only
  double yaw = 0;                                  // box only
  double radius = 0, height = 0;                   // cylinder only
};

// Hub, 4 arms, 4 rotors (9 parts).
std::vector<BodyPart> body_parts(const DroneBody& b);
// Radius of the smallest sphere about the drone's centre holding every part (≈ 0.21 m).
double bounding_radius(const DroneBody& b);
// Nearest hit of a body-frame ray with the body for t ∈ (t_min, t_max). Normal in the body frame.
bool intersect_body(const std::vector<BodyPart>& parts, const Ray& ray_b, double t_min, double t_max,
                    Hit* hit);

}  // namespace fact::sim
