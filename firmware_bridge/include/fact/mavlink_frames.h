// The frame conventions between fact and MAVLink / PX4 — the only place they are converted.
//
//   fact's f_i ("FLU" world): the drone's odometry frame, gravity-aligned, z up. It is taken as
//     ENU-like: x -> east, y -> north, z -> up (as MAVROS does for its "local" frame).
//   MAVLink local NED: x north, y east, z down.
//     position / velocity / acceleration:  NED = (y, x, -z) of f_i;  f_i = (y, x, -z) of NED.
//   Yaw: f_i yaw is counter-clockwise from +x (east) seen from above; NED yaw is clockwise from
//     north.  yaw_ned = pi/2 - yaw_fi (wrapped to (-pi, pi]); yaw rates change sign.
//   Body frames: fact's body is FLU (forward, left, up); PX4's is FRD (forward, right, down).
//     FRD = (x, -y, -z) of FLU, and back the same way.
//   Attitude: fact gives ZYX Euler angles (roll, pitch, yaw) of body FLU in f_i. The quaternion
//     PX4 wants rotates body FRD into local NED: q_ned_frd = q_ned_enu * q_enu_flu * q_flu_frd,
//     which as Euler angles is (roll, -pitch, pi/2 - yaw).
#pragma once

namespace fact::mavlink {

struct Vec3 {
  double x = 0, y = 0, z = 0;
};

// Unit quaternion, Hamilton convention (w, x, y, z), rotating vectors of the child frame into the
// parent frame: v_parent = q * v_child * conj(q).
struct Quat {
  double w = 1, x = 0, y = 0, z = 0;
};

struct Euler {
  double roll = 0, pitch = 0, yaw = 0;  // rad, ZYX (yaw about z, then pitch about y, then roll about x)
};

// World vectors (position m, velocity m/s, acceleration m/s²): f_i (ENU-like) <-> local NED.
Vec3 fi_to_ned(const Vec3& v);
Vec3 ned_to_fi(const Vec3& v);
// Body vectors: FLU <-> FRD.
Vec3 flu_to_frd(const Vec3& v);
Vec3 frd_to_flu(const Vec3& v);
// Heading (rad): f_i yaw <-> NED yaw, each wrapped to (-pi, pi]. Rates (rad/s) change sign.
double yaw_fi_to_ned(double yaw);
double yaw_ned_to_fi(double yaw);
double yaw_rate_fi_to_ned(double yaw_rate);
double yaw_rate_ned_to_fi(double yaw_rate);
// Attitude as Euler angles: body FLU in f_i <-> body FRD in NED.
Euler attitude_fi_to_ned(const Euler& e);
Euler attitude_ned_to_fi(const Euler& e);

// Angle wrapped to (-pi, pi].
double wrap_pi(double a);

// Quaternion helpers.
Quat quat_from_euler(const Euler& e);  // ZYX
Euler euler_from_quat(const Quat& q);  // ZYX; pitch in [-pi/2, pi/2]
Quat multiply(const Quat& a, const Quat& b);
Quat conjugate(const Quat& q);
Vec3 rotate(const Quat& q, const Vec3& v);  // q * v * conj(q)
// The rotation body FRD -> local NED for a body FLU attitude e in f_i, built as the product
// q_ned_enu * q_enu_flu(e) * q_flu_frd (not through attitude_fi_to_ned), with w >= 0.
Quat attitude_quat_ned_frd(const Euler& e_fi);

}  // namespace fact::mavlink
