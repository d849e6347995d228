// VIO odometry normalisation: raw samples from any source (the simulator's messages, a TUM
// trajectory file, a UDP line stream) in; one checked, continuous odometry stream in the drone's
// odometry frame f_i out. Plain functions over plain data; no LCM, no I/O (fact-vio-relay is the
// shell around it).
//
// Frames and units (see ../shared/docs/design.md): f_i is gravity-aligned FLU (x forward, y left,
// z up) with an arbitrary yaw; metres, radians, microseconds.
//
// The pose line (TUM trajectory format, also one UDP datagram):
//     timestamp tx ty tz qx qy qz qw
// timestamp in seconds (any epoch), position in metres in f_i, and the unit quaternion (Hamilton
// convention, x y z w order) of the body's attitude as a world-from-body rotation: it maps body
// (FLU) vectors into f_i. Fields are separated by spaces or tabs; blank lines and lines starting
// with '#' carry no sample. Yaw, pitch and roll are the Z-Y-X (intrinsic) Euler angles of that
// rotation, R = Rz(yaw)·Ry(pitch)·Rx(roll): yaw = atan2 of the rotated body x axis in the
// horizontal plane, so it is the heading even when the drone is tilted.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>
#include <string>

namespace fact {

// Wraps an angle into (−π, π].
double wrap_angle(double a);

// Yaw, pitch and roll of a world-from-body quaternion (see above), in radians: yaw in (−π, π],
// pitch in [−π/2, π/2], roll in (−π, π]. Returns "" or why the quaternion cannot be used: not
// finite, norm not within 1 ± 0.01 (it is normalised otherwise), or the body x axis within
// 0.001 rad of vertical (the heading is undefined).
struct Attitude {
  double yaw = 0, pitch = 0, roll = 0;
};
std::string attitude_from_quaternion(double qx, double qy, double qz, double qw, Attitude* out);

// One parsed pose line. Numbers are taken as written, including nan and inf: those are the
// filter's to reject (and count), not the parser's.
struct PoseLine {
  double time = 0;                                   // s
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // m, in f_i
  double qx = 0, qy = 0, qz = 0, qw = 1;             // world-from-body, Hamilton
};
enum class PoseLineKind { sample, empty, malformed };  // empty: blank line or '#' comment
// Parses one line (a trailing "\n" or "\r\n" is allowed). On malformed, *error says why, e.g.
// "expected 8 numbers, got 7" or "field 3 (tz) is not a number: \"1.2.3\"".
PoseLineKind parse_pose_line(const std::string& line, PoseLine* out, std::string* error);

// Why a sample was not published. Each has a counter name for the app's status message.
enum class Rejection {
  none,
  non_finite,    // NaN or inf in a field                        "rejected_nan"
  bad_time,      // finite, but not representable as int64 µs    "rejected_time"
  out_of_order,  // time not after the last accepted sample's    "rejected_out_of_order"
  jump,          // faster than max_speed or max_yaw_rate        "rejected_jump"
  bad_attitude,  // unusable quaternion (see attitude_from_…)    "rejected_attitude"
  malformed,     // a pose line that does not parse              "rejected_malformed"
  out_of_range,  // |position| beyond max_position, |velocity|    "rejected_range"
                 // beyond 2·max_speed, pitch outside [−π/2, π/2] or roll outside [−π, π]
};
constexpr int kNumRejections = 8;
const char* counter_name(Rejection r);  // the names above; "published" for none

struct OdometryFilterOptions {
  double max_speed = 10;     // m/s: a position change faster than this is a jump
  double max_yaw_rate = 6;   // rad/s: a yaw change faster than this is a jump
  double max_position = 1e4;  // m: a position component beyond ± this is out_of_range (the first sample's too)
  double max_gap = 10;       // s: a sample this long after the last accepted one is a jump (a far-future time)
  int restart_after = 20;    // a consistent run of this many rejected samples restarts the stream (see below)
};

// A raw sample.
struct OdometryInput {
  double utime = 0;  // µs; a double so that a NaN from a text source reaches the filter's checks
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // m, in f_i
  double yaw = 0;    // rad, wrapped or not (only its change between samples matters)
  double roll = 0;   // rad
  double pitch = 0;  // rad
  bool has_velocity = false;                           // the source measured it (the simulator)
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  // m/s, in f_i; used only when has_velocity
};

// A published sample: the content of fact::odometry_t.
struct OdometryOutput {
  int64_t utime = 0;  // µs, strictly increasing
  int64_t seq = 0;    // 0, 1, 2, … per published sample
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // m, in f_i
  // m/s, in f_i: the source's when it has one, otherwise the backward difference to the previous
  // published sample (zero for the first).
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  double yaw = 0;    // rad, unwrapped: continuous across ±π, starting at the first sample's yaw
  double roll = 0;   // rad
  double pitch = 0;  // rad
};

struct FilterResult {
  Rejection rejection = Rejection::none;
  bool empty = false;  // a blank or comment line: no sample, nothing published or counted
  std::string detail;  // why, with the values, e.g. "speed 52.1 m/s > max 10 m/s over 0.1 s"
  OdometryOutput output;  // valid when accepted()
  bool restarted = false;  // accepted as a new start after restart_after rejections in a row
  bool accepted() const { return rejection == Rejection::none && !empty; }
};

// The normaliser of one drone's stream. Every check compares against the last *accepted* sample,
// so a single outlier never poisons the stream.
//   - any non-finite field → non_finite; utime beyond ±9.2e18 µs → bad_time;
//   - a position component beyond ±max_position → out_of_range (the first sample too);
//   - utime (rounded to whole µs) ≤ the last accepted → out_of_order (duplicates included);
//   - Δt > max_gap, |Δposition| / Δt > max_speed, or |wrap(Δyaw)| / Δt > max_yaw_rate → jump;
//   - otherwise published: yaw unwrapped, seq + 1, velocity as above.
// When restart_after samples in a row are rejected as out_of_order or jump but each is a
// consistent continuation of the one before (later, within max_gap, max_speed and max_yaw_rate of
// it), the last of them restarts the stream: it is published as a first sample (seq 0, its own
// yaw; restarted), so that a VIO whose clock or frame was reset cannot block the stream for good
// (review, session 30: it did). A frozen VIO repeating one sample, or scattered outliers, never
// restart it.
class OdometryFilter {
 public:
  explicit OdometryFilter(OdometryFilterOptions options = {});

