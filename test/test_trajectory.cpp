// Minimum-jerk trajectories and yaw ramps: endpoints exact, velocity and acceleration within the
// limits by fine sampling (also from a moving start), the spin's yaw ramp (angle, rate and rate
// change limits), path points spacing, and bad input named.
#include "fact/planner.h"
#include "fact/trajectory.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace {

using Eigen::Vector3d;

TEST(Trajectory, MinJerkEndpointsExact) {
  fact::TrajectoryStart s;
  s.position = {0.5, -1.0, 1.2};
  s.velocity = {0.2, 0.1, 0.0};
  s.acceleration = {0.1, -0.2, 0.05};
  s.yaw = 0.7;
  const Vector3d target(2.0, 0.5, 1.4);
  const fact::Trajectory tr = fact::min_jerk(s, target, 3.0);
  const fact::TrajectorySample a = tr.sample(0), b = tr.sample(3.0), c = tr.sample(10.0);
  EXPECT_NEAR((a.position - s.position).norm(), 0, 1e-12);
  EXPECT_NEAR((a.velocity - s.velocity).norm(), 0, 1e-12);
  EXPECT_NEAR((a.acceleration - s.acceleration).norm(), 0, 1e-12);
  // Just before the end the polynomial itself reaches the target at rest.
  const fact::TrajectorySample e = tr.sample(3.0 - 1e-9);
  EXPECT_NEAR((e.position - target).norm(), 0, 1e-9);
  EXPECT_NEAR(e.velocity.norm(), 0, 1e-7);
  EXPECT_NEAR(e.acceleration.norm(), 0, 1e-6);
  EXPECT_NEAR((b.position - target).norm(), 0, 1e-12);
  EXPECT_NEAR((c.position - target).norm(), 0, 1e-12);
  EXPECT_EQ(c.velocity.norm(), 0);
  EXPECT_DOUBLE_EQ(a.yaw, 0.7);
  EXPECT_DOUBLE_EQ(c.yaw, 0.7);
  EXPECT_EQ(c.yaw_rate, 0);
}

TEST(Trajectory, WithinLimitsBySampling) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  fact::TrajectoryLimits lim;
  lim.v_max = 0.8;
  lim.a_max = 1.0;
  for (int trial = 0; trial < 200; ++trial) {
    fact::TrajectoryStart s;
    s.position = {u(rng), u(rng), 1 + u(rng)};
    if (trial % 2) {
      s.velocity = 0.5 * Vector3d(u(rng), u(rng), 0.3 * u(rng)) / std::sqrt(3.0);
      s.acceleration = 0.5 * Vector3d(u(rng), u(rng), 0) / std::sqrt(2.0);
    }
    const Vector3d target = s.position + 2.5 * Vector3d(u(rng), u(rng), 0.2 * u(rng));
    fact::Trajectory tr;
    ASSERT_EQ(fact::min_jerk_within_limits(s, target, lim, &tr), "");
    double vp = 0, ap = 0;
    for (double t = 0; t <= tr.duration(); t += 1e-3) {
      const fact::TrajectorySample x = tr.sample(t);
      vp = std::max(vp, x.velocity.norm());
      ap = std::max(ap, x.acceleration.norm());
    }
    EXPECT_LE(vp, lim.v_max * 1.001) << trial;
    EXPECT_LE(ap, lim.a_max * 1.001) << trial;
    EXPECT_NEAR((tr.end_position() - target).norm(), 0, 1e-9);
    // Rest to rest, the duration is near the analytic bound (not needlessly slow).
    if (trial % 2 == 0) {
      const double D = (target - s.position).norm();
      const double bound = std::max(1.875 * D / lim.v_max, std::sqrt(5.7735 * D / lim.a_max));
      EXPECT_LE(tr.duration(), bound * 1.03) << trial;
      EXPECT_GE(tr.duration(), bound * 0.999) << trial;
    }
  }
}

