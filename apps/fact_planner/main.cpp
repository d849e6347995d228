// fact-planner: the spin / observe / move cycle of one drone as an LCM app, a thin shell around
// lib/planner (fact/planner.h, fact/local_map.h, fact/trajectory.h). Inputs: own odometry
// (FACT_ODOMETRY_<id>), own detections (FACT_DETECTIONS_<id>), own frames for the local obstacle
// map (FACT_FRAMES_<id>), the swarm's complete rounds (FACT_SWARM_ROUNDS_<id>, fact-gossip) and the
// solver's result (FACT_RESULT_<id>). Output: fact::setpoint_t on FACT_SETPOINT_<id> at
// --setpoint-rate, sampled from the current trajectory; heartbeat, state and counters on FACT_STATUS.
//
// State machine (README.md): wait_odometry → takeoff → spin → wait → (done | move → spin → wait …).
// Hover (hold the last commanded position at rest) on stale odometry or an unusable plan.
//
// Exit codes: 0 stopped by SIGINT/SIGTERM, or --exit-when-done after the certified hold has been
// published for a second; 3 --exit-when-done and --max-rounds reached without a certified result;
// 1 LCM failed; 2 bad flags.
#include "common/app.h"
#include "common/convert.h"
#include "common/flags.h"
#include "fact/detections_t.hpp"
#include "fact/frame_t.hpp"
#include "fact/local_map.h"
#include "fact/odometry_t.hpp"
#include "fact/planner.h"
#include "fact/setpoint_t.hpp"
#include "fact/swarm_result_t.hpp"
#include "fact/swarm_rounds_t.hpp"
#include "fact/trajectory.h"

#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