  FilterResult push(const OdometryInput& in);
  // A pose line: non-finite numbers → non_finite, then the quaternion → bad_attitude, then push.
  // time_offset_us is added to the line's time (µs), e.g. to restamp a replay onto the wall clock.
  FilterResult push(const PoseLine& line, double time_offset_us = 0);
  // A pose line as text (a TUM file's line, a UDP datagram): parse_pose_line, then push; a line
  // that does not parse → malformed, a blank or comment line → empty.
  FilterResult push_text(const std::string& text);

  int64_t count(Rejection r) const { return counts_[static_cast<int>(r)]; }  // none = published
  const OdometryFilterOptions& options() const { return options_; }
  bool has_last() const { return has_last_; }
  const OdometryOutput& last() const { return last_; }  // the last published sample

 private:
  FilterResult reject(Rejection r, std::string detail);
  struct Anchor {  // a sample's time (µs), position (m, f_i) and yaw (rad)
    int64_t utime = 0;
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
    double yaw = 0;
  };
  // Why a sample at `utime` (after from.utime) is a jump from `from`, or "".
  std::string jump_between(const Anchor& from, const OdometryInput& in, int64_t utime) const;

  OdometryFilterOptions options_;
  std::array<int64_t, kNumRejections> counts_{};
  bool has_last_ = false;
  OdometryOutput last_;
  int consecutive_ = 0;  // the run of rejected samples, each consistent with the one before
  bool has_candidate_ = false;
  Anchor candidate_;     // the last sample of that run
};

// The raw sample of a pose line (time s → µs, attitude from the quaternion, no velocity). Returns
// the attitude_from_quaternion error, or "".
std::string input_from_pose_line(const PoseLine& line, OdometryInput* out);

// At most one log line per key per period: a flood of bad samples cannot flood the log.
class LogLimiter {
 public:
  explicit LogLimiter(int64_t period_us = 1000000) : period_us_(period_us) {}
  // True when a line for `key` may be written at now_us (the first ever, or ≥ period after the
  // last one allowed); *suppressed is then the number of lines held back since that last one.
  bool allow(const std::string& key, int64_t now_us, int64_t* suppressed = nullptr);

 private:
  struct Entry {
    int64_t last = 0;
    int64_t held = 0;
  };
  int64_t period_us_;
  std::map<std::string, Entry> entries_;
};

}  // namespace fact
