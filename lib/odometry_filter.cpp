// VIO odometry normalisation (see include/fact/odometry_filter.h).
#include "fact/odometry_filter.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <utility>
#include <vector>

namespace fact {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMaxUtime = 9.2e18;  // µs; llround of anything within this fits int64_t
constexpr double kMaxQuaternionNormError = 0.01;
constexpr double kMinHorizontalHeading = 1e-3;  // sin of 0.001 rad, to the x axis' horizontal part

const char* const kFieldNames[8] = {"time", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};

std::string number(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

}  // namespace

double wrap_angle(double a) {
  if (!std::isfinite(a)) return a;
  double r = std::remainder(a, 2 * kPi);  // [−π, π], exact
  if (r <= -kPi) r += 2 * kPi;
  return r;
}

std::string attitude_from_quaternion(double qx, double qy, double qz, double qw, Attitude* out) {
  if (!std::isfinite(qx) || !std::isfinite(qy) || !std::isfinite(qz) || !std::isfinite(qw))
    return "quaternion is not finite";
  const double norm = std::sqrt(qx * qx + qy * qy + qz * qz + qw * qw);
  if (!(std::abs(norm - 1) <= kMaxQuaternionNormError))
    return "quaternion norm " + number(norm) + " is not 1 (within " + number(kMaxQuaternionNormError) + ")";
  const double x = qx / norm, y = qy / norm, z = qz / norm, w = qw / norm;
  // The first column of R (the body x axis in f_i), and the last row's needed entries.
  const double r00 = 1 - 2 * (y * y + z * z);
  const double r10 = 2 * (x * y + w * z);
  const double r20 = 2 * (x * z - w * y);
  const double r21 = 2 * (y * z + w * x);
  const double r22 = 1 - 2 * (x * x + y * y);
  if (std::hypot(r00, r10) < kMinHorizontalHeading)
    return "body x axis is vertical (pitch " + number(std::asin(std::clamp(-r20, -1.0, 1.0))) +
           " rad): heading undefined";
  out->yaw = wrap_angle(std::atan2(r10, r00));
  out->pitch = std::asin(std::clamp(-r20, -1.0, 1.0));
  out->roll = wrap_angle(std::atan2(r21, r22));
  return "";
}

PoseLineKind parse_pose_line(const std::string& line, PoseLine* out, std::string* error) {
  std::string text = line;
  if (!text.empty() && text.back() == '\n') text.pop_back();
  if (!text.empty() && text.back() == '\r') text.pop_back();
  std::vector<std::string> tokens;
  std::size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
    if (i >= text.size()) break;
    std::size_t j = i;
    while (j < text.size() && text[j] != ' ' && text[j] != '\t') ++j;
    tokens.push_back(text.substr(i, j - i));
    i = j;
  }
  if (tokens.empty() || tokens[0][0] == '#') return PoseLineKind::empty;
  if (tokens.size() != 8) {
    if (error) *error = "expected 8 numbers (t tx ty tz qx qy qz qw), got " + std::to_string(tokens.size());
    return PoseLineKind::malformed;
  }
  double v[8];
  for (int k = 0; k < 8; ++k) {
    const char* begin = tokens[k].c_str();
    char* end = nullptr;
    errno = 0;
    v[k] = std::strtod(begin, &end);  // accepts nan and inf: the filter rejects them
    if (end != begin + tokens[k].size() || tokens[k].empty()) {  // the whole token, NUL bytes included
      std::string shown = tokens[k].size() > 40 ? tokens[k].substr(0, 40) + "..." : tokens[k];
      for (char& c : shown)
        if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) == 0x7f) c = '?';
      if (error) *error = "field " + std::to_string(k + 1) + " (" + kFieldNames[k] + ") is not a number: \"" + shown + "\"";
      return PoseLineKind::malformed;
    }
  }
  out->time = v[0];
  out->position = Eigen::Vector3d(v[1], v[2], v[3]);
  out->qx = v[4];
  out->qy = v[5];
  out->qz = v[6];
  out->qw = v[7];
  return PoseLineKind::sample;
}

