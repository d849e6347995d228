// fact-fc-bridge core: validation, the setpoint stream and its stop rules, odometry forwarding,
// arm / offboard commands, and the flight controller's state.
#include "bridge.h"

#include "fact/mavlink_frames.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

namespace fact::bridge {

namespace mav = fact::mavlink;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
const char* const kAxis[] = {"x", "y", "z"};

std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// "" when v is finite and within ±kLargestValue; otherwise "<name> = <v> is not finite" (counter
// rejected_nan) or "... is beyond ±1e+06" (rejected_range).
std::string check_value(const std::string& name, double v, std::string* counter) {
  if (!std::isfinite(v)) {
    *counter = "rejected_nan";
    return name + " = " + num(v) + " is not finite";
  }
  if (std::abs(v) > kLargestValue) {
    *counter = "rejected_range";
    return name + " = " + num(v) + " is beyond ±" + num(kLargestValue);
  }
  return "";
}

// The first bad field of a setpoint ("" when all are good), as check_value.
std::string bad_field(const fact::setpoint_t& sp, std::string* counter) {
  for (int i = 0; i < 3; ++i) {
    const std::string at = "[" + std::to_string(i) + "]";
    for (const auto& [name, v] : {std::pair<std::string, double>{"position" + at, sp.position[i]},
                                  {"velocity" + at, sp.velocity[i]}, {"acceleration" + at, sp.acceleration[i]}})
      if (std::string why = check_value(name, v, counter); !why.empty()) return why;
  }
  if (std::string why = check_value("yaw", sp.yaw, counter); !why.empty()) return why;
  return check_value("yaw_rate", sp.yaw_rate, counter);
}

std::string bad_field(const fact::odometry_t& od, std::string* counter) {
  for (int i = 0; i < 3; ++i) {
    const std::string at = "[" + std::to_string(i) + "]";
    if (std::string why = check_value("position" + at, od.position[i], counter); !why.empty()) return why;
    if (std::string why = check_value("velocity" + at, od.velocity[i], counter); !why.empty()) return why;
  }
  for (const auto& [name, v] : {std::pair<const char*, double>{"yaw", od.yaw}, {"roll", od.roll}, {"pitch", od.pitch}})
    if (std::string why = check_value(name, v, counter); !why.empty()) return why;
  return "";
}

// The first non-finite field of the flight controller's LOCAL_POSITION_NED or ATTITUDE ("" when none).
std::string non_finite_field(const mav::LocalPositionNed& m) {
  const std::pair<const char*, float> fields[] = {{"x", m.x}, {"y", m.y}, {"z", m.z}, {"vx", m.vx}, {"vy", m.vy}, {"vz", m.vz}};
  for (const auto& [name, v] : fields)
    if (!std::isfinite(v)) return std::string("LOCAL_POSITION_NED ") + name + " = " + num(v);
  return "";
}

std::string non_finite_field(const mav::Attitude& m) {
  const std::pair<const char*, float> fields[] = {{"roll", m.roll}, {"pitch", m.pitch}, {"yaw", m.yaw}};
  for (const auto& [name, v] : fields)
    if (!std::isfinite(v)) return std::string("ATTITUDE ") + name + " = " + num(v);
  return "";
}

}  // namespace

Bridge::Bridge(const BridgeOptions& o, Send send, PublishState publish, app::Status* status, const app::Log& log)
    : o_(o),
      send_(std::move(send)),
      publish_(std::move(publish)),
      status_(status),
      log_(log),
      encoder_(o.self),
      stream_period_us_(static_cast<int64_t>(std::llround(1e6 / o.stream_rate_hz))) {
  for (const char* name : {"setpoints_received", "setpoints_sent", "odometry_received", "odometry_sent",
                           "heartbeats_sent", "fc_heartbeats", "commands_sent", "undecodable", "rejected_nan",
                           "rejected_range", "rejected_geofence", "rejected_drone_id", "rejected_stale",
                           "rejected_out_of_order", "mavlink_bad_crc", "mavlink_bad_length",
                           "mavlink_unknown_id", "mavlink_signed_frame", "mavlink_unknown_flags", "mavlink_truncated", "mavlink_non_finite",
                           "send_failed"})
    status_->count(name, 0);
  status_->set_state("no setpoint yet");
}

