// Tests of fact::OdometryFilter and its helpers (lib/odometry_filter): angle wrapping and yaw
// unwrapping across ±π, quaternion → yaw/pitch/roll for known rotations, pose-line parsing, every
// rejection reason with its counter, velocity by finite difference, and the log rate limit.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "fact/odometry_filter.h"

namespace {

constexpr double kPi = 3.14159265358979323846;
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

// q = qz(yaw) · qy(pitch) · qx(roll): the world-from-body rotation Rz(yaw) Ry(pitch) Rx(roll).
void quaternion(double yaw, double pitch, double roll, double q[4]) {
  const double cy = std::cos(yaw / 2), sy = std::sin(yaw / 2);
  const double cp = std::cos(pitch / 2), sp = std::sin(pitch / 2);
  const double cr = std::cos(roll / 2), sr = std::sin(roll / 2);
  q[3] = cy * cp * cr + sy * sp * sr;  // w
  q[0] = cy * cp * sr - sy * sp * cr;  // x
  q[1] = cy * sp * cr + sy * cp * sr;  // y
  q[2] = sy * cp * cr - cy * sp * sr;  // z
}

fact::OdometryInput sample(double t_s, double x, double y, double z, double yaw) {
  fact::OdometryInput in;
  in.utime = t_s * 1e6;
  in.position = Eigen::Vector3d(x, y, z);
  in.yaw = yaw;
  return in;
}

fact::PoseLine pose(double t_s, double x, double y, double z, double yaw, double pitch = 0, double roll = 0) {
  fact::PoseLine p;
  p.time = t_s;
  p.position = Eigen::Vector3d(x, y, z);
  double q[4];
  quaternion(yaw, pitch, roll, q);
  p.qx = q[0];
  p.qy = q[1];
  p.qz = q[2];
  p.qw = q[3];
  return p;
}

TEST(WrapAngle, IntoHalfOpenInterval) {
  EXPECT_DOUBLE_EQ(fact::wrap_angle(0), 0);
  EXPECT_DOUBLE_EQ(fact::wrap_angle(kPi), kPi);
  EXPECT_DOUBLE_EQ(fact::wrap_angle(-kPi), kPi);  // (−π, π]
  EXPECT_NEAR(fact::wrap_angle(3 * kPi / 2), -kPi / 2, 1e-15);
  EXPECT_NEAR(fact::wrap_angle(-3 * kPi / 2), kPi / 2, 1e-15);
  EXPECT_NEAR(fact::wrap_angle(20 * kPi + 0.25), 0.25, 1e-13);
  EXPECT_NEAR(fact::wrap_angle(-20 * kPi - 0.25), -0.25, 1e-13);
  EXPECT_TRUE(std::isnan(fact::wrap_angle(kNaN)));
}

TEST(Attitude, KnownRotations) {
  fact::Attitude a;
  // Identity.
  ASSERT_EQ(fact::attitude_from_quaternion(0, 0, 0, 1, &a), "");
  EXPECT_NEAR(a.yaw, 0, 1e-15);
  EXPECT_NEAR(a.pitch, 0, 1e-15);
  EXPECT_NEAR(a.roll, 0, 1e-15);
  // 90° about z: the body x axis points along world y (left) → yaw +π/2.
  const double h = std::sqrt(0.5);
  ASSERT_EQ(fact::attitude_from_quaternion(0, 0, h, h, &a), "");
  EXPECT_NEAR(a.yaw, kPi / 2, 1e-15);
  EXPECT_NEAR(a.pitch, 0, 1e-15);
  EXPECT_NEAR(a.roll, 0, 1e-15);
  // 180° about z: yaw π (not −π).
  ASSERT_EQ(fact::attitude_from_quaternion(0, 0, 1, 0, &a), "");
  EXPECT_DOUBLE_EQ(a.yaw, kPi);
  ASSERT_EQ(fact::attitude_from_quaternion(0, 0, -1, 0, &a), "");
  EXPECT_DOUBLE_EQ(a.yaw, kPi);
  // −90° about z.
  ASSERT_EQ(fact::attitude_from_quaternion(0, 0, -h, h, &a), "");
  EXPECT_NEAR(a.yaw, -kPi / 2, 1e-15);
  // 90° roll about x: heading unchanged.
  ASSERT_EQ(fact::attitude_from_quaternion(h, 0, 0, h, &a), "");
  EXPECT_NEAR(a.yaw, 0, 1e-15);
  EXPECT_NEAR(a.roll, kPi / 2, 1e-15);
  EXPECT_NEAR(a.pitch, 0, 1e-15);
  // Pitch 0.3 about y (nose down in FLU: x axis rotates toward −z), heading unchanged.
  ASSERT_EQ(fact::attitude_from_quaternion(0, std::sin(0.15), 0, std::cos(0.15), &a), "");
  EXPECT_NEAR(a.yaw, 0, 1e-15);
  EXPECT_NEAR(a.pitch, 0.3, 1e-15);
  // q and −q are the same rotation.
  ASSERT_EQ(fact::attitude_from_quaternion(0, 0, -h, -h, &a), "");
  EXPECT_NEAR(a.yaw, kPi / 2, 1e-15);
}

TEST(Attitude, ComposedRotationsRoundTrip) {
  for (double yaw : {-3.0, -1.2, 0.0, 0.7, 2.5, 3.1}) {
    for (double pitch : {-1.2, -0.3, 0.0, 0.4}) {
      for (double roll : {-2.8, -0.5, 0.0, 0.2, 1.4}) {
        double q[4];
        quaternion(yaw, pitch, roll, q);
        fact::Attitude a;
        ASSERT_EQ(fact::attitude_from_quaternion(q[0], q[1], q[2], q[3], &a), "");
        EXPECT_NEAR(a.yaw, yaw, 1e-12) << yaw << " " << pitch << " " << roll;
        EXPECT_NEAR(a.pitch, pitch, 1e-12);
        EXPECT_NEAR(a.roll, roll, 1e-12);
        // The yaw is the heading of the rotated body x axis, whatever the tilt.
        const double x = q[0], y = q[1], z = q[2], w = q[3];
        EXPECT_NEAR(a.yaw, std::atan2(2 * (x * y + w * z), 1 - 2 * (y * y + z * z)), 1e-12);
      }
    }
  }
}

TEST(Attitude, NormalisesNearlyUnitQuaternions) {
  const double h = std::sqrt(0.5) * 1.005;  // norm 1.005
  fact::Attitude a;
  ASSERT_EQ(fact::attitude_from_quaternion(0, 0, h, h, &a), "");
  EXPECT_NEAR(a.yaw, kPi / 2, 1e-15);
}

TEST(Attitude, RejectsUnusableQuaternions) {
  fact::Attitude a;
  EXPECT_NE(fact::attitude_from_quaternion(0, 0, 0, 2, &a).find("norm 2"), std::string::npos);
  EXPECT_NE(fact::attitude_from_quaternion(0, 0, 0, 0, &a).find("norm 0"), std::string::npos);
  EXPECT_NE(fact::attitude_from_quaternion(kNaN, 0, 0, 1, &a).find("not finite"), std::string::npos);
  // Pitch 90°: the body x axis is vertical, the heading undefined.
  EXPECT_NE(fact::attitude_from_quaternion(0, std::sqrt(0.5), 0, std::sqrt(0.5), &a).find("heading undefined"),
            std::string::npos);
}

TEST(PoseLine, ParsesTumLines) {
  fact::PoseLine p;
  std::string err;
  ASSERT_EQ(fact::parse_pose_line("1305031102.175304 1.5 -2 0.25 0 0 0.7071 0.7071\n", &p, &err),
            fact::PoseLineKind::sample)
      << err;
  EXPECT_DOUBLE_EQ(p.time, 1305031102.175304);
  EXPECT_EQ(p.position, Eigen::Vector3d(1.5, -2, 0.25));
  EXPECT_DOUBLE_EQ(p.qz, 0.7071);
  EXPECT_DOUBLE_EQ(p.qw, 0.7071);
  ASSERT_EQ(fact::parse_pose_line("\t0 1\t2 3  0 0 0 1\r\n", &p, &err), fact::PoseLineKind::sample) << err;
  EXPECT_EQ(p.position, Eigen::Vector3d(1, 2, 3));
  // nan and inf are numbers to the parser: the filter rejects them.
  ASSERT_EQ(fact::parse_pose_line("1 nan 0 0 0 0 0 1", &p, &err), fact::PoseLineKind::sample);
  EXPECT_TRUE(std::isnan(p.position.x()));
  ASSERT_EQ(fact::parse_pose_line("inf 0 0 0 0 0 0 1", &p, &err), fact::PoseLineKind::sample);
  EXPECT_TRUE(std::isinf(p.time));
}

TEST(PoseLine, CommentsAndBlankLinesCarryNoSample) {
  fact::PoseLine p;
  std::string err;
  EXPECT_EQ(fact::parse_pose_line("", &p, &err), fact::PoseLineKind::empty);
  EXPECT_EQ(fact::parse_pose_line("   \n", &p, &err), fact::PoseLineKind::empty);
  EXPECT_EQ(fact::parse_pose_line("# timestamp tx ty tz qx qy qz qw", &p, &err), fact::PoseLineKind::empty);
  EXPECT_EQ(fact::parse_pose_line("  #1 2 3", &p, &err), fact::PoseLineKind::empty);
}

TEST(PoseLine, MalformedLinesSayWhy) {
  fact::PoseLine p;
  std::string err;
  EXPECT_EQ(fact::parse_pose_line("1 2 3", &p, &err), fact::PoseLineKind::malformed);
  EXPECT_EQ(err, "expected 8 numbers (t tx ty tz qx qy qz qw), got 3");
  EXPECT_EQ(fact::parse_pose_line("1 2 3 4 5 6 7 8 9", &p, &err), fact::PoseLineKind::malformed);
  EXPECT_EQ(err, "expected 8 numbers (t tx ty tz qx qy qz qw), got 9");
  EXPECT_EQ(fact::parse_pose_line("1 2 3 1.2.3 0 0 0 1", &p, &err), fact::PoseLineKind::malformed);
  EXPECT_EQ(err, "field 4 (tz) is not a number: \"1.2.3\"");
  EXPECT_EQ(fact::parse_pose_line("1,2,3,4,5,6,7,8", &p, &err), fact::PoseLineKind::malformed);
  // A NUL byte inside a token (a binary datagram) is not a number either.
  EXPECT_EQ(fact::parse_pose_line(std::string("1 2 3 4 0 0 0 1\0x", 17), &p, &err), fact::PoseLineKind::malformed);
  EXPECT_EQ(err, "field 8 (qw) is not a number: \"1?x\"");
  // Two lines in one datagram.
  EXPECT_EQ(fact::parse_pose_line("0 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1", &p, &err), fact::PoseLineKind::malformed);
}

TEST(OdometryFilter, UnwrapsYawAcrossPiManyTimes) {
  fact::OdometryFilter f;  // max yaw rate 6 rad/s
  // 0.5 rad per 0.1 s (5 rad/s) for 200 samples: about 16 turns; the input is wrapped into (−π, π].
  for (int k = 0; k < 200; ++k) {
    const double truth = -1.0 + 0.5 * k;
    const fact::FilterResult r = f.push(sample(0.1 * k, 0, 0, 0, fact::wrap_angle(truth)));
    ASSERT_TRUE(r.accepted()) << k << ": " << r.detail;
    EXPECT_NEAR(r.output.yaw, truth, 1e-9) << k;
    EXPECT_EQ(r.output.seq, k);
  }
  // And backwards, through zero and −π many times.
  for (int k = 200; k < 400; ++k) {
    const double truth = -1.0 + 0.5 * 199 - 0.5 * (k - 199);
    const fact::FilterResult r = f.push(sample(0.1 * k, 0, 0, 0, fact::wrap_angle(truth)));
    ASSERT_TRUE(r.accepted()) << k << ": " << r.detail;
    EXPECT_NEAR(r.output.yaw, truth, 1e-9) << k;
  }
  EXPECT_NEAR(f.last().yaw, -1.0 + 0.5 * 199 - 0.5 * 200, 1e-9);
  EXPECT_EQ(f.count(fact::Rejection::none), 400);
}

TEST(OdometryFilter, KeepsAlreadyUnwrappedYaw) {
  fact::OdometryFilter f;
  for (int k = 0; k < 50; ++k) {
    const double yaw = 10.0 + 0.45 * k;  // never wrapped by the source
    const fact::FilterResult r = f.push(sample(0.1 * k, 0, 0, 0, yaw));
    ASSERT_TRUE(r.accepted());
    EXPECT_NEAR(r.output.yaw, yaw, 1e-12);
  }
}

TEST(OdometryFilter, RejectsNonFiniteFields) {
  fact::OdometryFilter f;
  ASSERT_TRUE(f.push(sample(1.0, 0, 0, 0, 0)).accepted());
  fact::FilterResult r = f.push(sample(1.1, kNaN, 0, 0, 0));
  EXPECT_EQ(r.rejection, fact::Rejection::non_finite);
  EXPECT_EQ(r.detail, "position[0] is nan");
  r = f.push(sample(1.1, 0, 0, 0, kInf));
  EXPECT_EQ(r.detail, "yaw is inf");
  r = f.push(sample(kNaN, 0, 0, 0, 0));
  EXPECT_EQ(r.detail, "utime is nan");
  fact::OdometryInput in = sample(1.1, 0, 0, 0, 0);
  in.roll = -kInf;
  EXPECT_EQ(f.push(in).detail, "roll is -inf");
  in = sample(1.1, 0, 0, 0, 0);
  in.has_velocity = true;
  in.velocity = Eigen::Vector3d(0, kNaN, 0);
  EXPECT_EQ(f.push(in).detail, "velocity[1] is nan");
  in.has_velocity = false;  // an unused velocity is not checked
  EXPECT_TRUE(f.push(in).accepted());
  EXPECT_EQ(f.count(fact::Rejection::non_finite), 5);
  EXPECT_EQ(fact::counter_name(fact::Rejection::non_finite), std::string("rejected_nan"));
  // A NaN first sample does not become the reference either.
  fact::OdometryFilter g;
  EXPECT_FALSE(g.push(sample(1.0, 0, kNaN, 0, 0)).accepted());
  EXPECT_FALSE(g.has_last());
  EXPECT_EQ(g.push(sample(1.0, 0, 0, 0, 0)).output.seq, 0);
}

TEST(OdometryFilter, RejectsOutOfOrderAndDuplicateTimes) {
  fact::OdometryFilter f;
  ASSERT_TRUE(f.push(sample(2.0, 0, 0, 0, 0)).accepted());
  fact::FilterResult r = f.push(sample(2.0, 0, 0, 0, 0));  // duplicate
  EXPECT_EQ(r.rejection, fact::Rejection::out_of_order);
  EXPECT_EQ(r.detail, "utime 2000000 us is not after the last accepted 2000000 us");
  EXPECT_EQ(f.push(sample(1.5, 0, 0, 0, 0)).rejection, fact::Rejection::out_of_order);
  // Times closer than half a microsecond round to the same µs: a duplicate too.
  fact::OdometryInput in = sample(2.0, 0, 0, 0, 0);
  in.utime += 0.4;
  EXPECT_EQ(f.push(in).rejection, fact::Rejection::out_of_order);
  EXPECT_TRUE(f.push(sample(2.1, 0, 0, 0, 0)).accepted());
  EXPECT_EQ(f.count(fact::Rejection::out_of_order), 3);
  EXPECT_EQ(f.last().seq, 1);
  EXPECT_EQ(f.last().utime, 2100000);
  EXPECT_EQ(fact::counter_name(fact::Rejection::out_of_order), std::string("rejected_out_of_order"));
}

TEST(OdometryFilter, RejectsPositionAndYawJumps) {
  fact::OdometryFilterOptions o;
  o.max_speed = 10;
  o.max_yaw_rate = 6;
  fact::OdometryFilter f(o);
  ASSERT_TRUE(f.push(sample(0.0, 0, 0, 0, 3.0)).accepted());
  // 1.2 m in 0.1 s = 12 m/s.
  fact::FilterResult r = f.push(sample(0.1, 1.2, 0, 0, 3.0));
  EXPECT_EQ(r.rejection, fact::Rejection::jump);
  EXPECT_NE(r.detail.find("12 m/s > max 10 m/s"), std::string::npos) << r.detail;
  // 0.9 m in 0.1 s = 9 m/s: fine (compared with the last accepted sample, not the outlier).
  EXPECT_TRUE(f.push(sample(0.1, 0.9, 0, 0, 3.0)).accepted());
  // Yaw 3.0 → −2.5 across π is a step of 0.783 rad: 7.8 rad/s in 0.1 s.
  r = f.push(sample(0.2, 0.9, 0, 0, -2.5));
  EXPECT_EQ(r.rejection, fact::Rejection::jump);
  EXPECT_NE(r.detail.find("rad/s > max 6 rad/s"), std::string::npos) << r.detail;
  // The same step over 0.2 s is 3.9 rad/s: accepted, and continuous (3.0 + 0.783).
  r = f.push(sample(0.3, 0.9, 0, 0, -2.5));
  ASSERT_TRUE(r.accepted()) << r.detail;
  EXPECT_NEAR(r.output.yaw, -2.5 + 2 * kPi, 1e-12);
  EXPECT_EQ(f.count(fact::Rejection::jump), 2);
  EXPECT_EQ(fact::counter_name(fact::Rejection::jump), std::string("rejected_jump"));
}

TEST(OdometryFilter, AcceptsARealDiscontinuityOnceTheLimitsAllowIt) {
  fact::OdometryFilter f;  // 10 m/s
  ASSERT_TRUE(f.push(sample(0.0, 0, 0, 0, 0)).accepted());
  // The VIO resets 5 m away: rejected while 5 m / Δt > 10 m/s, accepted from Δt = 0.5 s.
  int rejected = 0;
  for (int k = 1; k <= 10; ++k) {
    const fact::FilterResult r = f.push(sample(0.1 * k, 5, 0, 0, 0));
    if (!r.accepted()) {
      ++rejected;
      EXPECT_EQ(r.rejection, fact::Rejection::jump);
    } else {
      EXPECT_EQ(k, 5);
      break;
    }
  }
  EXPECT_EQ(rejected, 4);
  EXPECT_EQ(f.last().position, Eigen::Vector3d(5, 0, 0));
}

// One bad sample must not block the stream for good (review, session 30: an absurd first
// position, one accepted far-future time and a VIO clock restart each did).
TEST(OdometryFilter, OneBadSampleNeverBlocksTheStream) {
  {  // an absurd first position is out of range; the next sample starts the stream
    fact::OdometryFilter f;
    const fact::FilterResult r = f.push(sample(0.0, 1e300, 0, 0, 0));
    EXPECT_EQ(r.rejection, fact::Rejection::out_of_range);
    EXPECT_EQ(r.detail, "position[0] = 1e+300 m is beyond ±10000 m");
    EXPECT_STREQ(fact::counter_name(r.rejection), "rejected_range");
    EXPECT_TRUE(f.push(sample(0.1, 1, 0, 0, 0)).accepted());
  }
  {  // a far-future time is a jump (the gap), not the new reference
    fact::OdometryFilter f;
    ASSERT_TRUE(f.push(sample(1.00, 0, 0, 0, 0)).accepted());
    const fact::FilterResult r = f.push(sample(1e9, 0, 0, 0, 0));
    EXPECT_EQ(r.rejection, fact::Rejection::jump);
    EXPECT_NE(r.detail.find("time gap of"), std::string::npos) << r.detail;
    for (int k = 1; k <= 5; ++k) EXPECT_TRUE(f.push(sample(1.0 + 0.1 * k, 0, 0, 0, 0)).accepted()) << k;
  }
  {  // the VIO's clock restarts at 0: 19 samples rejected, the 20th restarts the stream (seq 0)
    fact::OdometryFilter f;
    for (int k = 0; k < 10; ++k) ASSERT_TRUE(f.push(sample(100 + 0.1 * k, 0, 0, 0, 0)).accepted());
    for (int k = 0; k < 19; ++k) {
      const fact::FilterResult r = f.push(sample(0.1 * k, 2, 0, 0, 1));
      EXPECT_EQ(r.rejection, fact::Rejection::out_of_order) << k;
      EXPECT_FALSE(r.restarted);
    }
    const fact::FilterResult r = f.push(sample(1.9, 2, 0, 0, 1));
    ASSERT_TRUE(r.accepted()) << r.detail;
    EXPECT_TRUE(r.restarted);
    EXPECT_EQ(r.output.seq, 0);
    EXPECT_EQ(r.output.utime, 1900000);
    EXPECT_EQ(r.output.yaw, 1);
    EXPECT_NE(r.detail.find("stream restarted: 20 samples in a row"), std::string::npos) << r.detail;
    const fact::FilterResult next = f.push(sample(2.0, 2, 0, 0, 1));
    ASSERT_TRUE(next.accepted()) << next.detail;
    EXPECT_FALSE(next.restarted);
    EXPECT_EQ(next.output.seq, 1);
  }
  {  // a frozen VIO repeating its last sample, and scattered outliers, never restart it (review,
     // session 30: the first version republished a frozen pose as a new stream every 20 samples)
    fact::OdometryFilter f;
    ASSERT_TRUE(f.push(sample(1.0, 0, 0, 0, 0)).accepted());
    for (int k = 0; k < 60; ++k) EXPECT_FALSE(f.push(sample(1.0, 0, 0, 0, 0)).accepted()) << k;
    for (int k = 0; k < 60; ++k)
      EXPECT_FALSE(f.push(sample(1.1 + 0.1 * k, k % 2 ? 500.0 + 100 * k : -500.0 - 100 * k, 0, 0, 0)).accepted()) << k;
    EXPECT_EQ(f.count(fact::Rejection::none), 1);
  }
}

TEST(OdometryFilter, RejectsTimesBeyondInt64) {
  fact::OdometryFilter f;
  const fact::FilterResult r = f.push(sample(1e16, 0, 0, 0, 0));  // 1e22 µs
  EXPECT_EQ(r.rejection, fact::Rejection::bad_time);
  EXPECT_EQ(fact::counter_name(fact::Rejection::bad_time), std::string("rejected_time"));
}

TEST(OdometryFilter, VelocityByFiniteDifference) {
  fact::OdometryFilter f;
  fact::FilterResult r = f.push(sample(10.0, 1, 2, 3, 0));
  ASSERT_TRUE(r.accepted());
  EXPECT_EQ(r.output.velocity, Eigen::Vector3d::Zero());  // nothing to difference yet
  r = f.push(sample(10.25, 1.5, 1.0, 3.0, 0));
  ASSERT_TRUE(r.accepted());
  EXPECT_NEAR(r.output.velocity.x(), 2.0, 1e-9);
  EXPECT_NEAR(r.output.velocity.y(), -4.0, 1e-9);
  EXPECT_NEAR(r.output.velocity.z(), 0.0, 1e-9);
  // A rejected outlier in between does not enter the difference.
  EXPECT_FALSE(f.push(sample(10.3, 50, 0, 0, 0)).accepted());
  r = f.push(sample(10.75, 1.5, 1.0, 4.0, 0));
  ASSERT_TRUE(r.accepted());
  EXPECT_NEAR(r.output.velocity.z(), 2.0, 1e-9);
  EXPECT_NEAR(r.output.velocity.x(), 0.0, 1e-9);
}

TEST(OdometryFilter, KeepsTheSourcesVelocity) {
  fact::OdometryFilter f;
  fact::OdometryInput in = sample(1.0, 0, 0, 0, 0);
  in.has_velocity = true;
  in.velocity = Eigen::Vector3d(0.1, 0.2, 0.3);
  EXPECT_EQ(f.push(in).output.velocity, Eigen::Vector3d(0.1, 0.2, 0.3));
  in = sample(1.1, 0.5, 0, 0, 0);
  in.has_velocity = true;
  in.velocity = Eigen::Vector3d(4.9, 0, 0);
  EXPECT_EQ(f.push(in).output.velocity, Eigen::Vector3d(4.9, 0, 0));
}

// A finite velocity or attitude no drone can have is out of range (review, session 33: a velocity
// of 1e300 m/s and a pitch of −40 rad were published).
TEST(OdometryFilter, RejectsVelocityAndAttitudeOutOfRange) {
  fact::OdometryFilter f;  // max_speed 10 m/s
  fact::OdometryInput in = sample(1.0, 0, 0, 0, 0);
  in.has_velocity = true;
  in.velocity = Eigen::Vector3d(1e300, 0, 0);
  fact::FilterResult r = f.push(in);
  EXPECT_EQ(r.rejection, fact::Rejection::out_of_range);
  EXPECT_NE(r.detail.find("is beyond twice max_speed 10 m/s"), std::string::npos) << r.detail;
  in.velocity = Eigen::Vector3d(0, 19.9, 0);  // within twice max_speed
  EXPECT_TRUE(f.push(in).accepted());
  in = sample(1.1, 0, 0, 0, 0);
  in.pitch = -40;
  r = f.push(in);
  EXPECT_EQ(r.rejection, fact::Rejection::out_of_range);
  EXPECT_EQ(r.detail, "pitch = -40 rad is outside [-pi/2, pi/2]");
  in.pitch = 0;
  in.roll = 50;
  EXPECT_EQ(f.push(in).detail, "roll = 50 rad is outside [-pi, pi]");
  in.roll = -3.1;
  in.pitch = 1.5;
  EXPECT_TRUE(f.push(in).accepted());
  EXPECT_EQ(f.count(fact::Rejection::out_of_range), 3);
}

TEST(OdometryFilter, PoseLinesThroughTheFilter) {
  fact::OdometryFilter f;
  fact::FilterResult r = f.push(pose(100.0, 1, 2, 3, 3.0, 0.1, -0.2));
  ASSERT_TRUE(r.accepted()) << r.detail;
  EXPECT_EQ(r.output.utime, 100000000);
  EXPECT_NEAR(r.output.yaw, 3.0, 1e-12);
  EXPECT_NEAR(r.output.pitch, 0.1, 1e-12);
  EXPECT_NEAR(r.output.roll, -0.2, 1e-12);
  r = f.push(pose(100.1, 1.1, 2, 3, -3.0, 0.1, -0.2));  // across +π: 3.0 → 2π − 3.0
  ASSERT_TRUE(r.accepted()) << r.detail;
  EXPECT_NEAR(r.output.yaw, 2 * kPi - 3.0, 1e-12);
  EXPECT_NEAR(r.output.velocity.x(), 1.0, 1e-9);
  // A NaN in the quaternion is non_finite (counted as rejected_nan), not a bad attitude.
  fact::PoseLine p = pose(100.2, 1, 2, 3, 0);
  p.qz = kNaN;
  r = f.push(p);
  EXPECT_EQ(r.rejection, fact::Rejection::non_finite);
  EXPECT_EQ(r.detail, "qz is nan");
  p = pose(100.2, 1, 2, 3, 0);
  p.time = kInf;
  EXPECT_EQ(f.push(p).detail, "time is inf");
  p = pose(100.2, 1, 2, 3, 0);
  p.qw = 3;
  r = f.push(p);
  EXPECT_EQ(r.rejection, fact::Rejection::bad_attitude);
  EXPECT_EQ(fact::counter_name(r.rejection), std::string("rejected_attitude"));
  EXPECT_EQ(f.count(fact::Rejection::non_finite), 2);
  EXPECT_EQ(f.count(fact::Rejection::bad_attitude), 1);
}

TEST(OdometryFilter, TextLines) {
  fact::OdometryFilter f;
  fact::FilterResult r = f.push_text("# header");
  EXPECT_TRUE(r.empty);
  EXPECT_FALSE(r.accepted());
  r = f.push_text("5 0 0 1 0 0 0 1");
  ASSERT_TRUE(r.accepted()) << r.detail;
  EXPECT_EQ(r.output.utime, 5000000);
  r = f.push_text("5.1 0 0");
  EXPECT_EQ(r.rejection, fact::Rejection::malformed);
  EXPECT_EQ(fact::counter_name(r.rejection), std::string("rejected_malformed"));
  EXPECT_EQ(f.push_text("5.1 nan 0 1 0 0 0 1").rejection, fact::Rejection::non_finite);
  EXPECT_EQ(f.push_text("4.9 0 0 1 0 0 0 1").rejection, fact::Rejection::out_of_order);
  EXPECT_EQ(f.count(fact::Rejection::malformed), 1);
  EXPECT_EQ(f.count(fact::Rejection::none), 1);
}

TEST(LogLimiter, OneLinePerKeyPerPeriod) {
  fact::LogLimiter limit(1000000);
  int64_t held = -1;
  EXPECT_TRUE(limit.allow("rejected_nan", 0, &held));
  EXPECT_EQ(held, 0);
  for (int k = 1; k <= 100; ++k) EXPECT_FALSE(limit.allow("rejected_nan", k * 1000));
  EXPECT_TRUE(limit.allow("rejected_jump", 5000));  // other keys are independent
  EXPECT_FALSE(limit.allow("rejected_nan", 999999));
  EXPECT_TRUE(limit.allow("rejected_nan", 1000000, &held));
  EXPECT_EQ(held, 101);
  EXPECT_FALSE(limit.allow("rejected_nan", 1500000));
  EXPECT_TRUE(limit.allow("rejected_nan", 2000000, &held));
  EXPECT_EQ(held, 1);
  EXPECT_TRUE(limit.allow("rejected_nan", 1000, &held));  // the clock stepped back: not muted forever
}

}  // namespace
