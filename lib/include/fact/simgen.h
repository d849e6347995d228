// The scenario generator behind fact-simgen: a swarm observed over several rounds, with its
// ground truth, deterministic by seed. Truth is returned separately and must never reach the
// estimator, planner or detector.
//
// The model (world frame: FLU, z up, metres, radians):
//  - Drone i's odometry frame f_i is where its VIO started: on the ground below its round-0
//    position, origin (x, y, 0), with a yaw uniform in (−π, π]. Takeoff spots never change.
//  - Round 0: every drone hovers at its formation position. Between rounds each drone moves
//    horizontally by a distance uniform in [0, move] in a random direction, staying in the room,
//    at least min_separation (3-D) from every other drone and clear of obstacles (up to 100
//    tries, else it stays). Heights never change after takeoff.
//  - In a round each drone spins in place and detects every other drone within range_limit whose
//    line of sight (the segment between the centres) misses every obstacle, once, unless missed
//    (probability miss_rate). The heading at that detection is the true bearing to the target
//    plus a uniform offset in ±fov_horizontal/2. No vertical field-of-view limit is applied.
//  - False positives: Poisson(false_positives) per drone per round, each at a random heading,
//    range uniform in [0.5, range_limit or 8] m, azimuth uniform in ±fov_horizontal/2, elevation
//    uniform in ±29° (the D430's half vertical field of view); no extra noise.
//  - VIO drift: per drone a random walk over rounds (zero in round 0, one step before each later
//    round), added to everything the drone reports: odom_yaw, odom_position, DroneRound::yaw and
//    DroneRound::position. Detection vectors are physical and carry no drift.
//  - DroneRound::position/yaw: each round starts with the drone facing f_i's x axis, so yaw is
//    the drift alone, wrapped into (−π, π].
//  - A drone's observations in a round are shuffled; Truth::targets follows the same order.
//  - One std::mt19937_64, seeded once from SimOptions::seed. The number of draws does not depend
//    on the noise kind, its σ, the drift σ or miss_rate, so changing only those keeps the same
//    formation, moves, headings and obstacles.
#pragma once

#include "fact/rounds.h"

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace fact {

enum class Formation {
  random,   // uniform in the room, at least min_separation apart
  polygon,  // regular polygon centred on the world origin, side = spacing (rotation-symmetric)
  grid,     // square grid centred on the origin, ⌈√N⌉ columns along x, row-major, step = spacing
  line,     // a line along x centred on the origin, step = spacing
  given,    // SimOptions::positions
};
const char* to_string(Formation f);                           // "random", "polygon", …
bool parse_formation(const std::string& text, Formation* f);  // false (f untouched) if unknown

enum class NoiseKind {
  none,   // exact vectors
  paper,  // the paper's: per-axis σ = paper_sigma × range
  depth,  // depth camera: range σ = depth_c · d², bearing σ = depth_b (rad, both angles)
};
const char* to_string(NoiseKind k);                       // "none", "paper", "depth"
bool parse_noise(const std::string& text, NoiseKind* k);  // false (k untouched) if unknown

// A vertical cylinder: axis through (center.x, center.y), spanning z from center.z (its base;
// 0 = the floor) to center.z + height. A drone centre must stay min_separation / 2 outside it.
struct Obstacle {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // world, centre of the base (m)
  double radius = 0.3;                               // m
  double height = 3.0;                               // m
};

struct SimOptions {
  int drones = 4;                      // N ≥ 2
  int rounds = 3;                      // K ≥ 1
  std::vector<int> ids;                // drone ids: N unique, ≥ 0, any order; empty = 0 … N−1
  Formation formation = Formation::random;
  // World round-0 positions (m) for Formation::given, one per drone in the order of ids: x, y
  // are the takeoff spot, z the hover height. Must be empty for the other formations.
  std::vector<Eigen::Vector3d> positions;
  double room = 10.0;                  // square room side (m), centred on the world origin
  double spacing = 2.0;                // grid / line spacing, polygon side (m)
  double height_min = 1.0;             // takeoff heights uniform in [height_min, height_max] (m)
  double height_max = 2.5;             // m
  bool equal_heights = false;          // every drone at (height_min + height_max) / 2
  double min_separation = 1.0;         // m, kept at takeoff and after every move
  double move = 1.5;                   // largest horizontal move between rounds (m); 0 = hover
  NoiseKind noise = NoiseKind::none;
  double paper_sigma = 0.05;           // per-axis σ per metre of range (dimensionless)
  double depth_c = 0.008;              // 1/m
  double depth_b = 0.005;              // rad
  double range_limit = 0.0;            // m; 0 = unlimited
  double fov_horizontal = 87.0 * 3.14159265358979323846 / 180.0;  // rad, where a detection may sit in the image
  int obstacles = 0;                   // random cylinders, ≥ min_separation + radius from every takeoff spot
  double obstacle_radius = 0.4;        // m, radius of the random cylinders (3 m tall)
  std::vector<Obstacle> given_obstacles;  // placed as given, in addition to the random ones
  double miss_rate = 0.0;              // probability that a visible drone is not detected
  double false_positives = 0.0;        // mean number of spurious detections per drone per round (Poisson)
  double drift_yaw = 0.0;              // VIO yaw random walk, σ per round (rad)
  double drift_position = 0.0;         // VIO position random walk, σ per round and axis (m)
  std::uint64_t seed = 1;
};

// Ground truth: what an evaluation needs and the estimator must never see.
// Every per-drone vector is indexed like ids, which is ascending (the same as Rounds::drones).
struct Truth {
  std::vector<int> ids;
  std::vector<double> frame_yaw;                 // yaw of f_i in the world, per drone (rad)
  std::vector<Eigen::Vector3d> frame_origin;     // origin of f_i in the world, per drone (m)
  std::vector<std::vector<Eigen::Vector3d>> positions;  // positions[k][i]: world centre in round k
  // The frames the drifting odometry is in during round k: drifted_yaw[k][i] (rad) and
  // drifted_origin[k][i] (m, world). Without drift they equal frame_yaw and frame_origin.
  std::vector<std::vector<double>> drifted_yaw;
  std::vector<std::vector<Eigen::Vector3d>> drifted_origin;
  // targets[k][i][o]: id seen by observation o of drone i in round k, −1 = false positive
  std::vector<std::vector<std::vector<int>>> targets;
  std::vector<Obstacle> obstacles;               // the given obstacles, then the random ones
};

struct Scenario {
  Rounds rounds;
  Truth truth;
};

// Throws std::invalid_argument naming the option and its value when the options are unusable
// (e.g. N < 2, a room too small for the separation, positions.size() ≠ N for a given formation).
Scenario generate_scenario(const SimOptions& options);

// The poses the estimator should report for truth, in f_ref, one per truth.ids entry in that
// order: yaw of f_i in f_ref, wrap(θ_i − θ_ref) in (−π, π], and origin of f_i in f_ref,
// R(−θ_ref)·(o_i − o_ref) (m). Throws std::invalid_argument for an id not in truth.ids or a
// truth whose per-drone vectors differ in length.
struct TruePose {
  int id = 0;
  double yaw = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};
std::vector<TruePose> true_poses(const Truth& truth, int reference_id);
// The same for the drifted frames of round k (what an estimate from rounds up to k describes).
// Throws std::invalid_argument for a round not in the truth.
std::vector<TruePose> true_poses_in_round(const Truth& truth, int reference_id, int round);

}  // namespace fact