namespace {

constexpr const char* kApp = "fact-planner";
using Eigen::Vector3d;
using fact::app::FlagError;

struct Options {
  fact::app::CommonFlags common;
  std::string odometry_channel, detections_channel, frames_channel, rounds_channel, result_channel,
      setpoint_channel;  // "" = FACT_<NAME>_<id>
  std::string frames_url;            // "" = frames come on --lcm-url
  uint64_t seed = 1;                 // planner random generator (takeoff height, random moves)
  double setpoint_rate = 30;         // Hz, >= 20
  double odometry_timeout = 0.5;     // s, older odometry (by arrival) → hover
  double wait_timeout = 20;          // s in the wait state before moving without a result
  double frame_wait = 0.2;           // s a frame waits for its detections before it is mapped without removals
  int max_rounds = 20;               // spins before giving up on a certified result (hold)
  bool exit_when_done = false;
  std::vector<double> camera_offset = {0.10, 0.0, 0.0};  // m, optical centre in the body frame (FLU)
  std::vector<double> fence = {-50, 50, -50, 50};        // m, f_i: XMIN, XMAX, YMIN, YMAX (PlannerParams::fence)
  double camera_pitch = 0.0;         // rad, camera tilted down about the body y axis
  fact::PlannerParams planner;
  fact::LocalMapParams map;
};

void add_flags(CLI::App& app, Options& o) {
  fact::app::add_common_flags(app, &o.common, fact::app::DroneIdFlag::required);
  auto channel = [&](const char* flag, std::string& v, const char* what) {
    app.add_option(flag, v, what)->type_name("CHANNEL");
  };
  channel("--odometry-channel", o.odometry_channel, "Own odometry in (default FACT_ODOMETRY_<id>)");
  channel("--detections-channel", o.detections_channel, "Own detections in (default FACT_DETECTIONS_<id>)");
  channel("--frames-channel", o.frames_channel, "Own gray + depth frames in, for the map (default FACT_FRAMES_<id>)");
  app.add_option("--frames-url", o.frames_url, "LCM URL the frames come on, if not --lcm-url (as fact-detector's)")
      ->type_name("URL");
  channel("--rounds-channel", o.rounds_channel, "Complete rounds from fact-gossip (default FACT_SWARM_ROUNDS_<id>)");
  channel("--result-channel", o.result_channel, "Result from fact-solver (default FACT_RESULT_<id>)");
  channel("--setpoint-channel", o.setpoint_channel, "Setpoints out (default FACT_SETPOINT_<id>)");
  // A number flag; an integer one takes only a plain decimal integer (CLI11 read "010" as octal),
  // the seed one within [0, 2^64 − 1] (CLI11 wrapped "-1" to 2^64 − 1).
  auto num = [&](const char* flag, auto& v, const char* what) {
    CLI::Option* option = app.add_option(flag, v, what)->capture_default_str();
    using T = std::decay_t<decltype(v)>;
    if constexpr (std::is_same_v<T, std::uint64_t>) option->check(fact::app::uint64_text());
    else if constexpr (std::is_integral_v<T>) option->check(fact::app::decimal_integer());
  };
  num("--seed", o.seed, "Seed of the planner's generator (takeoff height, random moves)");
  num("--setpoint-rate", o.setpoint_rate, "Setpoints per second (Hz, >= 20)");
  num("--odometry-timeout", o.odometry_timeout, "Hover when the newest odometry arrived longer ago than this (s)");
  num("--wait-timeout", o.wait_timeout, "Wait this long for the swarm's rounds and result, then move without (s)");
  num("--frame-wait", o.frame_wait, "A frame waits this long for its detections, then is mapped without removals (s)");
  num("--max-rounds", o.max_rounds, "Spins before holding without a certified result (>= 1)");
  app.add_flag("--exit-when-done", o.exit_when_done,
               "Exit 0 once the certified hold has been published for 1 s (3 at --max-rounds without one)");
  app.add_option("--camera-offset", o.camera_offset, "Camera optical centre in the body frame x,y,z (m, FLU)")
      ->delimiter(',')->expected(3)->type_name("X,Y,Z");
  num("--camera-pitch", o.camera_pitch, "Camera tilted down about the body y axis (rad)");
  app.add_option("--fence", o.fence,
                 "Moves stay inside this box, drone_radius from its edges (m, f_i; within fact-fc-bridge's --geofence)")
      ->delimiter(',')->expected(4)->type_name("XMIN,XMAX,YMIN,YMAX")->capture_default_str();
  fact::PlannerParams& p = o.planner;
  num("--takeoff-min", p.takeoff_min, "Takeoff height drawn in [min, max] (m, f_i)");
  num("--takeoff-max", p.takeoff_max, "Takeoff height drawn in [min, max] (m, f_i)");
  num("--z-min", p.z_min, "Flight height window, lower end (m, f_i)");
  num("--z-max", p.z_max, "Flight height window, upper end (m, f_i)");
  num("--spin-rate", p.spin_rate, "Spin yaw rate limit (rad/s)");
  num("--yaw-accel", p.yaw_accel, "Spin yaw acceleration (rad/s^2)");
  num("--spin-overlap", p.spin_overlap, "Spin turns 2*pi + this (rad)");
  num("--min-separation", p.min_separation, "Minimum centre distance to every other drone (m)");
  num("--move-max", p.move_max, "Longest move (m)");
  num("--move-margin", p.move_margin, "Margin of the max-move rule (m)");
  num("--random-move-probability", p.random_move_probability, "Chance of a random direction (0..1)");
  num("--drone-radius", p.drone_radius, "Body bounding sphere (m)");
  num("--obstacle-margin", p.obstacle_margin, "Obstacles inflated by drone radius + this (m)");
  num("--move-settle", p.move_settle,
      "Spins start this long after the longest possible move (takeoff) would end, counted from the move decision (s)");
  num("--v-max", p.v_max, "Trajectory speed limit (m/s)");
  num("--a-max", p.a_max, "Trajectory acceleration limit (m/s^2)");
  num("--map-resolution", o.map.resolution, "Local map voxel edge (m)");
  num("--map-max-range", o.map.max_range, "Depths beyond this are not mapped (m)");
  num("--map-hit-threshold", o.map.hit_threshold, "Hits for a voxel to be occupied");
  app.footer(
      "State machine: wait_odometry -> takeoff -> spin -> wait -> done (certified: hold) | move -> spin -> ...\n"
      "A spin turns 2*pi + --spin-overlap so that fact-gossip (a round closes after a full 2*pi of unwrapped\n"
      "yaw) closes the round; its detections are the round's observed drones. Round r (0-based, at least the\n"
      "swarm's complete_rounds at the spin's start) waits for complete_rounds >= r + 1 and then a result with\n"
      "rounds_used >= r + 1, at most --wait-timeout s. Spins are synchronised: a drone spins only once the\n"
      "longest move any drone may fly (--move-max at --v-max, --a-max; the takeoff to --takeoff-max) has ended,\n"
      "plus --move-settle, counted from its move decision, so that no drone observes another in flight.\n"
      "Hover (last commanded position, at rest) on odometry older than --odometry-timeout or an unusable plan;\n"
      "the reason is in the status state.\n"
      "Setpoints (fact::setpoint_t, f_i, FLU): position m, velocity m/s, acceleration m/s^2, yaw rad, yaw_rate rad/s.\n"
      "Exit codes: 0 SIGINT/SIGTERM or --exit-when-done; 3 --exit-when-done at --max-rounds without a\n"
      "certified result; 1 LCM failed; 2 bad flags.");
}

void check(Options& o) {
  fact::app::check_common_flags(o.common, fact::app::DroneIdFlag::required);
  const int id = o.common.drone_id;
  auto def = [&](std::string& v, const char* base) { if (v.empty()) v = fact::app::channel(base, id); };
  def(o.odometry_channel, "FACT_ODOMETRY");
  def(o.detections_channel, "FACT_DETECTIONS");
  def(o.frames_channel, "FACT_FRAMES");
  def(o.rounds_channel, "FACT_SWARM_ROUNDS");
  def(o.result_channel, "FACT_RESULT");
  def(o.setpoint_channel, "FACT_SETPOINT");
  if (!(o.setpoint_rate >= 20 && o.setpoint_rate <= 1000))
    throw FlagError("--setpoint-rate: expected a number in [20, 1000] Hz, got " + std::to_string(o.setpoint_rate));
  // (a timeout that rounds to 0 µs hovers for ever, one beyond llround's range never waits: review,
  // session 30)
  fact::app::check_range("--odometry-timeout", o.odometry_timeout, 0.01, 60, "s");
  fact::app::check_range("--wait-timeout", o.wait_timeout, 0.01, 3600, "s");
  if (!(o.frame_wait >= 0 && o.frame_wait < 10))
    throw FlagError("--frame-wait: expected a number in [0, 10) s, got " + std::to_string(o.frame_wait));
  if (o.max_rounds < 1) throw FlagError("--max-rounds: expected >= 1, got " + std::to_string(o.max_rounds));
  for (double c : o.camera_offset)
    if (!std::isfinite(c)) throw FlagError("--camera-offset: expected finite numbers");
  if (!std::isfinite(o.camera_pitch)) throw FlagError("--camera-pitch: expected a finite number");
  for (int k = 0; k < 4; ++k) o.planner.fence[static_cast<std::size_t>(k)] = o.fence[static_cast<std::size_t>(k)];
  if (std::string e = fact::planner_params_error(o.planner); !e.empty()) throw FlagError("planner: " + e);
  // The map's grid (±12 m) grows with --map-max-range so that it holds a whole frame's reach on
  // each side of the drone (1.6 × max range covers the default camera's widest ray, 1.52 ×), plus 2 m.
  if (std::isfinite(o.map.max_range)) o.map.half_extent_xy = std::max(o.map.half_extent_xy, 1.6 * o.map.max_range + 2.0);
  // (said in the flags' terms here: the map's own message names only the voxel count)
  if (o.map.resolution > 0.01 && std::isfinite(o.map.max_range) && o.map.max_range > 0 &&
      fact::local_map_voxels(o.map) > fact::kMaxMapVoxels) {
    std::ostringstream e;
    e << "--map-max-range " << o.map.max_range << " m with --map-resolution " << o.map.resolution
      << " m needs a grid of ±" << o.map.half_extent_xy << " m, " << fact::local_map_voxels(o.map)
      << " voxels: more than " << fact::kMaxMapVoxels << " (a shorter range or a coarser resolution)";
    throw FlagError(e.str());
  }
  if (std::string e = fact::local_map_params_error(o.map); !e.empty()) throw FlagError("map: " + e);
}

// Odometry samples by time, interpolated linearly (yaw is unwrapped upstream).
struct Pose {
  int64_t utime = 0;
  Vector3d position = Vector3d::Zero();
  double yaw = 0, pitch = 0, roll = 0;
};

class PoseBuffer {
 public:
  void push(const Pose& p) {
    samples_.push_back(p);
    while (samples_.size() > 1000) samples_.pop_front();
  }
  bool empty() const { return samples_.empty(); }
  void clear() { samples_.clear(); }
  const Pose& newest() const { return samples_.back(); }
  // Interpolated at t; false when t is outside the buffer by more than `slack_us`.
  bool at(int64_t t, int64_t slack_us, Pose* out) const {
    if (samples_.empty() || t < samples_.front().utime - slack_us || t > samples_.back().utime + slack_us) return false;
    if (t <= samples_.front().utime) { *out = samples_.front(); return true; }
    if (t >= samples_.back().utime) { *out = samples_.back(); return true; }
    auto it = std::lower_bound(samples_.begin(), samples_.end(), t, [](const Pose& a, int64_t x) { return a.utime < x; });
    const Pose &b = *it, &a = *(it - 1);
    const double s = double(t - a.utime) / double(b.utime - a.utime);
    out->utime = t;
    out->position = a.position + s * (b.position - a.position);
    out->yaw = a.yaw + s * (b.yaw - a.yaw);
    out->pitch = a.pitch + s * (b.pitch - a.pitch);
    out->roll = a.roll + s * (b.roll - a.roll);
    return true;
  }