uint32_t Bridge::boot_ms(int64_t now) const {
  return static_cast<uint32_t>(start_us_ < 0 ? 0 : (now - start_us_) / 1000);
}

// Counts a rejection and logs it: the first 10 of each kind, then every 100th.
void Bridge::reject(const std::string& counter, const std::string& why) {
  status_->note(why);
  app::count_and_log(*status_, log_, counter, "rejected: " + why);
}

// ------------------------------------------------------------------------------- LCM input

std::string Bridge::check_setpoint(const fact::setpoint_t& sp, std::string* counter) const {
  if (sp.drone_id != o_.drone_id) {
    *counter = "rejected_drone_id";
    return "setpoint drone_id = " + std::to_string(sp.drone_id) + " (this bridge is drone " + std::to_string(o_.drone_id) + ")";
  }
  if (const std::string bad = bad_field(sp, counter); !bad.empty()) return "setpoint " + bad;
  for (int i = 0; i < 3; ++i) {
    if (sp.position[i] < o_.fence.min[i] || sp.position[i] > o_.fence.max[i]) {
      *counter = "rejected_geofence";
      return "setpoint position[" + std::to_string(i) + "] = " + num(sp.position[i]) + " m outside the geofence " +
             kAxis[i] + " [" + num(o_.fence.min[i]) + ", " + num(o_.fence.max[i]) + "] m";
    }
  }
  return "";
}

void Bridge::on_setpoint(const fact::setpoint_t& sp, const std::string& channel, int64_t now, int64_t stamp_clock) {
  if (start_us_ < 0) start_us_ = now;
  status_->count("setpoints_received");
  std::string counter;
  std::string why = check_setpoint(sp, &counter);
  // (compared without subtracting: a utime near INT64_MIN would overflow the difference)
  const int64_t m = o_.max_stamp_skew_us;
  if (why.empty() && m > 0 && (sp.utime < stamp_clock - m || sp.utime > stamp_clock + m)) {
    const double skew = static_cast<double>(stamp_clock) - static_cast<double>(sp.utime);  // > 0: in the past
    counter = "rejected_stale";
    why = "setpoint utime = " + std::to_string(sp.utime) + " is " + num(std::abs(skew) * 1e-6) + " s " +
          (skew > 0 ? "old" : "ahead of this clock") + " (at most " + num(m * 1e-6) +
          " s: a replayed log or a stuck publisher)";
  }
  if (!why.empty()) {
    reject(counter, why + " on " + channel);
    return;
  }
  setpoint_ = sp;
  setpoint_at_ = now;
  have_setpoint_ = true;
  update_stream_state(now);
}

