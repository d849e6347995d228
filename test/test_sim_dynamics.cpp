// Simulated dynamics, flight controller, VIO drift and scripts: a setpoint in f_i is reached in
// the world at o_i + R_z(θ_i)·sp within the acceleration and speed limits, the yaw-rate limit
// holds, the tilt points the thrust along a + g, the drift random walks have σ·√t spread, the
// drone holds its start pose before any setpoint, the spin script spins, and runs are
// deterministic by seed.
#include "fact/camera.h"
#include "fact/sim_dynamics.h"

#include <gtest/gtest.h>

#include <cmath>

namespace {

using namespace fact::sim;

constexpr double kDt = 0.002;

World quiet_world() {
  World w;
  w.room_size = {10, 10, 4};
  w.vio.position = 0;
  w.vio.yaw = 0;
  return w;
}

TEST(SimDynamics, ReachesSetpointInItsFrameWithinLimits) {
  const World w = quiet_world();
  std::mt19937_64 rng(1);
  DroneStart start{3, {1, 2, 0}, 1.0};
  SimDrone d = make_drone(start);
  d.setpoint.position = {2, 1, 1.5};  // in f_i
  d.setpoint.yaw = 0.5;
  d.have_setpoint = true;
  d.landed = false;
  const DynamicsLimits lim;
  double max_a = 0, max_v = 0;
  for (int k = 0; k < static_cast<int>(12.0 / kDt); ++k) {
    step_drone(&d, w, ControllerGains{}, lim, kDt, &rng);
    max_a = std::max(max_a, d.a.norm());
    max_v = std::max(max_v, d.v.norm());
  }
  const Eigen::Vector3d expected =
      start.position + Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ()) * Eigen::Vector3d(2, 1, 1.5);
  EXPECT_LT((d.p - expected).norm(), 0.01) << d.p.transpose();
  EXPECT_NEAR(d.yaw, 1.5, 1e-3);
  EXPECT_LE(max_a, lim.max_accel + 1e-9);
  EXPECT_GT(max_a, 0.9 * lim.max_accel);  // the limit was actually reached
  EXPECT_LE(max_v, lim.max_speed + 1e-9);
  EXPECT_GT(max_v, 1.0);
  EXPECT_LT(d.v.norm(), 0.01);
  const VioSample v = vio_sample(d);
  EXPECT_LT((v.position - Eigen::Vector3d(2, 1, 1.5)).norm(), 0.01);
  EXPECT_NEAR(v.yaw, 0.5, 1e-3);
}

TEST(SimDynamics, YawRateLimitRespected) {
  const World w = quiet_world();
  std::mt19937_64 rng(1);
  SimDrone d = make_drone(DroneStart{0, {0, 0, 0}, 0});
  d.setpoint.position = {0, 0, 0};
  d.setpoint.yaw = 3.0;
  d.have_setpoint = true;
  d.landed = false;
  double max_rate = 0;
  double t_reach = -1;
  for (int k = 0; k < static_cast<int>(5.0 / kDt); ++k) {
    const double before = d.yaw;
    step_drone(&d, w, ControllerGains{}, DynamicsLimits{}, kDt, &rng);
    max_rate = std::max(max_rate, std::abs(d.yaw - before) / kDt);
    if (t_reach < 0 && std::abs(d.yaw - 3.0) < 0.01) t_reach = (k + 1) * kDt;
  }
  EXPECT_LE(max_rate, 1.5 + 1e-9);
  EXPECT_GT(max_rate, 1.5 - 1e-9);
  EXPECT_GT(t_reach, 3.0 / 1.5);  // cannot be faster than the limit allows
  EXPECT_LT(t_reach, 4.0);
  // A setpoint across ±π turns the short way: from 3.0 to −3.0 is +0.28 rad.
  d.setpoint.yaw = -3.0;
  for (int k = 0; k < static_cast<int>(5.0 / kDt); ++k) step_drone(&d, w, ControllerGains{}, DynamicsLimits{}, kDt, &rng);
  EXPECT_NEAR(d.yaw, 2 * M_PI - 3.0, 1e-3);
}

TEST(SimDynamics, TiltPointsThrustAlongAccelerationPlusGravity) {
  for (double yaw : {0.0, 1.0, -2.5}) {
    const Eigen::Vector3d a(1.5, -2.0, 0.5);
    double roll = 0, pitch = 0;
    tilt_from_acceleration(a, yaw, &roll, &pitch);
    const Eigen::Vector3d thrust = fact::body_attitude(yaw, pitch, roll) * Eigen::Vector3d::UnitZ();
    EXPECT_NEAR((thrust - (a + Eigen::Vector3d(0, 0, 9.81)).normalized()).norm(), 0, 1e-12) << yaw;
  }
  double roll = 0, pitch = 0;
  tilt_from_acceleration({2, 0, 0}, 0, &roll, &pitch);
  EXPECT_GT(pitch, 0.1);  // accelerating forward: nose down (positive pitch)
  EXPECT_NEAR(roll, 0, 1e-12);
}