 private:
  std::deque<Pose> samples_;
};

// Odometry beyond what a drone of this swarm reports ("" when within): positions within 10 km
// (as the estimator's input), velocities within 100 m/s, angles within ±1e6 rad (yaw is unwrapped).
// A takeoff planned from z = 1e300 had an infinite duration and NaN setpoints, one from -1e7 m took
// 5.5 s to plan (review, session 30).
std::string odometry_out_of_range(const fact::odometry_t& m) {
  for (int i = 0; i < 3; ++i) {
    const std::string at = "[" + std::to_string(i) + "] = ";
    if (std::abs(m.position[i]) > 1e4) return "position" + at + std::to_string(m.position[i]) + " m is beyond ±1e4 m";
    if (std::abs(m.velocity[i]) > 100) return "velocity" + at + std::to_string(m.velocity[i]) + " m/s is beyond ±100 m/s";
  }
  for (const auto& [name, v] : {std::pair<const char*, double>{"yaw", m.yaw}, {"pitch", m.pitch}, {"roll", m.roll}})
    if (std::abs(v) > 1e6) return std::string(name) + " = " + std::to_string(v) + " rad is beyond ±1e6 rad";
  return "";
}

bool finite(const double* v, int n) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}

std::string fmt(const Vector3d& v) {
  std::ostringstream s;
  s.precision(3);
  s << std::fixed << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return s.str();
}

enum class Phase { wait_odometry, takeoff, spin, wait, move, done };
const char* name(Phase p) {
  switch (p) {
    case Phase::wait_odometry: return "wait_odometry";
    case Phase::takeoff: return "takeoff";
    case Phase::spin: return "spin";
    case Phase::wait: return "wait";
    case Phase::move: return "move";
    case Phase::done: return "done";
  }
  return "?";
}

class Planner {
 public:
  Planner(lcm::LCM& lcm, const Options& o)
      : lcm_(lcm), o_(o), log_(kApp, o.common.drone_id), status_(&lcm, o.common.status_channel, kApp, o.common.drone_id),
        map_(o.map) {
    status_.set_period_us(static_cast<int64_t>(std::llround(o.common.status_period * 1e6)));
    for (const char* c : {"odometry", "detections", "observations", "frames", "frames_mapped", "map_recentred", "frames_without_detections",
                          "swarm_rounds", "stale_rounds", "results", "setpoints", "rejected_setpoint", "rejected_nan", "rejected_range",
                          "wrong_drone_id", "odometry_restarts",
                          "out_of_order", "invalid_input", "undecodable", "no_odometry_at_time", "map_failed", "plans",
                          "hover", "wait_timeouts", "publish_failed"})
      status_.count(c, 0);
    rng_.state = o.seed;
    extrinsics_.R_body_cam =
        Eigen::AngleAxisd(o.camera_pitch, Vector3d::UnitY()).toRotationMatrix() * extrinsics_.R_body_cam;
    extrinsics_.t_body_cam = Vector3d(o.camera_offset[0], o.camera_offset[1], o.camera_offset[2]);
    set_state("wait_odometry: no odometry yet on " + o.odometry_channel);
  }