const char* counter_name(Rejection r) {
  switch (r) {
    case Rejection::none: return "published";
    case Rejection::non_finite: return "rejected_nan";
    case Rejection::bad_time: return "rejected_time";
    case Rejection::out_of_order: return "rejected_out_of_order";
    case Rejection::jump: return "rejected_jump";
    case Rejection::bad_attitude: return "rejected_attitude";
    case Rejection::malformed: return "rejected_malformed";
    case Rejection::out_of_range: return "rejected_range";
  }
  return "rejected_unknown";
}

std::string input_from_pose_line(const PoseLine& line, OdometryInput* out) {
  Attitude a;
  std::string err = attitude_from_quaternion(line.qx, line.qy, line.qz, line.qw, &a);
  if (!err.empty()) return err;
  out->utime = line.time * 1e6;
  out->position = line.position;
  out->yaw = a.yaw;
  out->roll = a.roll;
  out->pitch = a.pitch;
  out->has_velocity = false;
  out->velocity.setZero();
  return "";
}

OdometryFilter::OdometryFilter(OdometryFilterOptions options) : options_(options) {}

FilterResult OdometryFilter::reject(Rejection r, std::string detail) {
  ++counts_[static_cast<int>(r)];
  FilterResult result;
  result.rejection = r;
  result.detail = std::move(detail);
  return result;
}

FilterResult OdometryFilter::push(const OdometryInput& in) {
  // Non-finite fields, named.
  std::string bad;
  auto check = [&bad](const char* name, double v) {
    if (!std::isfinite(v)) bad += (bad.empty() ? "" : ", ") + std::string(name) + " is " + number(v);
  };
  check("utime", in.utime);
  check("position[0]", in.position.x());
  check("position[1]", in.position.y());
  check("position[2]", in.position.z());
  check("yaw", in.yaw);
  check("roll", in.roll);
  check("pitch", in.pitch);
  if (in.has_velocity) {
    check("velocity[0]", in.velocity.x());
    check("velocity[1]", in.velocity.y());
    check("velocity[2]", in.velocity.z());
  }
  if (!bad.empty()) return reject(Rejection::non_finite, bad);
  if (std::abs(in.utime) > kMaxUtime)
    return reject(Rejection::bad_time, "utime " + number(in.utime) + " us is beyond the int64 range");

  for (int i = 0; i < 3; ++i)
    if (std::abs(in.position[i]) > options_.max_position)
      return reject(Rejection::out_of_range, "position[" + std::to_string(i) + "] = " + number(in.position[i]) +
                                                 " m is beyond ±" + number(options_.max_position) + " m");
  // A reported velocity beyond twice max_speed, or an attitude outside its range (pitch in
  // [−π/2, π/2], roll in [−π, π]), is no drone's (review, session 33: 1e300 m/s and a pitch of
  // −40 rad were published; the planner dropped such samples whole, the detector used them).
  if (in.has_velocity && in.velocity.norm() > 2 * options_.max_speed)
    return reject(Rejection::out_of_range, "velocity |(" + number(in.velocity.x()) + ", " + number(in.velocity.y()) +
                                               ", " + number(in.velocity.z()) + ")| m/s is beyond twice max_speed " +
                                               number(options_.max_speed) + " m/s");
  if (std::abs(in.pitch) > kPi / 2 + 1e-9)
    return reject(Rejection::out_of_range, "pitch = " + number(in.pitch) + " rad is outside [-pi/2, pi/2]");
  if (std::abs(in.roll) > kPi + 1e-9)
    return reject(Rejection::out_of_range, "roll = " + number(in.roll) + " rad is outside [-pi, pi]");

  OdometryOutput out;
  out.utime = std::llround(in.utime);
  out.position = in.position;
  out.roll = in.roll;
  out.pitch = in.pitch;
  bool restarted = false;
  if (has_last_) {
    Rejection kind = Rejection::none;
    std::string why;
    if (out.utime <= last_.utime) {
      kind = Rejection::out_of_order;
      why = "utime " + std::to_string(out.utime) + " us is not after the last accepted " + std::to_string(last_.utime) + " us";
    } else {
      why = jump_between(Anchor{last_.utime, last_.position, last_.yaw}, in, out.utime);
      if (!why.empty()) kind = Rejection::jump;
    }
    if (kind != Rejection::none) {
      // A run of rejected samples counts toward a restart only while each is a consistent
      // continuation of the one before (a stream of its own): a frozen VIO repeating one sample, or
      // scattered outliers, never restart the stream (review, session 30).
      const Anchor here{out.utime, in.position, in.yaw};
      const bool continues = has_candidate_ && out.utime > candidate_.utime && jump_between(candidate_, in, out.utime).empty();
      consecutive_ = continues ? consecutive_ + 1 : 1;
      candidate_ = here;
      has_candidate_ = true;
      if (consecutive_ < options_.restart_after) return reject(kind, why);
      restarted = true;
    }
  }
  if (!has_last_ || restarted) {
    out.yaw = in.yaw;
    out.velocity = in.has_velocity ? in.velocity : Eigen::Vector3d::Zero();
    out.seq = 0;
  } else {
    const double dt = static_cast<double>(out.utime - last_.utime) / 1e6;  // s, > 0
    out.yaw = last_.yaw + wrap_angle(in.yaw - last_.yaw);
    out.velocity = in.has_velocity ? in.velocity : Eigen::Vector3d((in.position - last_.position) / dt);
    out.seq = last_.seq + 1;
  }
  consecutive_ = 0;
  has_candidate_ = false;
  ++counts_[static_cast<int>(Rejection::none)];
  has_last_ = true;
  last_ = out;
  FilterResult result;
  result.output = out;
  result.restarted = restarted;
  if (restarted)
    result.detail = "stream restarted: " + std::to_string(options_.restart_after) +
                    " samples in a row, each consistent with the one before, were out of order or jumps from the last "
                    "accepted";
  return result;
}

