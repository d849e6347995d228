// Drone dynamics (point mass with limits, tilt from the thrust direction), the simulated flight
// controller on VIO, the VIO drift random walks, and the scripted motions.
#include "fact/sim_dynamics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace fact::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kGravity = 9.81;

double wrap_pi(double a) { return std::remainder(a, 2 * kPi); }

// Rotation about z by angle a applied to a 3-vector.
Eigen::Vector3d rot_z(double a, const Eigen::Vector3d& v) {
  const double c = std::cos(a), s = std::sin(a);
  return Eigen::Vector3d(c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z());
}

Eigen::Vector3d clamp_norm(const Eigen::Vector3d& v, double limit) {
  const double n = v.norm();
  return n > limit ? Eigen::Vector3d(v * (limit / n)) : v;
}

}  // namespace

std::string setpoint_error(const Setpoint& sp) {
  auto vec = [](const char* name, const Eigen::Vector3d& v) -> std::string {
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(v[k])) return std::string(name) + "[" + std::to_string(k) + "] = " + std::to_string(v[k]);
    return "";
  };
  for (const std::string& e : {vec("position", sp.position), vec("velocity", sp.velocity),
                               vec("acceleration", sp.acceleration)})
    if (!e.empty()) return e;
  if (!std::isfinite(sp.yaw)) return "yaw = " + std::to_string(sp.yaw);
  if (!std::isfinite(sp.yaw_rate)) return "yaw_rate = " + std::to_string(sp.yaw_rate);
  return "";
}

std::string setpoint_range_error(const Setpoint& sp) {
  const auto g = [](double x) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", x);
    return std::string(b);
  };
  auto vec = [&](const char* name, const Eigen::Vector3d& v, double limit, const char* unit) -> std::string {
    for (int k = 0; k < 3; ++k)
      if (!(std::abs(v[k]) <= limit))
        return std::string(name) + "[" + std::to_string(k) + "] = " + g(v[k]) + " (|" + name + "| <= " + g(limit) + " " +
               unit + ")";
    return "";
  };
  for (const std::string& e : {vec("position", sp.position, kMaxSetpointPosition, "m"),
                               vec("velocity", sp.velocity, kMaxSetpointVelocity, "m/s"),
                               vec("acceleration", sp.acceleration, kMaxSetpointAcceleration, "m/s^2")})
    if (!e.empty()) return e;
  if (!(std::abs(sp.yaw_rate) <= kMaxSetpointYawRate))
    return "yaw_rate = " + g(sp.yaw_rate) + " (|yaw_rate| <= " + g(kMaxSetpointYawRate) + " rad/s)";
  return "";
}

SimDrone make_drone(const DroneStart& start) {
  SimDrone d;
  d.id = start.id;
  d.origin = start.position;
  d.frame_yaw = start.yaw;
  d.p = start.position;
  d.yaw = start.yaw;
  return d;
}

void tilt_from_acceleration(const Eigen::Vector3d& a_world, double yaw, double* roll, double* pitch) {
  // Thrust direction in the heading frame (R_z(−yaw)·(a + g z)); the body z axis of
  // R_y(pitch)·R_x(roll) is (cos r sin p, −sin r, cos r cos p).
  const Eigen::Vector3d t = rot_z(-yaw, a_world + Eigen::Vector3d(0, 0, kGravity));
  *pitch = std::atan2(t.x(), t.z());
  *roll = std::atan2(-t.y(), std::hypot(t.x(), t.z()));
}

Eigen::Vector3d controller_acceleration(const Setpoint& sp, const VioSample& vio, const ControllerGains& g,
                                        const DynamicsLimits& lim) {
  const Eigen::Vector3d v_des = clamp_norm(sp.velocity + g.kp_pos * (sp.position - vio.position), lim.max_speed);
  return clamp_norm(sp.acceleration + g.kp_vel * (v_des - vio.velocity), lim.max_accel);
}