  // ---- inputs ----------------------------------------------------------------------------------
  void on_odometry(const lcm::ReceiveBuffer* rbuf, const std::string& ch) {
    fact::odometry_t m;
    if (!fact::app::decode(rbuf, ch, &m, &status_, log_)) return;
    if (!own(m.drone_id, "odometry", ch)) return;
    if (!finite(m.position, 3) || !finite(m.velocity, 3) || !std::isfinite(m.yaw) || !std::isfinite(m.roll) ||
        !std::isfinite(m.pitch))
      return reject("rejected_nan", "odometry seq " + std::to_string(m.seq) + " has a non-finite field");
    if (std::string why = odometry_out_of_range(m); !why.empty())
      return reject("rejected_range", "odometry seq " + std::to_string(m.seq) + ": " + why);
    // fact-vio-relay restarted its stream (seq 0) or was restarted, and its times may start over
    // (fact::app::odometry_restarted). The buffer starts again with it; otherwise every later
    // sample was out of order and the drone hovered on stale odometry for good (review, session
    // 30). (Not only seq 0: that one message may be lost; and seq 0 again with an earlier time when
    // the restart came right after the first sample.) One reordered datagram is not a restart.
    if (!poses_.empty() && (fact::app::odometry_restarted(last_seq_, poses_.newest().utime, m.seq, m.utime) ||
                            (m.seq == 0 && m.utime < poses_.newest().utime))) {
      status_.count("odometry_restarts");
      log_.event("odometry restarted (seq " + std::to_string(m.seq) + " after " + std::to_string(last_seq_) + ", utime " +
                 std::to_string(m.utime) + " us after " + std::to_string(poses_.newest().utime) +
                 " us): the pose buffer starts again");
      poses_.clear();
    }
    if (!poses_.empty() && m.utime <= poses_.newest().utime)
      return reject("out_of_order", "odometry utime " + std::to_string(m.utime) + " not after the previous one");
    status_.count("odometry");
    poses_.push(Pose{m.utime, Vector3d(m.position[0], m.position[1], m.position[2]), m.yaw, m.pitch, m.roll});
    last_seq_ = m.seq;
    odometry_arrival_ = fact::app::monotonic_us();
  }

  void on_detections(const lcm::ReceiveBuffer* rbuf, const std::string& ch) {
    fact::detections_t m;
    if (!fact::app::decode(rbuf, ch, &m, &status_, log_)) return;
    if (!own(m.drone_id, "detections", ch)) return;
    for (const fact::detection_t& d : m.detections)
      if (!finite(d.vector, 3) || !std::isfinite(d.box[0]) || !std::isfinite(d.box[1]) || !std::isfinite(d.box[2]) ||
          !std::isfinite(d.box[3]))
        return reject("rejected_nan", "detections of frame " + std::to_string(m.frame_seq) + " have a non-finite field");
    for (const fact::detection_t& d : m.detections)
      if (d.box[2] < 0 || d.box[3] < 0)
        return reject("invalid_input", "detections of frame " + std::to_string(m.frame_seq) + ": box size " +
                                           std::to_string(d.box[2]) + " × " + std::to_string(d.box[3]) + " px is negative");
    status_.count("detections");
    std::vector<fact::BoxDetection> boxes;
    for (const fact::detection_t& d : m.detections) boxes.push_back({d.box[0], d.box[1], d.box[2], d.box[3], d.confidence});
    boxes_[m.utime] = std::move(boxes);
    while (boxes_.size() > 64) boxes_.erase(boxes_.begin());
    if (phase_ != Phase::spin || m.detections.empty()) return;
    Pose pose;
    if (!poses_.at(m.utime, us(o_.odometry_timeout), &pose))
      return reject("no_odometry_at_time", "detections at " + std::to_string(m.utime) + ": no odometry near that time");
    for (const fact::detection_t& d : m.detections) {
      const Vector3d p = fact::observed_position(pose.position, pose.yaw, Vector3d(d.vector[0], d.vector[1], d.vector[2]));
      auto& [sum, n] = seen_[d.track_id];
      sum = (n == 0 ? Vector3d::Zero() : sum) + p;
      ++n;
      status_.count("observations");
    }
  }

  void on_frame(const lcm::ReceiveBuffer* rbuf, const std::string& ch) {
    auto m = std::make_shared<fact::frame_t>();
    if (!fact::app::decode(rbuf, ch, m.get(), &status_, log_)) return;
    if (!own(m->drone_id, "frame", ch)) return;
    const int64_t n = int64_t(m->width) * m->height;
    if (m->width <= 0 || m->height <= 0 || m->depth_size != n || m->gray_size != n)
      return reject("invalid_input", "frame seq " + std::to_string(m->seq) + ": sizes do not match width x height");
    status_.count("frames");
    frames_.push_back({m, fact::app::monotonic_us()});
    while (frames_.size() > 4) {  // never fall behind: the oldest is mapped with what is known
      map_frame(*frames_.front().frame);
      frames_.pop_front();
    }
  }

  void on_rounds(const lcm::ReceiveBuffer* rbuf, const std::string& ch) {
    fact::swarm_rounds_t m;
    if (!fact::app::decode(rbuf, ch, &m, &status_, log_)) return;
    if (!own(m.drone_id, "swarm_rounds", ch)) return;
    fact::Rounds rounds;
    if (std::string e = fact::app::rounds_from_message(m, &rounds); !e.empty())
      return reject("invalid_input", "swarm_rounds on " + ch + ": " + e);
    status_.count("swarm_rounds");
    if (m.complete_rounds < complete_rounds_) {  // older than what we have (a restarted fact-gossip?)
      status_.count("stale_rounds");
      fact::app::log_counted(log_, "stale_rounds", status_.value("stale_rounds"),
                             "swarm_rounds on " + ch + " with " + std::to_string(m.complete_rounds) +
                                 " complete round(s), fewer than the " + std::to_string(complete_rounds_) +
                                 " already taken: ignored");
      return;
    }
    complete_rounds_ = m.complete_rounds;
    round_starts_.clear();  // each drone's newest round-start pose, in its own frame
    std::map<int, int> newest;
    for (const fact::round_packet_t& p : m.packets)
      if (!newest.count(p.drone_id) || p.round > newest[p.drone_id]) {
        newest[p.drone_id] = p.round;
        round_starts_[p.drone_id] = {Vector3d(p.position[0], p.position[1], p.position[2]), p.yaw};
      }
  }