std::string OdometryFilter::jump_between(const Anchor& from, const OdometryInput& in, int64_t utime) const {
  const double dt = static_cast<double>(utime - from.utime) / 1e6;  // s, > 0
  if (dt > options_.max_gap)
    return "time gap of " + number(dt) + " s after the last accepted sample (max " + number(options_.max_gap) + " s)";
  const Eigen::Vector3d step = in.position - from.position;
  const double speed = step.norm() / dt;
  if (!(speed <= options_.max_speed))
    return "position jump of " + number(step.norm()) + " m in " + number(dt) + " s (" + number(speed) + " m/s > max " +
           number(options_.max_speed) + " m/s)";
  const double dyaw = wrap_angle(in.yaw - from.yaw);
  const double yaw_rate = std::abs(dyaw) / dt;
  if (!(yaw_rate <= options_.max_yaw_rate))
    return "yaw jump of " + number(dyaw) + " rad in " + number(dt) + " s (" + number(yaw_rate) + " rad/s > max " +
           number(options_.max_yaw_rate) + " rad/s)";
  return "";
}

FilterResult OdometryFilter::push(const PoseLine& line, double time_offset_us) {
  std::string bad;
  const double v[8] = {line.time, line.position.x(), line.position.y(), line.position.z(),
                       line.qx,   line.qy,           line.qz,           line.qw};
  for (int k = 0; k < 8; ++k)
    if (!std::isfinite(v[k])) bad += (bad.empty() ? "" : ", ") + std::string(kFieldNames[k]) + " is " + number(v[k]);
  if (!bad.empty()) return reject(Rejection::non_finite, bad);
  OdometryInput in;
  std::string err = input_from_pose_line(line, &in);
  if (!err.empty()) return reject(Rejection::bad_attitude, err);
  in.utime += time_offset_us;
  return push(in);
}

FilterResult OdometryFilter::push_text(const std::string& text) {
  PoseLine line;
  std::string error;
  switch (parse_pose_line(text, &line, &error)) {
    case PoseLineKind::empty: {
      FilterResult r;
      r.empty = true;
      return r;
    }
    case PoseLineKind::malformed: return reject(Rejection::malformed, error);
    case PoseLineKind::sample: break;
  }
  return push(line);
}

bool LogLimiter::allow(const std::string& key, int64_t now_us, int64_t* suppressed) {
  auto it = entries_.find(key);
  if (it == entries_.end()) {
    entries_.emplace(key, Entry{now_us, 0});
    if (suppressed) *suppressed = 0;
    return true;
  }
  Entry& e = it->second;
  if (now_us - e.last >= period_us_ || now_us < e.last) {  // a clock step back does not mute a key forever
    if (suppressed) *suppressed = e.held;
    e.last = now_us;
    e.held = 0;
    return true;
  }
  ++e.held;
  return false;
}

}  // namespace fact