void Bridge::on_odometry(const fact::odometry_t& od, const std::string& channel, int64_t now) {
  if (start_us_ < 0) start_us_ = now;
  status_->count("odometry_received");
  if (od.drone_id != o_.drone_id) {
    reject("rejected_drone_id", "odometry drone_id = " + std::to_string(od.drone_id) + " on " + channel +
                                    " (this bridge is drone " + std::to_string(o_.drone_id) + ")");
    return;
  }
  std::string counter;
  if (const std::string bad = bad_field(od, &counter); !bad.empty()) {
    reject(counter, "odometry " + bad + " on " + channel);
    return;
  }
  // A stream that starts again (fact::app::odometry_restarted: seq 0, a jump back beyond
  // reordering, or a time 1 s earlier) is a VIO restart: a reset for PX4's EKF2. Any other sample
  // that does not move forward is a duplicated or reordered datagram: not forwarded (review,
  // session 32: one reordered datagram reset EKF2's VIO fusion).
  if (have_odometry_seq_ && od.seq <= last_odometry_seq_) {
    if (!app::odometry_restarted(last_odometry_seq_, last_odometry_utime_, od.seq, od.utime)) {
      reject("rejected_out_of_order", "odometry seq " + std::to_string(od.seq) + " after " +
                                          std::to_string(last_odometry_seq_) + " on " + channel +
                                          ": a duplicated or reordered sample, not forwarded");
      return;
    }
    ++reset_counter_;
    log_.event("odometry seq " + std::to_string(od.seq) + " after " + std::to_string(last_odometry_seq_) +
               ": VIO reset, reset_counter = " + std::to_string(reset_counter_));
  }
  have_odometry_seq_ = true;
  last_odometry_seq_ = od.seq;
  last_odometry_utime_ = od.utime;

  const mav::Euler att{od.roll, od.pitch, od.yaw};
  const mav::Quat q = mav::attitude_quat_ned_frd(att);
  const mav::Vec3 p = mav::fi_to_ned({od.position[0], od.position[1], od.position[2]});
  // Velocity in the body FRD frame (child_frame_id = MAV_FRAME_BODY_FRD, as PX4's EKF2 reads it).
  const mav::Vec3 v = mav::rotate(mav::conjugate(q), mav::fi_to_ned({od.velocity[0], od.velocity[1], od.velocity[2]}));
  mav::Odometry m;
  m.time_usec = static_cast<uint64_t>(od.utime < 0 ? 0 : od.utime);
  m.x = static_cast<float>(p.x);
  m.y = static_cast<float>(p.y);
  m.z = static_cast<float>(p.z);
  m.q = {static_cast<float>(q.w), static_cast<float>(q.x), static_cast<float>(q.y), static_cast<float>(q.z)};
  m.vx = static_cast<float>(v.x);
  m.vy = static_cast<float>(v.y);
  m.vz = static_cast<float>(v.z);
  m.rollspeed = m.pitchspeed = m.yawspeed = kNaN;  // odometry_t carries no angular rates: unknown
  m.pose_covariance[0] = kNaN;                     // unknown covariances
  m.velocity_covariance[0] = kNaN;
  m.frame_id = mav::kFrameLocalNed;
  m.child_frame_id = mav::kFrameBodyFrd;
  m.reset_counter = reset_counter_;
  m.estimator_type = mav::kEstimatorVio;
  m.quality = 0;  // unknown
  send_(encoder_.encode(m));
  ++odometry_sent_;
  status_->count("odometry_sent");
}

// ------------------------------------------------------------------------------- FC input

void Bridge::on_fc_bytes(const uint8_t* data, std::size_t n, int64_t now, bool datagram) {
  if (start_us_ < 0) start_us_ = now;
  const auto on_frame_now = [&](const mav::Frame& f) { on_frame(f, now); };
  const auto on_reject = [&](const mav::Rejection& r) {
    reject(std::string("mavlink_") + mav::to_string(r.reason), "MAVLink from the FC: " + r.detail);
  };
  parser_.feed(data, n, on_frame_now, on_reject);
  if (datagram) parser_.end_of_datagram(on_frame_now, on_reject);
}

void Bridge::on_frame(const mav::Frame& f, int64_t now) {
  if (f.sysid != o_.target_system) return;  // another vehicle or a GCS: not ours
  mav::Heartbeat hb;
  if (mav::decode(f, &hb)) {
    if (f.compid == o_.target_component) on_heartbeat(hb, now);
    return;
  }
  // A non-finite value from the flight controller is counted and dropped: the last valid one stays.
  if (mav::LocalPositionNed position; mav::decode(f, &position)) {
    if (const std::string bad = non_finite_field(position); !bad.empty())
      return reject("mavlink_non_finite", "MAVLink from the FC: " + bad + " is not finite");
    position_ = position;
    position_valid_ = true;
    position_at_ = now;
    return;
  }
  if (mav::Attitude attitude; mav::decode(f, &attitude)) {
    if (const std::string bad = non_finite_field(attitude); !bad.empty())
      return reject("mavlink_non_finite", "MAVLink from the FC: " + bad + " is not finite");
    attitude_ = attitude;
    attitude_valid_ = true;
    attitude_at_ = now;
  }
}