double controller_yaw_rate(const Setpoint& sp, const VioSample& vio, const ControllerGains& g,
                           const DynamicsLimits& lim) {
  const double r = sp.yaw_rate + g.kp_yaw * wrap_pi(sp.yaw - vio.yaw);
  return std::clamp(r, -lim.max_yaw_rate, lim.max_yaw_rate);
}

// The VIO frame is rigid: yaw φ = θ_i − d_y in the world (its heading reads yaw − φ = yaw − θ_i +
// d_y), origin o_i − R_z(φ)·d_p, so vio_pos = R_z(−φ)(p − o_i) + d_p and vio_vel = R_z(−φ)·v.
// (Positions and velocities used to turn by θ_i alone while the heading took d_y too: bearings
// and positions disagreed by d_y, and the frame's origin moved by d_y·|p − o_i| as a drone flew.)
double vio_frame_yaw(const SimDrone& d) { return d.frame_yaw - d.drift_yaw; }

VioSample vio_sample(const SimDrone& d) {
  VioSample s;
  const double phi = vio_frame_yaw(d);
  s.position = rot_z(-phi, d.p - d.origin) + d.drift_p;
  s.velocity = rot_z(-phi, d.v);
  s.yaw = d.yaw - phi;
  s.roll = d.roll;
  s.pitch = d.pitch;
  return s;
}

void step_drone(SimDrone* d, const World& world, const ControllerGains& g, const DynamicsLimits& lim, double dt,
                std::mt19937_64* drift_rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  const double sq = std::sqrt(dt);
  for (int k = 0; k < 3; ++k) d->drift_p[k] += world.vio.position * sq * normal(*drift_rng);
  d->drift_yaw += world.vio.yaw * sq * normal(*drift_rng);
  if (d->landed || !d->have_setpoint) return;

  const VioSample vio = vio_sample(*d);
  const Eigen::Vector3d a_f = controller_acceleration(d->setpoint, vio, g, lim);
  d->a = rot_z(vio_frame_yaw(*d), a_f);  // physical world acceleration: a_f is in the VIO frame
  d->yaw_rate = controller_yaw_rate(d->setpoint, vio, g, lim);

  d->v = clamp_norm(d->v + d->a * dt, lim.max_speed);
  d->p += d->v * dt;
  d->yaw += d->yaw_rate * dt;

  // Floor, walls and ceiling: stop at them (no bounce). The walls and the ceiling stop the body,
  // not its centre: the centre keeps the body's bounding radius from them, so the camera (0.10 m
  // ahead) never leaves the room (at the wall it rendered a frame with no valid pixel). The floor
  // stops the centre, where the drone sits before takeoff.
  static const double r = bounding_radius(DroneBody{});
  const Eigen::Vector3d lo = room_min(world) + Eigen::Vector3d(r, r, 0), hi = room_max(world) - Eigen::Vector3d(r, r, r);
  for (int k = 0; k < 3; ++k) {
    if (d->p[k] < lo[k]) {
      d->p[k] = lo[k];
      d->v[k] = std::max(0.0, d->v[k]);
    } else if (d->p[k] > hi[k]) {
      d->p[k] = hi[k];
      d->v[k] = std::min(0.0, d->v[k]);
    }
  }
  tilt_from_acceleration(d->a, d->yaw, &d->roll, &d->pitch);
}

bool parse_script(const std::string& s, Script* out) {
  if (s == "none") *out = Script::none;
  else if (s == "hover") *out = Script::hover;
  else if (s == "spin") *out = Script::spin;
  else return false;
  return true;
}

Setpoint script_setpoint(Script s, ScriptState* st, const VioSample& vio, double t, double spin_rate) {
  Setpoint sp;
  sp.position = Eigen::Vector3d(0, 0, st->height);
  if (!st->airborne && std::abs(vio.position.z() - st->height) < 0.05 && vio.velocity.norm() < 0.1) {
    st->airborne = true;
    st->spin_start = t;
  }
  if (s == Script::spin && st->airborne) {
    sp.yaw_rate = spin_rate;
    sp.yaw = spin_rate * (t - st->spin_start);
  }
  return sp;
}

}  // namespace fact::sim
