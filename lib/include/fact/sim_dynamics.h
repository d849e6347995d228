// Simulated drone dynamics, the simulated flight controller, VIO with drift, and the scripted
// motions (library fact_sim). Plain data and small functions, no I/O.
//
// Frames: world w (z up); drone i's odometry frame f_i = the takeoff spot o_i with yaw θ_i.
// VIO (what the drone believes, in f_i) is a rigid frame of yaw φ = θ_i − d_y(t) in the world:
//   vio_pos = R_z(−φ)(p − o_i) + d_p(t),  vio_yaw = yaw − φ = yaw − θ_i + d_y(t),  vio_vel = R_z(−φ) v
// with d_p (3) and d_y random walks of σ = VioDrift::position / ::yaw per √s.
// The flight controller works in f_i on VIO; its commanded acceleration a_f (f_i) acts in the
// world as R_z(φ) · a_f.
#pragma once

#include "fact/sim_world.h"

#include <Eigen/Core>

#include <random>

namespace fact::sim {

struct DynamicsLimits {
  double max_accel = 3.0;      // m/s², norm of the commanded acceleration
  double max_speed = 2.0;      // m/s, norm of the velocity
  double max_yaw_rate = 1.5;   // rad/s
};

// Flight-controller gains: v_des = sp.vel + kp_pos·(sp.pos − pos) (norm ≤ max_speed),
// a = sp.acc + kp_vel·(v_des − vel) (norm ≤ max_accel), yaw_rate = sp.yaw_rate + kp_yaw·wrap(sp.yaw − yaw).
struct ControllerGains {
  double kp_pos = 1.5;   // 1/s
  double kp_vel = 3.0;   // 1/s
  double kp_yaw = 2.0;   // 1/s
};

// A setpoint in the drone's own frame f_i (FLU), as fact::setpoint_t carries it.
struct Setpoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();      // m
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();      // m/s (feed-forward)
  Eigen::Vector3d acceleration = Eigen::Vector3d::Zero();  // m/s² (feed-forward)
  double yaw = 0;       // rad (any multiple of 2π; the error is wrapped)
  double yaw_rate = 0;  // rad/s (feed-forward)
};
// "" or the first non-finite field, e.g. "position[1] = nan".
std::string setpoint_error(const Setpoint& sp);

// Magnitudes no quadrotor in a room can mean (a scrambled or unit-confused sender), refused on
// LCM and MAVLink alike; a finite 1e200 used to make the controller's clamp command nothing.
constexpr double kMaxSetpointPosition = 1000;      // m, each axis
constexpr double kMaxSetpointVelocity = 100;       // m/s, each axis
constexpr double kMaxSetpointAcceleration = 100;   // m/s², each axis
constexpr double kMaxSetpointYawRate = 100;        // rad/s
// "" or the first field beyond those limits, e.g. "position[0] = 1e+200 (|position| <= 1000 m)".
std::string setpoint_range_error(const Setpoint& sp);

// What the VIO reports (in f_i) plus the IMU attitude.
struct VioSample {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  double yaw = 0;    // unwrapped (continuous)
  double roll = 0, pitch = 0;
};

// One simulated drone: true state (world) and its VIO drift.
struct SimDrone {
  int id = 0;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // o_i (world, m)
  double frame_yaw = 0;                              // θ_i (rad)
  Eigen::Vector3d p = Eigen::Vector3d::Zero();       // centre (world, m)
  Eigen::Vector3d v = Eigen::Vector3d::Zero();       // velocity (world, m/s)
  Eigen::Vector3d a = Eigen::Vector3d::Zero();       // last applied acceleration (world, m/s²)
  double yaw = 0;            // world heading, unwrapped (rad)
  double yaw_rate = 0;       // rad/s
  double roll = 0, pitch = 0;  // from the thrust direction (rad)
  Eigen::Vector3d drift_p = Eigen::Vector3d::Zero();  // d_p (m)
  double drift_yaw = 0;                               // d_y (rad)
  bool landed = true;        // holds the start pose until the first setpoint
  bool have_setpoint = false;
  Setpoint setpoint;         // the one being followed (f_i)
};

// A drone resting at its takeoff spot, f_i = (start.position, start.yaw).
SimDrone make_drone(const DroneStart& start);

// Roll and pitch (rad) that point the thrust along a_world + g·z for a body heading `yaw`
// (Z-Y-X Euler, FLU; g = 9.81 m/s²).
void tilt_from_acceleration(const Eigen::Vector3d& a_world, double yaw, double* roll, double* pitch);

// The flight controller: the commanded acceleration in f_i (3) and yaw rate, from the setpoint
// and the VIO sample, within the limits.
Eigen::Vector3d controller_acceleration(const Setpoint& sp, const VioSample& vio, const ControllerGains& g,
                                        const DynamicsLimits& lim);
double controller_yaw_rate(const Setpoint& sp, const VioSample& vio, const ControllerGains& g,
                           const DynamicsLimits& lim);

// What the drone's VIO reports now.
VioSample vio_sample(const SimDrone& d);

// Advances one drone by dt (s): drift random walks (drawn from `drift_rng`, also while landed),
// then, unless landed, the controller on VIO, the limits, semi-implicit Euler integration,
// the tilt, and the floor (z ≥ 0) and room bounds. Setting d->setpoint and have_setpoint = true
// (and landed = false) is the caller's job.
void step_drone(SimDrone* d, const World& world, const ControllerGains& g, const DynamicsLimits& lim,
                double dt, std::mt19937_64* drift_rng);

// Scripted motion for tests and benchmarks without a planner.
//   none:  no setpoints (the drone stays landed unless someone sends setpoints)
//   hover: take off to `height` above the takeoff spot and hold (f_i position (0, 0, height), yaw 0)
//   spin:  as hover, then once airborne yaw continuously at spin_rate
enum class Script { none, hover, spin };
// Parses "none" | "hover" | "spin"; false otherwise.
bool parse_script(const std::string& s, Script* out);

struct ScriptState {
  double height = 1.5;        // m, drawn from the world's height range
  bool airborne = false;      // reached the height (within 0.05 m, speed < 0.1 m/s)
  double spin_start = 0;      // s, time the spin began
};

// The scripted setpoint at time t (s) given the drone's VIO; updates `st` (airborne, spin_start).
// Only meaningful for hover / spin.
Setpoint script_setpoint(Script s, ScriptState* st, const VioSample& vio, double t, double spin_rate);

}  // namespace fact::sim