void Bridge::on_heartbeat(const mav::Heartbeat& hb, int64_t now) {
  status_->count("fc_heartbeats");
  if (!fc_seen_)
    log_.event("flight controller heartbeat: sysid " + std::to_string(o_.target_system) + " autopilot " +
               std::to_string(hb.autopilot) + " type " + std::to_string(hb.type));
  fc_seen_ = true;
  fc_heartbeat_ = hb;
  fc_heartbeat_at_ = now;
  update_stream_state(now);
}

// ------------------------------------------------------------------------------- stream state

std::string Bridge::reason_text(int64_t now) const {
  switch (why_) {
    case Why::streaming: return "streaming";
    case Why::no_setpoint: return "no setpoint yet";
    case Why::setpoint_stale: return "setpoint stale (" + std::to_string((now - setpoint_at_) / 1000) + " ms old)";
    case Why::no_heartbeat: return "no flight-controller heartbeat yet";
    case Why::heartbeat_lost:
      return "flight-controller heartbeat lost (" + std::to_string((now - fc_heartbeat_at_) / 1000) + " ms)";
  }
  return "";
}

void Bridge::update_stream_state(int64_t now) {
  Why why = Why::streaming;
  if (!fc_seen_)
    why = Why::no_heartbeat;
  else if (now - fc_heartbeat_at_ > o_.heartbeat_timeout_us)
    why = Why::heartbeat_lost;
  else if (!have_setpoint_)
    why = Why::no_setpoint;
  else if (now - setpoint_at_ > o_.setpoint_timeout_us)
    why = Why::setpoint_stale;
  if (why == why_) return;
  const bool was = why_ == Why::streaming;
  why_ = why;
  const std::string text = reason_text(now);
  status_->set_state(text);
  if (why == Why::streaming) {
    streaming_since_ = now;
    next_setpoint_at_ = now;
    log_.event("streaming setpoints at " + num(o_.stream_rate_hz) + " Hz");
  } else if (was) {
    log_.event("streaming stopped: " + text + "; PX4's offboard-loss failsafe takes over");
  } else {
    log_.event("not streaming: " + text);
  }
  publish_state(now);
}

// ------------------------------------------------------------------------------- output

void Bridge::send_heartbeat(int64_t now) {
  mav::Heartbeat hb;
  hb.type = mav::kMavTypeOnboardController;
  hb.autopilot = mav::kMavAutopilotInvalid;
  hb.base_mode = 0;
  hb.custom_mode = 0;
  hb.system_status = mav::kMavStateActive;
  send_(encoder_.encode(hb));
  status_->count("heartbeats_sent");
  next_heartbeat_at_ = now + 1000000;
}

void Bridge::send_setpoint(int64_t now) {
  const mav::Vec3 p = mav::fi_to_ned({setpoint_.position[0], setpoint_.position[1], setpoint_.position[2]});
  const mav::Vec3 v = mav::fi_to_ned({setpoint_.velocity[0], setpoint_.velocity[1], setpoint_.velocity[2]});
  const mav::Vec3 a = mav::fi_to_ned({setpoint_.acceleration[0], setpoint_.acceleration[1], setpoint_.acceleration[2]});
  mav::SetPositionTargetLocalNed m;
  m.time_boot_ms = boot_ms(now);
  m.x = static_cast<float>(p.x);
  m.y = static_cast<float>(p.y);
  m.z = static_cast<float>(p.z);
  m.vx = static_cast<float>(v.x);
  m.vy = static_cast<float>(v.y);
  m.vz = static_cast<float>(v.z);
  m.afx = static_cast<float>(a.x);
  m.afy = static_cast<float>(a.y);
  m.afz = static_cast<float>(a.z);
  m.yaw = static_cast<float>(mav::yaw_fi_to_ned(setpoint_.yaw));
  m.yaw_rate = static_cast<float>(mav::yaw_rate_fi_to_ned(setpoint_.yaw_rate));
  m.type_mask = 0;  // use every field: position, velocity and acceleration feed-forward, yaw, yaw rate
  m.target_system = o_.target_system;
  m.target_component = o_.target_component;
  m.coordinate_frame = mav::kFrameLocalNed;
  send_(encoder_.encode(m));
  ++setpoints_sent_;
  status_->count("setpoints_sent");
}