TEST(Trajectory, PathPointsAreCloseEnough) {
  fact::TrajectoryStart s;
  fact::Trajectory tr;
  ASSERT_EQ(fact::min_jerk_within_limits(s, Vector3d(1.5, 0.3, 0), {}, &tr), "");
  const auto pts = fact::path_points(tr, 0.05);
  ASSERT_GE(pts.size(), 2u);
  EXPECT_NEAR((pts.front() - s.position).norm(), 0, 1e-12);
  EXPECT_NEAR((pts.back() - Vector3d(1.5, 0.3, 0)).norm(), 0, 1e-9);
  for (size_t k = 1; k < pts.size(); ++k) EXPECT_LE((pts[k] - pts[k - 1]).norm(), 0.05);
}

TEST(Trajectory, SpinRampWithinRateAndAccel) {
  fact::PlannerParams p;
  const fact::Plan spin = fact::plan_spin(Vector3d(1, 2, 1.5), 0.3, p);
  ASSERT_EQ(spin.kind, fact::PlanKind::hold);
  const fact::Trajectory& tr = spin.trajectory;
  const double T = tr.duration();
  ASSERT_GT(T, 0);
  const double dt = 1e-3;
  double prev_rate = 0, max_rate = 0, max_acc = 0;
  for (double t = 0; t <= T + dt; t += dt) {
    const fact::TrajectorySample x = tr.sample(t);
    EXPECT_NEAR((x.position - Vector3d(1, 2, 1.5)).norm(), 0, 1e-12);
    max_rate = std::max(max_rate, std::abs(x.yaw_rate));
    if (t > 0) max_acc = std::max(max_acc, std::abs(x.yaw_rate - prev_rate) / dt);
    prev_rate = x.yaw_rate;
  }
  EXPECT_LE(max_rate, p.spin_rate + 1e-12);
  EXPECT_GT(max_rate, 0.99 * p.spin_rate);  // a full turn at 0.6 rad/s reaches the cruise rate
  EXPECT_LE(max_acc, p.yaw_accel * 1.001);
  const fact::TrajectorySample end = tr.sample(T);
  EXPECT_NEAR(end.yaw - 0.3, 2 * M_PI + p.spin_overlap, 1e-9);  // one full turn plus the overlap
  EXPECT_EQ(end.yaw_rate, 0);
  // The yaw is the integral of the rate (trapezoid rule).
  double integral = 0;
  for (double t = 0; t < T; t += dt) integral += 0.5 * (tr.sample(t).yaw_rate + tr.sample(std::min(T, t + dt)).yaw_rate) * std::min(dt, T - t);
  EXPECT_NEAR(integral, 2 * M_PI + p.spin_overlap, 1e-4);
  // Clockwise.
  const fact::Plan cw = fact::plan_spin(Vector3d(0, 0, 1), 0.0, p, -1);
  EXPECT_NEAR(cw.trajectory.sample(cw.trajectory.duration()).yaw, -(2 * M_PI + p.spin_overlap), 1e-9);
}

TEST(Trajectory, ShortYawTurnIsATriangle) {
  fact::YawProfile y;
  y.angle = 0.1;
  y.rate = 1.0;
  y.accel = 1.0;
  EXPECT_NEAR(y.duration(), 2 * std::sqrt(0.1), 1e-12);
  double yaw, rate;
  y.sample(y.duration() / 2, &yaw, &rate);
  EXPECT_NEAR(yaw, 0.05, 1e-12);
  EXPECT_NEAR(rate, std::sqrt(0.1), 1e-12);
}

TEST(Trajectory, NonFiniteInputNamed) {
  fact::TrajectoryStart s;
  fact::Trajectory tr;
  s.velocity.y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(fact::min_jerk_within_limits(s, Vector3d(1, 0, 0), {}, &tr), "start.velocity is not finite");
  s.velocity.y() = 0;
  EXPECT_EQ(fact::min_jerk_within_limits(s, Vector3d(1, std::numeric_limits<double>::infinity(), 0), {}, &tr),
            "target is not finite");
  fact::TrajectoryLimits lim;
  lim.a_max = 0;
  EXPECT_EQ(fact::min_jerk_within_limits(s, Vector3d(1, 0, 0), lim, &tr), "limits.a_max must be > 0");
}

}  // namespace
