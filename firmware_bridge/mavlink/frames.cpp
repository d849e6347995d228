// FLU / ENU-like f_i <-> NED / FRD conversions (conventions in fact/mavlink_frames.h).
#include "fact/mavlink_frames.h"

#include <cmath>

namespace fact::mavlink {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

Vec3 fi_to_ned(const Vec3& v) { return {v.y, v.x, -v.z}; }
Vec3 ned_to_fi(const Vec3& v) { return {v.y, v.x, -v.z}; }
Vec3 flu_to_frd(const Vec3& v) { return {v.x, -v.y, -v.z}; }
Vec3 frd_to_flu(const Vec3& v) { return {v.x, -v.y, -v.z}; }

double wrap_pi(double a) {
  if (!std::isfinite(a)) return a;
  double r = std::remainder(a, 2 * kPi);  // [-pi, pi]
  if (r <= -kPi) r += 2 * kPi;
  return r;
}

double yaw_fi_to_ned(double yaw) { return wrap_pi(kPi / 2 - yaw); }
double yaw_ned_to_fi(double yaw) { return wrap_pi(kPi / 2 - yaw); }
double yaw_rate_fi_to_ned(double yaw_rate) { return -yaw_rate; }
double yaw_rate_ned_to_fi(double yaw_rate) { return -yaw_rate; }

Euler attitude_fi_to_ned(const Euler& e) { return {e.roll, -e.pitch, yaw_fi_to_ned(e.yaw)}; }
Euler attitude_ned_to_fi(const Euler& e) { return {e.roll, -e.pitch, yaw_ned_to_fi(e.yaw)}; }

Quat quat_from_euler(const Euler& e) {
  const double cr = std::cos(e.roll / 2), sr = std::sin(e.roll / 2);
  const double cp = std::cos(e.pitch / 2), sp = std::sin(e.pitch / 2);
  const double cy = std::cos(e.yaw / 2), sy = std::sin(e.yaw / 2);
  return {cy * cp * cr + sy * sp * sr, cy * cp * sr - sy * sp * cr, cy * sp * cr + sy * cp * sr,
          sy * cp * cr - cy * sp * sr};
}

Euler euler_from_quat(const Quat& q) {
  Euler e;
  e.roll = std::atan2(2 * (q.w * q.x + q.y * q.z), 1 - 2 * (q.x * q.x + q.y * q.y));
  const double s = 2 * (q.w * q.y - q.z * q.x);
  e.pitch = std::asin(s > 1 ? 1 : (s < -1 ? -1 : s));
  e.yaw = std::atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z));
  return e;
}

Quat multiply(const Quat& a, const Quat& b) {
  return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
          a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

Quat conjugate(const Quat& q) { return {q.w, -q.x, -q.y, -q.z}; }

Vec3 rotate(const Quat& q, const Vec3& v) {
  const Quat p = multiply(multiply(q, Quat{0, v.x, v.y, v.z}), conjugate(q));
  return {p.x, p.y, p.z};
}

Quat attitude_quat_ned_frd(const Euler& e_fi) {
  const double h = std::sqrt(0.5);
  const Quat ned_enu{0, h, h, 0};  // pi about (1, 1, 0)/sqrt(2): swaps x and y, flips z
  const Quat flu_frd{0, 1, 0, 0};  // pi about x: flips y and z
  Quat q = multiply(multiply(ned_enu, quat_from_euler(e_fi)), flu_frd);
  if (q.w < 0) q = {-q.w, -q.x, -q.y, -q.z};
  return q;
}

}  // namespace fact::mavlink