void Bridge::send_command(uint16_t command, float p1, float p2) {
  mav::CommandLong c;
  c.param = {p1, p2, 0, 0, 0, 0, 0};
  c.command = command;
  c.target_system = o_.target_system;
  c.target_component = o_.target_component;
  c.confirmation = static_cast<uint8_t>(command_rounds_ > 255 ? 255 : command_rounds_);
  send_(encoder_.encode(c));
  status_->count("commands_sent");
}

// Arm / offboard requests: only with the flags, only while streaming for >= command_after_us,
// once per command_interval_us, until the FC's heartbeat shows the state or the tries run out.
void Bridge::send_commands(int64_t now) {
  if (!o_.arm && !o_.offboard) return;
  if (why_ != Why::streaming || now - streaming_since_ < o_.command_after_us) return;
  const bool armed = (fc_heartbeat_.base_mode & mav::kModeFlagSafetyArmed) != 0;
  const bool offboard = (fc_heartbeat_.base_mode & mav::kModeFlagCustomModeEnabled) &&
                        mav::px4_main_mode(fc_heartbeat_.custom_mode) == mav::kPx4MainModeOffboard;
  const bool need_mode = o_.offboard && !offboard, need_arm = o_.arm && !armed;
  if (commands_done_) {
    // Requests end for good once the state was reached: a pilot who takes over (another mode, or
    // disarms) is not overridden (review, session 32: the tries left were spent re-arming).
    if ((need_mode || need_arm) && !left_state_logged_)
      log_.event(std::string("flight controller left the requested state (") + (need_arm ? "disarmed" : "armed") + ", " +
                 (need_mode ? "not offboard" : "offboard") + "): not requested again");
    left_state_logged_ = need_mode || need_arm;
    return;
  }
  if (!need_mode && !need_arm) {
    log_.event("flight controller reports the requested state (armed / offboard): no more requests");
    commands_done_ = true;
    return;
  }
  if (command_rounds_ >= o_.command_tries || (command_rounds_ > 0 && now - last_command_at_ < o_.command_interval_us))
    return;
  if (need_mode) send_command(mav::kCmdDoSetMode, 1.0f, static_cast<float>(mav::kPx4MainModeOffboard));
  if (need_arm) send_command(mav::kCmdComponentArmDisarm, 1.0f, 0.0f);
  ++command_rounds_;
  last_command_at_ = now;
  log_.event(std::string("requested") + (need_mode ? " offboard mode" : "") + (need_mode && need_arm ? " and" : "") + (need_arm ? " arming" : "") + " (try " +
             std::to_string(command_rounds_) + " of " + std::to_string(o_.command_tries) + ")");
  if (command_rounds_ == o_.command_tries)
    log_.event("no more arm / offboard requests: the flight controller did not report the state after " +
               std::to_string(o_.command_tries) + " tries");
}

