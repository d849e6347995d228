// The planning rules of the paper made precise (library fact_planner): takeoff, spin, the minimum
// separation, the maximum move distance, the choice of target, the deliberate move for an
// ambiguous formation, the hold when certified; the push-out of a target from the inflated
// obstacle pieces (libccd GJK + EPA); collision-checked minimum-jerk trajectories with fallbacks.
//
// All positions are in the drone's own odometry frame f_i (FLU, z up; m, s, rad). The planner
// never sees the simulator's world or true poses: obstacles come from its own LocalMap
// (fact/local_map.h), other drones from its own detections and, when given, the solver's result.
// Plain functions over plain data; state (the random generator) flows in and out as values.
#pragma once

#include "fact/local_map.h"
#include "fact/trajectory.h"

#include <Eigen/Core>

#include <cstdint>
#include <array>
#include <string>
#include <vector>

namespace fact {

// Every planner parameter, with its unit (PX4-style: declared here once).
//
// Mutual visibility. The max-move rule below is safe for two drones that know of each other. The
// depth camera sees only ±α vertically (α ≈ 29° for the D430 at 424 × 240; ≈ 25° effective for
// a whole drone to show enough pixels), so two drones stacked closely enough are blind to each
// other, both ways. Moves are horizontal (targets stay in the height window), so with heights
// in a window of spread Δh = z_max − z_min and any two drones ≥ s = min_separation apart, their
// horizontal distance is ρ ≥ √(s² − Δh²) and each is within the other's view when
// Δh < ρ·tan α, which holds for every such pair when Δh ≤ s·sin α (0.42 m for s = 1 m,
// α = 25°). The defaults keep the takeoff and flight window at 1.2–1.6 m for this reason.
// (Obstacles can still hide a drone; the benchmark measures what that leaves.)
struct PlannerParams {
  // Takeoff: a height (z in f_i) drawn uniformly in [takeoff_min, takeoff_max].
  double takeoff_min = 1.2;        // m
  double takeoff_max = 1.6;        // m
  // Spin: a yaw ramp by 2π + spin_overlap (one full turn plus an overlap, so the gossip app,
  // which closes a round after a full 2π of unwrapped yaw, always sees the turn complete even
  // with odometry noise), at most spin_rate, rate ramped up and down at yaw_accel.
  double spin_rate = 0.6;          // rad/s
  double yaw_accel = 1.4;          // rad/s²
  double spin_overlap = 0.35;      // rad
  // Separation and moves.
  double min_separation = 1.0;     // m, centre to centre, from every other drone, always
  double move_max = 1.5;           // m, longest move
  double move_margin = 0.10;       // m, the `margin` of the max-move rule (absorbs detection range error)
  double random_move_probability = 0.1;  // chance of a random direction instead of the farthest drone
  // Obstacles: pieces inflated by drone_radius + obstacle_margin.
  double drone_radius = 0.21;      // m, bounding sphere of the body (fact_sim's body: 0.21 m)
  double obstacle_margin = 0.15;   // m
  int push_tries = 6;              // push-out: at most 4·push_tries single pushes before giving up
  double push_epsilon = 0.01;      // m, pushed this much beyond the surface of the inflation
  // Flight height window in f_i: targets are clamped into it and pushed-out targets must stay in
  // it (see "mutual visibility" above: keep it the takeoff window).
  double z_min = 1.2;              // m
  double z_max = 1.6;              // m
  // Horizontal fence in f_i, m: XMIN, XMAX, YMIN, YMAX. Move targets stay inside it by
  // drone_radius (paths are straight, so the whole move does). Keep it within fact-fc-bridge's
  // --geofence, whose default box it is: the bridge rejects a setpoint outside its fence, and the
  // stream, and so the flight, then stops (review, session 30: the planner had no x/y limit).
  std::array<double, 4> fence{-50, 50, -50, 50};
  // Trajectory limits and collision checks.
  double v_max = 0.8;              // m/s
  double a_max = 1.0;              // m/s²
  double check_spacing = 0.05;     // m, path points at most this far apart are checked
  // Fallbacks: shorter moves along the chosen direction (fractions of the move), then the other
  // directions (turned by ±45°, ±90°, ±135°, 180°), each at the same fractions.
  std::vector<double> fallback_fractions{1.0, 0.75, 0.5, 0.25};
  double min_useful_move = 0.1;    // m, shorter alternatives are not worth flying: hover instead
  // Synchronised spins: after a move decision (or takeoff) a drone spins only once the longest
  // move (takeoff) any drone may fly has ended, plus this settle time, which covers the spread of
  // the drones' decision times (the gossip latency). See move_slot.
  double move_settle = 0.5;        // s
};

// "" when usable, else which field and value is wrong.
std::string planner_params_error(const PlannerParams& p);

// A small seeded generator (splitmix64) whose whole state is one integer, so it flows as a value.
struct PlannerRng {
  uint64_t state = 1;
  uint64_t next();
  double uniform();  // [0, 1)
};

// What the estimator says about the swarm (fact/estimator.h's status, seen by the planner).
enum class ResultStatus { none, ambiguous, not_certified, certified };
const char* to_string(ResultStatus s);

// The planner's inputs for one step (all f_i).
struct PlannerInput {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();      // m, own centre
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();      // m/s
  Eigen::Vector3d acceleration = Eigen::Vector3d::Zero();  // m/s²
  double yaw = 0;                                          // rad
  // Other drones seen in the last spin, from own detections: observed_position() of each (the
  // planner app passes the latest spin that saw any, when the last one saw none).
  std::vector<Eigen::Vector3d> observed;
  // Other drones' positions from the solver's result, when there is one (may be empty).
  std::vector<Eigen::Vector3d> known;
  ResultStatus status = ResultStatus::none;
  PlannerRng rng;
};

// A detection's position in f_i: own position at detection + R_z(yaw at detection) · vector_g
// (vector_g: the detector's vector in the gravity-aligned body frame, m).
Eigen::Vector3d observed_position(const Eigen::Vector3d& own_position, double own_yaw,
                                  const Eigen::Vector3d& vector_g);

// "" or the first non-finite field, named (e.g. "observed[2] is not finite").
std::string planner_input_error(const PlannerInput& in);

enum class PlanKind { hold, move, hover_fallback, rejected };
const char* to_string(PlanKind k);

// A plan: what to fly and why. rejected: the input was invalid (reason names the field); the
// trajectory is then empty (duration 0 at the origin) and must not be flown.
struct Plan {
  PlanKind kind = PlanKind::hold;
  Eigen::Vector3d target = Eigen::Vector3d::Zero();  // m, f_i
  Trajectory trajectory;
  std::string reason;
  double max_move = 0;        // m, the max-move bound used
  double nearest_drone = 0;   // m, distance d to the nearest known drone (inf: none)
  PlannerRng rng;             // the generator's state after this step
};

// ---- Rules --------------------------------------------------------------------------------

// A takeoff height drawn uniformly in [takeoff_min, takeoff_max]; advances *rng.
double takeoff_height(const PlannerParams& p, PlannerRng* rng);
// Takeoff: straight up from `position` to takeoff_height (min-jerk within limits), yaw kept.
Plan plan_takeoff(const Eigen::Vector3d& position, double yaw, const PlannerParams& p, PlannerRng rng);
// Spin: hold `position`, turn yaw by 2π + spin_overlap (sign +1 counter-clockwise, −1 clockwise).
Plan plan_spin(const Eigen::Vector3d& position, double yaw, const PlannerParams& p, int direction = 1);

// The max-move rule. With d the distance to the nearest known drone and s = min_separation:
//   max_move = min(move_max, max(0, (d − s)/2 − margin)).
// Why two drones i, j planning blind (neither knowing the other's plan) cannot come closer than s:
// each stays inside the ball of radius r_i ≤ (d_i − s)/2 about its start (the whole path is
// checked to stay in it), and d_i ≤ D, d_j ≤ D where D = |p_i − p_j| is their distance (each
// knows the other). At any time |q_i − q_j| ≥ D − r_i − r_j ≥ D − (D − s)/2 − (D − s)/2 = s.
// The margin absorbs position noise. d = +inf (no drone known): move_max.
double max_move_distance(double nearest_distance, const PlannerParams& p);

// Synchronised spins. The estimator takes every drone to be at its round position for the whole
// round, so no drone may observe while another is still flying to its spot. Every drone decides
// its move at about the same time (when the swarm's round completes), and no move is longer than
// move_max, so each waits move_slot(p) from its decision, whatever its own move (or hold), before
// it spins: the duration of a rest-to-rest move of move_max at the trajectory limits plus
// move_settle (s). A round completes only when the slowest drone has spun, so the wait costs the
// swarm at most the gap between the longest move flown and move_max, plus move_settle.
double move_slot(const PlannerParams& p);
// The same for the takeoff from `start_z` to the highest takeoff height, takeoff_max (s).
double takeoff_slot(double start_z, const PlannerParams& p);

// ---- Safety (libccd) ------------------------------------------------------------------------

// Inflation of every obstacle piece: drone_radius + obstacle_margin (m).
double obstacle_inflation(const PlannerParams& p);

// Whether p lies inside the piece inflated by `inflation` (box ⊕ sphere, a rounded box).
bool inside_inflated(const ObstacleBox& box, double inflation, const Eigen::Vector3d& p);

// Penetration of point p into the inflated piece (box ⊕ sphere of radius `inflation`), by
// libccd's GJK + EPA (ccdGJKPenetration) on support functions of the rounded box and of the point:
// false when p is outside; else *depth (m) and *direction (unit, f_i) such that p + depth·direction
// lies on the inflated surface (EPA's tolerance: 0.1 mm).
bool penetration(const ObstacleBox& box, double inflation, const Eigen::Vector3d& p, double* depth,
                 Eigen::Vector3d* direction);

// Pushes `target` out of every inflated piece: repeatedly finds a piece whose inflation holds it
// and moves it by the penetration depth (+ push_epsilon) along the penetration direction. When the
// point comes back into a piece it was pushed out of (a gap narrower than two inflations), that
// piece and those pushed from since are merged into their bounding box (one convex piece) and the
// point is pushed out of it. At most 4·push_tries pushes. true and *out when the point ends free
// of every piece (also when it was free already: *out = target); false otherwise.
bool push_out(const Eigen::Vector3d& target, const std::vector<ObstacleBox>& pieces, const PlannerParams& p,
              Eigen::Vector3d* out, int* pushes = nullptr);

// Collision check of a whole trajectory: path points ≤ check_spacing apart must be outside every
// inflated piece (a path that starts inside a piece's inflation may leave it but never come closer
// to that piece than at its start), ≥ min_separation from every drone in `drones`, and within `ball_radius` (+1 mm)
// of `ball_center` (the max-move ball; pass +inf for none). "" or the first problem found
// (e.g. "path point 12 at (1.20, 0.40, 1.50) is 0.21 m from obstacle piece 3 (inflation 0.36 m)").
std::string check_trajectory(const Trajectory& trajectory, const std::vector<ObstacleBox>& pieces,
                             const std::vector<Eigen::Vector3d>& drones, const Eigen::Vector3d& ball_center,
                             double ball_radius, const PlannerParams& p);

// ---- The planner step -------------------------------------------------------------------------

// One step: inputs + own obstacle pieces → Plan.
//  - invalid input → rejected (the reason names the field);
//  - certified → hold (come to rest where the drone is);
//  - d = distance to the nearest drone of observed ∪ known, max_move = max_move_distance(d);
//  - ambiguous → a deliberate move of max_move in a random horizontal direction, uniform within
//    ±90° of the direction to the observed (else known) drones' centroid, uniform over the circle
//    when none is seen; even when the farthest-drone rule would give none (hold only if max_move
//    is 0: reason says so);
//  - otherwise, with random_move_probability a random horizontal direction, else the horizontal
//    direction toward the farthest observed (else known) drone; none known → hold;
//  - target = position + max_move·direction (z clamped to [z_min, z_max]), pushed out of the
//    inflated pieces, kept inside the max-move ball; min-jerk trajectory within v_max, a_max;
//    collision-checked (check_trajectory);
//  - not safe → alternatives: shorter moves along the direction, then other directions; none →
//    hover_fallback (come to rest where the drone is) with the reason.
Plan plan_step(const PlannerInput& in, const std::vector<ObstacleBox>& pieces, const PlannerParams& p);

}  // namespace fact
