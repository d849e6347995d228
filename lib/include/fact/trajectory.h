// Smooth trajectories for the planner (library fact_planner): minimum-jerk (quintic) position
// polynomials from any position / velocity / acceleration to a target at rest, with a duration
// chosen so the velocity and acceleration stay within limits (checked by sampling), and a yaw that
// is kept or ramped with a trapezoidal rate profile (limited rate and rate change). Sampling gives
// exactly what fact::setpoint_t carries: position, velocity, acceleration, yaw, yaw_rate.
//
// Everything is in the drone's own odometry frame f_i (FLU, z up; m, s, rad). Plain data, no I/O.
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

namespace fact {

// One point of a trajectory: what a setpoint carries.
struct TrajectorySample {
  double t = 0;                                             // s since the trajectory's start
  Eigen::Vector3d position = Eigen::Vector3d::Zero();       // m
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();       // m/s
  Eigen::Vector3d acceleration = Eigen::Vector3d::Zero();   // m/s²
  double yaw = 0;                                           // rad, unwrapped (may leave [−π, π))
  double yaw_rate = 0;                                      // rad/s
};

// A yaw turn of `angle` (rad, signed, may exceed 2π) starting at yaw0 (rad): the rate ramps up at
// `accel` (rad/s², > 0) to at most `rate` (rad/s, > 0), cruises, ramps down to 0 (trapezoid, or a
// triangle when the turn is too short to reach `rate`). angle = 0: the yaw is kept.
struct YawProfile {
  double yaw0 = 0;
  double angle = 0;
  double rate = 1;
  double accel = 1;
  double duration() const;                     // s
  void sample(double t, double* yaw, double* yaw_rate) const;  // t clamped to [0, duration]
};

// Position p(t) = coeffs · [1, τ, τ², τ³, τ⁴, τ⁵]ᵀ with τ = min(t, position_duration) — coeffs is
// 3 × 6, row k = axis k (x, y, z of f_i), column j the coefficient of τ^j (m/s^j); after
// position_duration the drone rests at the end point. The yaw follows `yaw`. The trajectory's
// duration is the longer of the two.
struct Trajectory {
  Eigen::Matrix<double, 3, 6> coeffs = Eigen::Matrix<double, 3, 6>::Zero();
  double position_duration = 0;  // s
  YawProfile yaw;
  double duration() const;       // s
  TrajectorySample sample(double t) const;  // t clamped to [0, duration()]
  Eigen::Vector3d end_position() const;
};

// The state a trajectory starts from (f_i).
struct TrajectoryStart {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();      // m
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();      // m/s
  Eigen::Vector3d acceleration = Eigen::Vector3d::Zero();  // m/s²
  double yaw = 0;                                          // rad
};

// Dynamic limits (magnitudes of the 3-vectors).
struct TrajectoryLimits {
  double v_max = 1.0;         // m/s
  double a_max = 1.5;         // m/s²
  double sample_dt = 0.02;    // s, how finely the limits are checked
};

// A trajectory at rest at `position` with yaw kept (duration 0).
Trajectory hold_trajectory(const Eigen::Vector3d& position, double yaw);

// The quintic with p, v, a at t = 0 from `start` and p = target, v = a = 0 at t = duration (> 0).
// Yaw kept at start.yaw.
Trajectory min_jerk(const TrajectoryStart& start, const Eigen::Vector3d& target, double duration);

// Peak speed and acceleration of the position part, by sampling every `dt` (and at both ends).
void peak_rates(const Trajectory& trajectory, double dt, double* v_peak, double* a_peak);

// min_jerk with the shortest duration (within 2 %) whose sampled peaks stay within the limits:
// starts from the rest-to-rest bound T = max(1.875·D/v_max, √(5.774·D/a_max)) and lengthens it
// until the sampled peaks fit. "" or why not (non-finite input, limits ≤ 0, or an initial
// velocity / acceleration already beyond the limits), with *out untouched then.
std::string min_jerk_within_limits(const TrajectoryStart& start, const Eigen::Vector3d& target,
                                   const TrajectoryLimits& limits, Trajectory* out);

// Points of the position path at most `spacing` (m) apart (by a bound of the speed), including both
// ends; what the collision checks test.
std::vector<Eigen::Vector3d> path_points(const Trajectory& trajectory, double spacing);

}  // namespace fact