TEST(SimDynamics, HoldsStartPoseBeforeAnySetpoint) {
  World w = quiet_world();
  std::mt19937_64 rng(1);
  SimDrone d = make_drone(DroneStart{0, {1, -1, 0}, 0.7});
  for (int k = 0; k < 1000; ++k) step_drone(&d, w, ControllerGains{}, DynamicsLimits{}, kDt, &rng);
  EXPECT_EQ(d.p, Eigen::Vector3d(1, -1, 0));
  EXPECT_EQ(d.yaw, 0.7);
  const VioSample v = vio_sample(d);
  EXPECT_EQ(v.position, Eigen::Vector3d::Zero());
  EXPECT_EQ(v.yaw, 0.0);
}

TEST(SimDynamics, SetpointErrorNamesTheField) {
  Setpoint sp;
  EXPECT_EQ(setpoint_error(sp), "");
  sp.velocity[2] = std::nan("");
  EXPECT_EQ(setpoint_error(sp).rfind("velocity[2] = ", 0), 0u) << setpoint_error(sp);
  sp = Setpoint{};
  sp.yaw_rate = INFINITY;
  EXPECT_EQ(setpoint_error(sp).rfind("yaw_rate", 0), 0u);
}

// Many landed drones for T seconds: each drift component is a random walk with variance σ²·T.
TEST(SimVio, DriftRandomWalkStatistics) {
  World w = quiet_world();
  w.vio.position = 0.01;
  w.vio.yaw = 0.002;
  std::mt19937_64 rng(99);
  const int n = 400;
  const double T = 50, dt = 0.01;
  double sp2 = 0, sy2 = 0, mean_x = 0;
  for (int i = 0; i < n; ++i) {
    SimDrone d = make_drone(DroneStart{i, {0, 0, 0}, 0.3});
    for (int k = 0; k < static_cast<int>(T / dt); ++k) step_drone(&d, w, ControllerGains{}, DynamicsLimits{}, dt, &rng);
    sp2 += d.drift_p.squaredNorm() / 3;
    sy2 += d.drift_yaw * d.drift_yaw;
    mean_x += d.drift_p.x();
    // The VIO reports exactly the drift while the drone sits at its origin.
    const VioSample v = vio_sample(d);
    ASSERT_NEAR((v.position - d.drift_p).norm(), 0, 1e-15);
    ASSERT_NEAR(v.yaw, d.drift_yaw, 1e-15);
  }
  const double sd_p = std::sqrt(sp2 / n), sd_y = std::sqrt(sy2 / n);
  EXPECT_NEAR(sd_p, 0.01 * std::sqrt(T), 0.08 * 0.01 * std::sqrt(T));
  EXPECT_NEAR(sd_y, 0.002 * std::sqrt(T), 0.12 * 0.002 * std::sqrt(T));
  EXPECT_NEAR(mean_x / n, 0, 4 * 0.01 * std::sqrt(T / n));
}

// The flight controller works on VIO: with drift the physical position is off by the drift.
TEST(SimVio, ControllerFollowsDriftedVio) {
  World w = quiet_world();
  std::mt19937_64 rng(1);
  SimDrone d = make_drone(DroneStart{0, {0, 0, 0}, 0.0});
  d.drift_p = {0.3, 0, 0};
  d.setpoint.position = {0, 0, 1};
  d.have_setpoint = true;
  d.landed = false;
  for (int k = 0; k < static_cast<int>(8.0 / kDt); ++k) step_drone(&d, w, ControllerGains{}, DynamicsLimits{}, kDt, &rng);
  EXPECT_LT((d.p - Eigen::Vector3d(-0.3, 0, 1)).norm(), 0.01) << d.p.transpose();
}