  void on_result(const lcm::ReceiveBuffer* rbuf, const std::string& ch) {
    fact::swarm_result_t m;
    if (!fact::app::decode(rbuf, ch, &m, &status_, log_)) return;
    if (!own(m.drone_id, "swarm_result", ch)) return;
    fact::Estimate e;
    if (std::string err = fact::app::result_from_message(m, &e); !err.empty())
      return reject("invalid_input", "swarm_result on " + ch + ": " + err);
    // The kept result is the one with the most rounds: an impossible count would shadow every real
    // one after it (review, session 30). One round ahead of the rounds received is allowed: the
    // result may overtake its rounds message, or that message may have been lost.
    if (m.rounds_used < 0 || m.rounds_used > complete_rounds_ + 1)
      return reject("invalid_input", "swarm_result on " + ch + ": rounds_used = " + std::to_string(m.rounds_used) +
                                         " is outside [0, " + std::to_string(complete_rounds_ + 1) +
                                         "] (complete rounds received + 1)");
    status_.count("results");
    if (!result_ || m.rounds_used >= result_->rounds_used) result_ = m;
  }

  // ---- the loop --------------------------------------------------------------------------------
  // Runs after every wait: maps frames, steps the state machine, publishes a setpoint when due.
  // Returns -1 to keep running, else the exit code. `now` is fact::app::monotonic_us(): every
  // interval (trajectory time, the setpoint deadline, odometry staleness, waits, the spin slot)
  // is a difference on it, so a wall-clock step neither stops the stream nor cuts a move or spin
  // short (review, session 30: a step back of an hour stopped the setpoints, a step forward
  // ended a spin with a 4.4 rad yaw jump). Messages keep now_us() stamps, and every drone's spin
  // slot is a delay from the same gossip and result messages, so the swarm stays in step.
  int every(int64_t now) {
    while (!frames_.empty() && (boxes_.count(frames_.front().frame->utime) ||
                                now - frames_.front().arrival >= us(o_.frame_wait))) {
      map_frame(*frames_.front().frame);
      frames_.pop_front();
    }
    step(now);
    if (now >= next_setpoint_) {
      publish_setpoint(now);
      const int64_t period = us(1.0 / o_.setpoint_rate);
      next_setpoint_ = now - next_setpoint_ > period ? now + period : next_setpoint_ + period;
    }
    status_.tick(fact::app::now_us());  // (the status message carries wall or simulation time)
    if (o_.exit_when_done && phase_ == Phase::done && now - done_since_ >= 1000000 && hold_published_) {
      log_.event(certified_ ? "exit: certified hold published for 1 s" : "exit: --max-rounds reached, not certified");
      return certified_ ? 0 : 3;
    }
    return -1;
  }

  // When the next setpoint is due (µs, monotonic_us() clock): the main loop wakes for it.
  int64_t next_deadline() const { return next_setpoint_; }

  void final_status() {
    status_.set_state("stopped");
    status_.publish(fact::app::now_us());
  }

 private:
  static int64_t us(double s) { return static_cast<int64_t>(std::llround(s * 1e6)); }

  bool own(int id, const char* what, const std::string& ch) {
    if (id == o_.common.drone_id) return true;
    reject("wrong_drone_id", std::string(what) + " from drone " + std::to_string(id) + " on " + ch);
    return false;
  }

  void reject(const std::string& counter, const std::string& line) {
    status_.note(line);
    fact::app::count_and_log(status_, log_, counter, line);
  }

  void set_state(const std::string& s) {
    if (s == state_) return;
    state_ = s;
    status_.set_state(s);
    log_.event("state: " + s);
    status_.publish(fact::app::now_us());
  }

  // The planner's parameters with the fence cut to the map's extent: beyond it no obstacle is
  // known, so no move may end there (the map follows the drone and always holds it well inside).
  fact::PlannerParams within_map(fact::PlannerParams p) const {
    const fact::ObstacleBox b = map_.bounds();
    p.fence = {std::max(p.fence[0], b.lo.x()), std::min(p.fence[1], b.hi.x()), std::max(p.fence[2], b.lo.y()),
               std::min(p.fence[3], b.hi.y())};
    return p;
  }

  static std::string fmt2(double lo, double hi) {
    char s[64];
    std::snprintf(s, sizeof s, "[%.1f, %.1f]", lo, hi);
    return s;
  }

  void map_frame(const fact::frame_t& m) {
    Pose pose;
    if (!poses_.at(m.utime, us(o_.odometry_timeout), &pose))
      return reject("no_odometry_at_time", "frame seq " + std::to_string(m.seq) + ": no odometry near its time");
    std::vector<fact::BoxDetection> boxes;
    if (auto it = boxes_.find(m.utime); it != boxes_.end())
      boxes = it->second;
    else
      status_.count("frames_without_detections");
    depth_.resize(m.depth_mm.size());
    for (size_t i = 0; i < depth_.size(); ++i) depth_[i] = m.depth_mm[i] > 0 ? static_cast<uint16_t>(m.depth_mm[i]) : 0;
    fact::FrameView view;
    view.utime = m.utime;
    view.intrinsics = fact::CameraIntrinsics{m.width, m.height, m.fx, m.fy, m.cx, m.cy};
    view.gray = m.gray.data();
    view.depth_mm = depth_.data();
    fact::MapPose mp{pose.position, pose.yaw, pose.pitch, pose.roll};
    fact::FrameIntegration st;
    if (std::string e = map_.add_frame(view, extrinsics_, mp, boxes, &st); !e.empty())
      return reject("map_failed", "frame seq " + std::to_string(m.seq) + ": " + e);
    status_.count("frames_mapped");
    if (st.recentred) {
      status_.count("map_recentred");
      const fact::ObstacleBox b = map_.bounds();
      log_.event("map re-centred on the drone: it covers x " + fmt2(b.lo.x(), b.hi.x()) + ", y " + fmt2(b.lo.y(), b.hi.y()) +
                 " m of f_i; " + std::to_string(st.forgotten) + " occupied voxel(s) beyond it forgotten");
    }
  }