fact::fc_state_t Bridge::state(int64_t now) const {
  fact::fc_state_t s{};
  s.utime = now;
  s.drone_id = o_.drone_id;
  s.connected = fc_seen_ && now - fc_heartbeat_at_ <= o_.heartbeat_timeout_us;
  s.armed = fc_seen_ && (fc_heartbeat_.base_mode & mav::kModeFlagSafetyArmed) != 0;
  s.offboard = fc_seen_ && (fc_heartbeat_.base_mode & mav::kModeFlagCustomModeEnabled) &&
               mav::px4_main_mode(fc_heartbeat_.custom_mode) == mav::kPx4MainModeOffboard;
  s.custom_mode = fc_heartbeat_.custom_mode;
  s.base_mode = fc_heartbeat_.base_mode;
  s.system_status = fc_heartbeat_.system_status;
  s.heartbeat_age_ms = fc_seen_ ? (now - fc_heartbeat_at_) / 1000 : -1;
  s.position_valid = position_valid_;
  s.position_age_ms = position_valid_ ? (now - position_at_) / 1000 : -1;
  const mav::Vec3 p = mav::ned_to_fi({position_.x, position_.y, position_.z});
  const mav::Vec3 v = mav::ned_to_fi({position_.vx, position_.vy, position_.vz});
  s.position[0] = p.x; s.position[1] = p.y; s.position[2] = p.z;
  s.velocity[0] = v.x; s.velocity[1] = v.y; s.velocity[2] = v.z;
  s.attitude_valid = attitude_valid_;
  s.attitude_age_ms = attitude_valid_ ? (now - attitude_at_) / 1000 : -1;
  const mav::Euler e = mav::attitude_ned_to_fi({attitude_.roll, attitude_.pitch, attitude_.yaw});
  s.roll = e.roll;
  s.pitch = e.pitch;
  s.yaw = e.yaw;
  s.streaming = why_ == Why::streaming;
  s.reason = reason_text(now);
  s.setpoints_sent = setpoints_sent_;
  s.odometry_sent = odometry_sent_;
  return s;
}

void Bridge::publish_state(int64_t now) {
  const fact::fc_state_t s = state(now);
  publish_(s);
  last_connected_ = s.connected;
  last_armed_ = s.armed;
  last_offboard_ = s.offboard;
  next_state_at_ = now + static_cast<int64_t>(std::llround(1e6 / o_.state_rate_hz));
}

void Bridge::tick(int64_t now) {
  if (start_us_ < 0) start_us_ = now;
  update_stream_state(now);
  if (now >= next_heartbeat_at_) send_heartbeat(now);
  if (why_ == Why::streaming && now >= next_setpoint_at_) {
    send_setpoint(now);
    next_setpoint_at_ += stream_period_us_;
    if (next_setpoint_at_ <= now) next_setpoint_at_ = now + stream_period_us_;  // fell behind: no burst
  }
  send_commands(now);
  // Cheap change detection; the full message is built only when it is published.
  const bool connected = fc_seen_ && now - fc_heartbeat_at_ <= o_.heartbeat_timeout_us;
  const bool armed = fc_seen_ && (fc_heartbeat_.base_mode & mav::kModeFlagSafetyArmed) != 0;
  const bool offboard = fc_seen_ && (fc_heartbeat_.base_mode & mav::kModeFlagCustomModeEnabled) &&
                        mav::px4_main_mode(fc_heartbeat_.custom_mode) == mav::kPx4MainModeOffboard;
  const bool changed = connected != last_connected_ || armed != last_armed_ || offboard != last_offboard_;
  if (changed)
    log_.event(std::string("flight controller: ") + (connected ? "connected" : "not connected") +
               (armed ? ", armed" : ", disarmed") + (offboard ? ", offboard" : ""));
  if (changed || now >= next_state_at_) publish_state(now);
}

int64_t Bridge::wait_us(int64_t now) const {
  int64_t due = std::min(next_heartbeat_at_, next_state_at_);
  if (why_ == Why::streaming) due = std::min(due, next_setpoint_at_);
  // Stream stop rules are checked at least this often, too.
  due = std::min(due, now + 20000);
  return due > now ? due - now : 0;
}

}  // namespace fact::bridge