// The drifted VIO is a rigid frame: its effective frame (from the true pose and the VIO sample, as
// fact-run-report computes it) is the same wherever the drone is and however it is turned (it
// moved by d_y·|p − o_i| when positions turned by θ_i alone and the heading by θ_i − d_y).
TEST(SimVio, DriftedVioIsARigidFrame) {
  SimDrone d = make_drone(DroneStart{0, {1, 2, 0}, 0.7});
  d.drift_p = {0.2, -0.1, 0.05};
  d.drift_yaw = 0.03;
  const auto frame = [&](const Eigen::Vector3d& p, double yaw) {
    d.p = p;
    d.yaw = yaw;
    d.v = {0.5, -0.2, 0};
    const VioSample v = vio_sample(d);
    const double f_yaw = d.yaw - v.yaw;
    const Eigen::Vector3d f_origin = d.p - Eigen::AngleAxisd(f_yaw, Eigen::Vector3d::UnitZ()) * v.position;
    // The velocity turns with the positions: R(f_yaw)·vio_vel is the world velocity.
    EXPECT_LT((Eigen::AngleAxisd(f_yaw, Eigen::Vector3d::UnitZ()) * v.velocity - d.v).norm(), 1e-12);
    return std::make_pair(f_yaw, f_origin);
  };
  const auto [yaw0, origin0] = frame({1, 2, 0}, 0.7);
  EXPECT_NEAR(yaw0, 0.7 - 0.03, 1e-12);
  for (const auto& [p, yaw] : std::vector<std::pair<Eigen::Vector3d, double>>{{{4, -3, 1.5}, 2.0}, {{-2, 5, 1}, -1.0}}) {
    const auto [y, o] = frame(p, yaw);
    EXPECT_NEAR(y, yaw0, 1e-12);
    EXPECT_LT((o - origin0).norm(), 1e-12) << o.transpose() << " vs " << origin0.transpose();
  }
}

// A setpoint beyond the wall: the drone stops with its body inside the room (its centre stopped
// at the wall, and the camera 0.10 m ahead left the room).
TEST(SimDynamics, WallsStopTheBodyNotJustTheCentre) {
  World w = quiet_world();
  std::mt19937_64 rng(1);
  const double r = bounding_radius(DroneBody{});
  for (const Eigen::Vector3d& target : {Eigen::Vector3d(999, 0, 1), Eigen::Vector3d(0, 0, 99)}) {
    SimDrone d = make_drone(DroneStart{0, {0, 0, 0}, 0.0});
    d.setpoint.position = target;
    d.have_setpoint = true;
    d.landed = false;
    for (int k = 0; k < static_cast<int>(15.0 / kDt); ++k) step_drone(&d, w, ControllerGains{}, DynamicsLimits{}, kDt, &rng);
    if (target.x() > 100) {
      EXPECT_NEAR(d.p.x(), room_max(w).x() - r, 1e-9);  // the wall
    } else {
      EXPECT_NEAR(d.p.z(), room_max(w).z() - r, 1e-9);  // the ceiling
    }
  }
  EXPECT_GT(r, 0.10);  // the camera's offset: it stays inside
}

TEST(SimScript, SpinTakesOffThenSpinsAtTheRate) {
  const World w = quiet_world();
  std::mt19937_64 rng(1);
  SimDrone d = make_drone(DroneStart{0, {0, 0, 0}, 0.4});
  d.have_setpoint = true;
  d.landed = false;
  ScriptState st;
  st.height = 1.3;
  double t = 0;
  double yaw_at_8 = 0;
  for (int k = 0; k < static_cast<int>(12.0 / kDt); ++k) {
    d.setpoint = script_setpoint(Script::spin, &st, vio_sample(d), t, 0.8);
    step_drone(&d, w, ControllerGains{}, DynamicsLimits{}, kDt, &rng);
    t += kDt;
    if (std::abs(t - 8.0) < kDt / 2) yaw_at_8 = d.yaw;
  }
  ASSERT_TRUE(st.airborne);
  EXPECT_LT(st.spin_start, 6.0);
  EXPECT_NEAR(d.p.z(), 1.3, 0.02);
  EXPECT_LT(d.p.head<2>().norm(), 0.02);
  EXPECT_NEAR((d.yaw - yaw_at_8) / (t - 8.0), 0.8, 0.01);
  EXPECT_NEAR(d.yaw_rate, 0.8, 0.01);
}

TEST(SimDynamics, DeterministicBySeed) {
  World w = quiet_world();
  w.vio.position = 0.01;
  auto run = [&](uint64_t seed) {
    std::mt19937_64 rng(seed);
    SimDrone d = make_drone(DroneStart{0, {0, 0, 0}, 0});
    d.setpoint.position = {1, 1, 1};
    d.have_setpoint = true;
    d.landed = false;
    for (int k = 0; k < 1000; ++k) step_drone(&d, w, ControllerGains{}, DynamicsLimits{}, kDt, &rng);
    return d.p;
  };
  EXPECT_EQ(run(5), run(5));
  EXPECT_NE(run(5), run(6));
}

TEST(SimScript, ParseScript) {
  Script s;
  EXPECT_TRUE(parse_script("spin", &s));
  EXPECT_EQ(s, Script::spin);
  EXPECT_TRUE(parse_script("hover", &s));
  EXPECT_EQ(s, Script::hover);
  EXPECT_FALSE(parse_script("loop", &s));
}

}  // namespace