  // A new trajectory from now.
  void fly(const fact::Trajectory& t, int64_t now) {
    trajectory_ = t;
    trajectory_start_ = now;
  }
  bool trajectory_done(int64_t now) const { return (now - trajectory_start_) * 1e-6 >= trajectory_.duration(); }

  void enter(Phase p, int64_t now, const std::string& why) {
    phase_ = p;
    phase_since_ = now;
    std::ostringstream s;
    s << name(p) << " round " << round_ << ": " << why;
    phase_state_ = s.str();
  }

  // "; spin at +T s": when the synchronised spin may start (fact::move_slot), for the state line.
  std::string spin_time(int64_t now) const {
    std::ostringstream s;
    s << "; spin at +" << std::fixed << std::setprecision(2) << (spin_not_before_ - now) * 1e-6 << " s";
    return s.str();
  }

  void start_spin(int64_t now) {
    if (round_ >= o_.max_rounds) {
      fly(fact::hold_trajectory(poses_.newest().position, poses_.newest().yaw), now);
      return enter(Phase::done, now, "not certified after " + std::to_string(o_.max_rounds) + " rounds (--max-rounds): holding");
    }
    round_ = std::max(round_, complete_rounds_);
    seen_.clear();
    const Pose& p = poses_.newest();
    fact::Plan plan = fact::plan_spin(p.position, p.yaw, o_.planner);
    status_.count("plans");
    fly(plan.trajectory, now);
    enter(Phase::spin, now, plan.reason + " (swarm complete_rounds " + std::to_string(complete_rounds_) + ")");
  }

  // Other drones' newest round-start positions in f_i through the result's frame poses.
  std::vector<Vector3d> known() const {
    std::vector<Vector3d> out;
    if (!result_) return out;
    std::map<int, const fact::drone_pose_t*> pose;
    for (const fact::drone_pose_t& d : result_->drones)
      if (d.resolved) pose[d.id] = &d;
    auto own = pose.find(o_.common.drone_id);
    if (own == pose.end()) return out;
    const Vector3d ti(own->second->position[0], own->second->position[1], own->second->position[2]);
    const Eigen::Matrix3d Ri_inv = Eigen::AngleAxisd(-own->second->yaw, Vector3d::UnitZ()).toRotationMatrix();
    for (const auto& [id, start] : round_starts_) {
      if (id == o_.common.drone_id || !pose.count(id)) continue;
      const fact::drone_pose_t& d = *pose[id];
      const Vector3d tj(d.position[0], d.position[1], d.position[2]);
      out.push_back(Ri_inv * (Eigen::AngleAxisd(d.yaw, Vector3d::UnitZ()) * start.first + tj - ti));
    }
    return out;
  }

  void plan_move(int64_t now, fact::ResultStatus status, const std::string& why) {
    fact::PlannerInput in;
    const Pose& p = poses_.newest();
    in.position = p.position;
    in.yaw = p.yaw;
    in.status = status;
    in.rng = rng_;
    for (const auto& [track, s] : seen_) in.observed.push_back(s.first / s.second);
    // A spin that saw no drone (occluded, or a far drone missed) keeps the latest sightings (f_i):
    // without them the move would be blind, with no max-move bound from the nearest drone and no
    // direction toward the swarm.
    const bool remembered = in.observed.empty() && !last_observed_.empty();
    if (in.observed.empty()) in.observed = last_observed_;
    last_observed_ = in.observed;
    in.known = known();
    const std::vector<fact::ObstacleBox> pieces = map_.pieces();
    fact::Plan plan = fact::plan_step(in, pieces, within_map(o_.planner));
    rng_ = plan.rng;
    status_.count("plans");
    std::ostringstream s;
    s << why << "; " << fact::to_string(status) << ", " << in.observed.size() << (remembered ? " remembered" : " observed")
      << ", " << in.known.size()
      << " known, " << pieces.size() << " obstacle pieces: " << fact::to_string(plan.kind) << " to " << fmt(plan.target)
      << " (max_move " << plan.max_move << " m): " << plan.reason;
    if (plan.kind == fact::PlanKind::rejected || plan.kind == fact::PlanKind::hover_fallback) {
      status_.count("hover");
      plan_hover_ = std::string("hover: ") + fact::to_string(plan.kind) + " plan: " + plan.reason;
      fly(fact::hold_trajectory(last_.position, last_.yaw), now);
      hover_until_ = now + 1000000;  // hover at least one second, then spin when the move slot ends
    } else {
      fly(plan.trajectory, now);
    }
    spin_not_before_ = now + us(fact::move_slot(o_.planner));
    enter(Phase::move, now, s.str() + spin_time(now));
  }

  void step(int64_t now) {
    if (poses_.empty()) return;  // wait_odometry: nothing to hold yet, no setpoints
    const double age = (now - odometry_arrival_) * 1e-6;
    if (age > o_.odometry_timeout && phase_ != Phase::wait_odometry) {  // stale: freeze at the last commanded point
      if (!hovering_) {
        hovering_ = true;
        status_.count("hover");
        hover_phase_end_ = trajectory_.sample(1e9);
        brake(now);
      }
      std::ostringstream s;
      s << "hover: odometry stale (none for more than " << o_.odometry_timeout << " s) in " << phase_state_;
      return set_state(s.str());
    }
    if (hovering_) {  // inputs are back: resume the phase's trajectory from where it stopped
      hovering_ = false;
      resume(now);
    }
    switch (phase_) {
      case Phase::wait_odometry: {
        fact::Plan plan = fact::plan_takeoff(poses_.newest().position, poses_.newest().yaw, o_.planner, rng_);
        rng_ = plan.rng;
        status_.count("plans");
        last_ = fact::TrajectorySample{};
        last_.position = poses_.newest().position;
        last_.yaw = poses_.newest().yaw;
        fly(plan.trajectory, now);
        spin_not_before_ = now + us(fact::takeoff_slot(poses_.newest().position.z(), o_.planner));
        enter(Phase::takeoff, now, "to " + fmt(plan.target) + ": " + plan.reason + spin_time(now));
        break;
      }
      case Phase::takeoff:
        if (trajectory_done(now) && now >= spin_not_before_) start_spin(now);
        break;
      case Phase::spin:
        if (trajectory_done(now)) {
          std::ostringstream s;
          s << "spin done, " << seen_.size() << " drones observed; waiting for complete_rounds >= " << round_ + 1;
          enter(Phase::wait, now, s.str());
        }
        break;
      case Phase::wait: {
        const int need = round_ + 1;
        if (complete_rounds_ >= need && result_ && result_->rounds_used >= need) {
          round_ = need;
          if (result_->status == "certified") {
            certified_ = true;
            fly(fact::plan_step(fact::PlannerInput{poses_.newest().position, Vector3d::Zero(), Vector3d::Zero(),
                                                   poses_.newest().yaw, {}, {}, fact::ResultStatus::certified, rng_},
                                {}, o_.planner).trajectory, now);
            std::ostringstream s;
            s << "certified result (rounds_used " << result_->rounds_used << ", reference " << result_->reference
              << "): holding";
            for (const fact::drone_pose_t& d : result_->drones)
              s << "; drone " << d.id << " frame yaw " << d.yaw << " rad origin " << fmt(Vector3d(d.position[0], d.position[1], d.position[2]));
            enter(Phase::done, now, s.str());
          } else {
            plan_move(now, result_->status == "ambiguous" ? fact::ResultStatus::ambiguous : fact::ResultStatus::not_certified,
                      "result " + result_->status + " with rounds_used " + std::to_string(result_->rounds_used));
          }
        } else if (now - phase_since_ >= us(o_.wait_timeout)) {
          status_.count("wait_timeouts");
          round_ = std::max(need, complete_rounds_);
          std::ostringstream s;
          s << "no result for round " << need - 1 << " within " << o_.wait_timeout << " s (complete_rounds "
            << complete_rounds_ << ", newest result rounds_used " << (result_ ? result_->rounds_used : 0) << ")";
          plan_move(now, fact::ResultStatus::none, s.str());
        } else {
          std::ostringstream s;
          s << "wait round " << round_ << ": complete_rounds " << complete_rounds_ << "/" << need << ", result rounds_used "
            << (result_ ? result_->rounds_used : 0) << "/" << need;
          phase_state_ = s.str();
        }
        break;
      }
      case Phase::move:
        if (trajectory_done(now) && now >= hover_until_ && now >= spin_not_before_) {
          plan_hover_.clear();
          start_spin(now);
        }
        break;
      case Phase::done:
        break;
    }
    set_state(plan_hover_.empty() ? phase_state_ : plan_hover_ + " (" + phase_state_ + ")");
  }

  // A min-jerk trajectory from `start` to rest at `target` within v_max and a_max when `move`,
  // held at start's position instead when it is not worth a move or the limits cannot be kept
  // (start already beyond them); the yaw turns by `turn` from start.yaw at the spin's rate limits.
  fact::Trajectory to_rest(const fact::TrajectoryStart& start, const Vector3d& target, bool move, double turn) const {
    const fact::TrajectoryLimits limits{o_.planner.v_max, o_.planner.a_max, 0.02};
    fact::Trajectory t = fact::hold_trajectory(start.position, start.yaw);
    if (move && !fact::min_jerk_within_limits(start, target, limits, &t).empty())
      t = fact::hold_trajectory(start.position, start.yaw);
    t.yaw = fact::YawProfile{start.yaw, turn, o_.planner.spin_rate, o_.planner.yaw_accel};
    return t;
  }

  // Entering a hover: from the last setpoint (position, velocity, acceleration) to rest within
  // v_max and a_max, at the braking distance |v|²/(2 a_max) ahead; the yaw stays. Freezing the
  // last commanded point at rest asked for a stop in one setpoint (|Δv| 0.76 m/s mid-move:
  // review, session 30). Without a smooth stop (limits already exceeded) it holds the point.
  void brake(int64_t now) {
    fact::TrajectoryStart start;
    start.position = last_.position;
    start.velocity = last_.velocity;
    start.acceleration = last_.acceleration;
    start.yaw = last_.yaw;
    const double speed = last_.velocity.norm();
    const Vector3d stop = last_.position + last_.velocity * (speed / (2 * o_.planner.a_max));
    hover_trajectory_ = to_rest(start, stop, speed > 1e-3, 0);
    hover_start_ = now;
  }

  // After a hover: the rest of the interrupted trajectory, from the hover point at rest to its end
  // position and end yaw (a straight segment of the original straight path; the yaw ramp's rest).
  void resume(int64_t now) {
    fact::TrajectoryStart start;
    start.position = last_.position;
    start.yaw = last_.yaw;
    const fact::Trajectory t = to_rest(start, hover_phase_end_.position,
                                       (hover_phase_end_.position - last_.position).norm() > 1e-3,
                                       hover_phase_end_.yaw - last_.yaw);
    fly(t, now);
    log_.event("odometry back: resuming " + std::string(name(phase_)) + " to " + fmt(hover_phase_end_.position));
  }

  void publish_setpoint(int64_t now) {
    if (poses_.empty()) return;
    fact::TrajectorySample s = hovering_ ? hover_trajectory_.sample((now - hover_start_) * 1e-6)
                                         : trajectory_.sample((now - trajectory_start_) * 1e-6);
    if (!plan_hover_.empty()) {
      s.velocity.setZero();
      s.acceleration.setZero();
      s.yaw_rate = 0;
    }
    if (!s.position.allFinite() || !s.velocity.allFinite() || !s.acceleration.allFinite() || !std::isfinite(s.yaw) ||
        !std::isfinite(s.yaw_rate)) {
      reject("rejected_setpoint", "non-finite setpoint from the " + std::string(name(phase_)) + " trajectory: holding");
      s = last_;
      s.velocity.setZero();
      s.acceleration.setZero();
      s.yaw_rate = 0;
    }
    fact::setpoint_t m;
    m.utime = fact::app::now_us();  // (the message's stamp: wall or simulation time; `now` is monotonic)
    m.drone_id = o_.common.drone_id;
    for (int i = 0; i < 3; ++i) {
      m.position[i] = s.position[i];
      m.velocity[i] = s.velocity[i];
      m.acceleration[i] = s.acceleration[i];
    }
    m.yaw = s.yaw;
    m.yaw_rate = s.yaw_rate;
    if (lcm_.publish(o_.setpoint_channel, &m) != 0) return reject("publish_failed", "publish on " + o_.setpoint_channel + " failed");
    status_.count("setpoints");
    last_ = s;
    if (phase_ == Phase::done && !hovering_) {
      if (!hold_published_) done_since_ = now;
      hold_published_ = true;
    }
  }

  lcm::LCM& lcm_;
  const Options& o_;
  fact::app::Log log_;
  fact::app::Status status_;
  fact::LocalMap map_;
  fact::CameraExtrinsics extrinsics_;
  fact::PlannerRng rng_;
  PoseBuffer poses_;
  int64_t odometry_arrival_ = 0;
  std::map<int64_t, std::vector<fact::BoxDetection>> boxes_;  // detection boxes by frame utime
  struct PendingFrame {
    std::shared_ptr<fact::frame_t> frame;
    int64_t arrival;
  };
  std::deque<PendingFrame> frames_;
  std::vector<uint16_t> depth_;
  std::map<int, std::pair<Vector3d, int>> seen_;  // this spin: track id → (sum of positions in f_i, count)
  std::vector<Vector3d> last_observed_;            // the latest spin's sightings that had any (f_i, m)
  int complete_rounds_ = 0;
  std::map<int, std::pair<Vector3d, double>> round_starts_;  // drone id → newest round-start position, yaw (own frame)
  std::optional<fact::swarm_result_t> result_;
  Phase phase_ = Phase::wait_odometry;
  int64_t phase_since_ = 0;
  int round_ = 0;  // the round being spun / waited for (0-based)
  std::string state_, phase_state_ = "wait_odometry", plan_hover_;
  fact::Trajectory trajectory_;
  int64_t trajectory_start_ = 0, next_setpoint_ = 0, hover_until_ = 0, done_since_ = 0;
  int64_t spin_not_before_ = 0;  // the synchronised spin starts no earlier (fact::move_slot, fact::takeoff_slot)
  fact::TrajectorySample last_, hover_phase_end_;  // the last published setpoint; the interrupted trajectory's end
  fact::Trajectory hover_trajectory_;                // the stop a hover flies (brake), from hover_start_
  int64_t hover_start_ = 0;
  int64_t last_seq_ = 0;  // the newest accepted odometry's seq
  bool hovering_ = false, certified_ = false, hold_published_ = false;
};

}  // namespace

int main(int argc, char** argv) {
  Options options;
  CLI::App app{"Runs one drone's takeoff / spin / wait / move cycle and streams its setpoints (LCM).", kApp};
  add_flags(app, options);
  app.get_formatter()->column_width(36);
  if (const int code = fact::app::parse_flags(app, argc, argv, kApp, [&] { check(options); }); code >= 0) return code;
  const fact::app::Log log(kApp, options.common.drone_id);
  lcm::LCM lcm(options.common.lcm_url);
  if (!fact::app::lcm_opened(lcm, options.common.lcm_url, log)) return 1;
  fact::app::install_stop_handler();
  if (!fact::app::start_clock(lcm, options.common, log)) return 1;
  Planner planner(lcm, options);
  lcm.subscribe(options.odometry_channel, &Planner::on_odometry, &planner);
  lcm.subscribe(options.detections_channel, &Planner::on_detections, &planner);
  std::unique_ptr<lcm::LCM> frames_lcm;  // only with --frames-url
  if (!options.frames_url.empty()) {
    frames_lcm = std::make_unique<lcm::LCM>(options.frames_url);
    if (!frames_lcm->good()) {
      log.event("error: cannot open LCM for frames at --frames-url " + options.frames_url);
      return 1;
    }
  }
  (frames_lcm ? *frames_lcm : lcm).subscribe(options.frames_channel, &Planner::on_frame, &planner);
  lcm.subscribe(options.rounds_channel, &Planner::on_rounds, &planner);
  lcm.subscribe(options.result_channel, &Planner::on_result, &planner);
  log.event("publishing setpoints on " + options.setpoint_channel + " at " + std::to_string(options.setpoint_rate) + " Hz");
  int exit_code = -1;
  // Wakes for every message and exactly when the next setpoint is due (at least every 20 ms).
  const int code = fact::app::run_deadline_loop(lcm, 20000, [&](int64_t now) {
    const int c = planner.every(now);
    if (c >= 0 && exit_code < 0) {
      exit_code = c;
      fact::app::request_stop();
    }
    return planner.next_deadline();
  }, {frames_lcm.get()}, &fact::app::monotonic_us);
  planner.final_status();
  log.event(code != 0 ? "stopped: LCM failed" : "stopped");
  return code != 0 ? 1 : exit_code >= 0 ? exit_code : 0;
}
