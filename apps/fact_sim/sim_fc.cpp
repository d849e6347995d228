// The simulated flight controller of fact-sim: see sim_fc.h.
#include "sim_fc.h"

#include "fact/mavlink_frames.h"

#include <arpa/inet.h>
#include <errno.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>

namespace fact::sim_fc {

namespace mav = fact::mavlink;

namespace {

const char* const kNedAxis[] = {"north", "east", "down"};

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

std::string mode_name(uint32_t main, uint32_t sub) {
  if (main == kMainPosctl) return "POSCTL";
  if (main == kMainOffboard) return "OFFBOARD";
  if (main == kMainAuto && sub == kSubAutoLoiter) return "AUTO.LOITER";
  return "main " + std::to_string(main) + " sub " + std::to_string(sub);
}

std::string address(const sockaddr_in& a) {
  char host[INET_ADDRSTRLEN] = {};
  ::inet_ntop(AF_INET, &a.sin_addr, host, sizeof host);
  return std::string(host) + ":" + std::to_string(ntohs(a.sin_port));
}

}  // namespace

// ------------------------------------------------------------------------------- SimFc

SimFc::SimFc(int drone_id, const FcOptions& o, app::Status* status, const app::Log* log)
    : id_(drone_id), o_(o), status_(status), log_(log), encoder_({o.sysid, o.compid}) {
  if (o_.auto_arm) {
    armed_ = true;
    main_mode_ = kMainOffboard;
  }
}

void SimFc::event(const std::string& line) const { log_->event("drone " + std::to_string(id_) + " FC: " + line); }

void SimFc::reject(const std::string& counter, const std::string& why) {
  status_->note(why);
  app::count_and_log(*status_, *log_, counter, "drone " + std::to_string(id_) + " FC: rejected: " + why);
}

uint32_t SimFc::custom_mode() const {
  if (failsafe_) return (kMainAuto << 16) | (kSubAutoLoiter << 24);
  return (main_mode_ << 16) | (sub_mode_ << 24);
}

uint8_t SimFc::base_mode() const {
  return static_cast<uint8_t>(mav::kModeFlagCustomModeEnabled | (armed_ ? mav::kModeFlagSafetyArmed : 0));
}

bool SimFc::for_us(uint8_t system, uint8_t component) const {
  return (system == 0 || system == o_.sysid) && (component == 0 || component == o_.compid);
}

void SimFc::on_bytes(const uint8_t* data, std::size_t n, const sim::SimDrone& drone, int64_t t) {
  const auto on_frame_here = [&](const mav::Frame& f) { on_frame(f, drone, t); };
  const auto on_reject = [&](const mav::Rejection& r) { reject(std::string("fc_mavlink_") + mav::to_string(r.reason), r.detail); };
  parser_.feed(data, n, on_frame_here, on_reject);
  parser_.end_of_datagram(on_frame_here, on_reject);  // (n is one UDP datagram)
}

void SimFc::on_frame(const mav::Frame& f, const sim::SimDrone& drone, int64_t t) {
  mav::Heartbeat hb;
  mav::SetPositionTargetLocalNed sp;
  mav::CommandLong cmd;
  mav::Odometry od;
  if (mav::decode(f, &hb)) {
    status_->count("fc_peer_heartbeats");
  } else if (mav::decode(f, &sp)) {
    if (!for_us(sp.target_system, sp.target_component)) {
      reject("fc_not_for_us", "SET_POSITION_TARGET_LOCAL_NED for " + std::to_string(sp.target_system) + "/" +
                                  std::to_string(sp.target_component) + " (this FC is " + std::to_string(o_.sysid) + "/" +
                                  std::to_string(o_.compid) + ")");
      return;
    }
    on_setpoint(sp, t);
  } else if (mav::decode(f, &cmd)) {
    if (!for_us(cmd.target_system, cmd.target_component)) {
      reject("fc_not_for_us", "COMMAND_LONG " + std::to_string(cmd.command) + " for " + std::to_string(cmd.target_system) +
                                  "/" + std::to_string(cmd.target_component) + " (this FC is " + std::to_string(o_.sysid) +
                                  "/" + std::to_string(o_.compid) + ")");
      return;
    }
    on_command(cmd, drone, t);
  } else if (mav::decode(f, &od)) {
    // PX4's EKF2 would fuse it; the simulated FC estimates from the drone's own VIO (the same
    // samples the bridge forwards), so it is only counted.
    status_->count("fc_odometry");
  } else {
    status_->count("fc_ignored");  // a known message a flight controller does not take (e.g. ATTITUDE)
  }
}

void SimFc::on_setpoint(const mav::SetPositionTargetLocalNed& m, int64_t t) {
  const std::string what = "SET_POSITION_TARGET_LOCAL_NED";
  if (m.coordinate_frame != mav::kFrameLocalNed) {
    reject("fc_rejected_frame", what + " in MAV_FRAME " + std::to_string(m.coordinate_frame) +
                                    ": only MAV_FRAME_LOCAL_NED (1) is supported");
    return;
  }
  const uint16_t mask = m.type_mask;
  if (mask & kForceSet) {
    reject("fc_rejected_type_mask", what + " type_mask " + std::to_string(mask) + ": force setpoints (bit 512) are not supported");
    return;
  }
  const float ned_p[3] = {m.x, m.y, m.z}, ned_v[3] = {m.vx, m.vy, m.vz}, ned_a[3] = {m.afx, m.afy, m.afz};
  bool use_p[3], use_v[3], use_a[3];
  for (int k = 0; k < 3; ++k) {
    use_p[k] = !(mask & (kIgnoreX << k));
    use_v[k] = !(mask & (kIgnoreVx << k));
    use_a[k] = !(mask & (kIgnoreAx << k));
    if (!use_p[k] && !use_v[k] && !use_a[k]) {
      reject("fc_rejected_type_mask", what + " type_mask " + std::to_string(mask) + " leaves the " + kNedAxis[k] +
                                          " axis without position, velocity or acceleration");
      return;
    }
  }
  const bool use_yaw = !(mask & kIgnoreYaw), use_yaw_rate = !(mask & kIgnoreYawRate);
  // Non-finite values in used fields: rejected (PX4 would read NaN as "not set"; here it is garbage).
  const char* const names[3][3] = {{"x", "y", "z"}, {"vx", "vy", "vz"}, {"afx", "afy", "afz"}};
  for (int k = 0; k < 3; ++k) {
    const float v[3] = {ned_p[k], ned_v[k], ned_a[k]};
    const bool used[3] = {use_p[k], use_v[k], use_a[k]};
    for (int j = 0; j < 3; ++j)
      if (used[j] && !std::isfinite(v[j])) {
        reject("fc_rejected_nan", what + " " + names[j][k] + " = " + num(v[j]) + " is not finite");
        return;
      }
  }
  if (use_yaw && !std::isfinite(m.yaw)) {
    reject("fc_rejected_nan", what + " yaw = " + num(m.yaw) + " is not finite");
    return;
  }
  if (use_yaw_rate && !std::isfinite(m.yaw_rate)) {
    reject("fc_rejected_nan", what + " yaw_rate = " + num(m.yaw_rate) + " is not finite");
    return;
  }
  // Magnitudes no quadrotor in a room can mean (a scrambled or unit-confused sender).
  for (int k = 0; k < 3; ++k) {
    if ((use_p[k] && std::abs(ned_p[k]) > sim::kMaxSetpointPosition) ||
        (use_v[k] && std::abs(ned_v[k]) > sim::kMaxSetpointVelocity) ||
        (use_a[k] && std::abs(ned_a[k]) > sim::kMaxSetpointAcceleration)) {
      reject("fc_rejected_range", what + " " + kNedAxis[k] + " axis out of range (|position| <= " +
                                      num(sim::kMaxSetpointPosition) + " m, |velocity| <= " + num(sim::kMaxSetpointVelocity) +
                                      " m/s, |acceleration| <= " + num(sim::kMaxSetpointAcceleration) + " m/s^2): " +
                                      num(ned_p[k]) + ", " + num(ned_v[k]) + ", " + num(ned_a[k]));
      return;
    }
  }
  if (use_yaw_rate && std::abs(m.yaw_rate) > sim::kMaxSetpointYawRate) {
    reject("fc_rejected_range", what + " yaw_rate = " + num(m.yaw_rate) + " rad/s out of range");
    return;
  }
  auto pick = [](const float* v, const bool* used) {
    return mav::Vec3{used[0] ? v[0] : 0.0, used[1] ? v[1] : 0.0, used[2] ? v[2] : 0.0};
  };
  const mav::Vec3 p = mav::ned_to_fi(pick(ned_p, use_p)), v = mav::ned_to_fi(pick(ned_v, use_v)),
                  a = mav::ned_to_fi(pick(ned_a, use_a));
  Target tg;
  tg.sp.position = Eigen::Vector3d(p.x, p.y, p.z);
  tg.sp.velocity = Eigen::Vector3d(v.x, v.y, v.z);
  tg.sp.acceleration = Eigen::Vector3d(a.x, a.y, a.z);
  tg.sp.yaw = use_yaw ? mav::yaw_ned_to_fi(m.yaw) : 0.0;
  tg.sp.yaw_rate = use_yaw_rate ? mav::yaw_rate_ned_to_fi(m.yaw_rate) : 0.0;
  // f_i axis i is NED axis (1, 0, 2)[i].
  const int ned_of[3] = {1, 0, 2};
  for (int i = 0; i < 3; ++i) {
    tg.pos[i] = use_p[ned_of[i]];
    tg.vel[i] = use_v[ned_of[i]];
    tg.acc[i] = use_a[ned_of[i]];
  }
  tg.yaw = use_yaw;
  tg.yaw_rate = use_yaw_rate;
  if (!have_target_)
    event("first setpoint (type_mask " + std::to_string(mask) + "): f_i (" + num(p.x) + ", " + num(p.y) + ", " + num(p.z) + ")");
  target_ = tg;
  have_target_ = true;
  target_at_ = t;
  status_->count("fc_setpoints");
}

void SimFc::on_command(const mav::CommandLong& c, const sim::SimDrone& drone, int64_t t) {
  auto deny = [&](const std::string& why) {
    reject("fc_command_denied", "COMMAND_LONG " + std::to_string(c.command) + ": " + why);
  };
  if (c.command == mav::kCmdComponentArmDisarm) {
    if (c.param[0] == 1.0f) {
      if (!armed_) event("armed (mode " + mode_name(main_mode_, sub_mode_) + ")");
      armed_ = true;
    } else if (c.param[0] == 0.0f) {
      // On the ground: standing on the floor, or back on the spot it took off from (a start on a
      // box). The height above the start alone let a drone that took off from a box and flew
      // off it disarm in mid-air (review, session 33).
      const double above_floor = drone.p.z();  // (the floor is z = 0; dynamics stops the centre there)
      const double above_start = drone.p.z() - drone.origin.z();
      const bool on_start = (drone.p - drone.origin).head<2>().norm() <= 0.1 && std::abs(above_start) <= 0.02;
      const bool on_ground = drone.landed || ((above_floor <= 0.02 || on_start) && drone.v.norm() < 0.2);
      if (!on_ground) return deny("disarm refused in the air (" + num(above_floor) + " m above the floor)");
      if (armed_) event("disarmed");
      armed_ = false;
    } else {
      return deny("param1 = " + num(c.param[0]) + " (expected 1 arm or 0 disarm)");
    }
  } else if (c.command == mav::kCmdDoSetMode) {
    const float base = c.param[0];
    // (MAV_MODE is a uint8: anything outside [0, 256) has no flags, and the cast would be undefined)
    if (!(base >= 0 && base < 256) || (static_cast<int>(base) & mav::kModeFlagCustomModeEnabled) == 0)
      return deny("DO_SET_MODE param1 = " + num(base) + " lacks MAV_MODE_FLAG_CUSTOM_MODE_ENABLED");
    const float main = c.param[1], sub = c.param[2];
    uint32_t new_main = 0, new_sub = 0;
    if (main == static_cast<float>(kMainOffboard)) {
      if (!setpoint_fresh(t))
        return deny("OFFBOARD refused: no setpoint in the last " + num(o_.offboard_timeout_us * 1e-6) +
                    " s (PX4 needs the setpoint stream first)");
      new_main = kMainOffboard;
    } else if (main == static_cast<float>(kMainPosctl)) {
      new_main = kMainPosctl;
    } else if (main == static_cast<float>(kMainAuto) && sub == static_cast<float>(kSubAutoLoiter)) {
      new_main = kMainAuto;
      new_sub = kSubAutoLoiter;
    } else {
      return deny("DO_SET_MODE main mode " + num(main) + " sub mode " + num(sub) +
                  " not supported (OFFBOARD 6, POSCTL 3, AUTO 4 / LOITER 3)");
    }
    if (new_main != main_mode_ || new_sub != sub_mode_ || failsafe_)
      event("mode " + mode_name(new_main, new_sub) + (armed_ ? " (armed)" : " (disarmed)"));
    main_mode_ = new_main;
    sub_mode_ = new_sub;
    failsafe_ = false;  // a mode chosen by the operator replaces the failsafe
  } else {
    return deny("command not supported by the simulated FC");
  }
  status_->count("fc_commands");
}

void SimFc::control(sim::SimDrone* d, int64_t t) {
  if (!armed_) {
    if (!d->landed) {  // disarmed on the ground: the drone rests there
      d->landed = true;
      d->v.setZero();
      d->a.setZero();
      d->roll = d->pitch = 0;
      d->yaw_rate = 0;
    }
    activity_ = Activity::idle;
    return;
  }
  const sim::VioSample vio = sim::vio_sample(*d);
  bool follow = false, entering_failsafe = false;
  if (main_mode_ == kMainOffboard && have_target_) {
    if (setpoint_fresh(t)) {
      if (failsafe_) event("setpoints again: OFFBOARD resumed");
      failsafe_ = false;
      follow = true;
    } else if (!failsafe_) {
      failsafe_ = entering_failsafe = true;
      status_->count("fc_failsafe");
    }
  }
  if (follow) {
    sim::Setpoint sp;
    for (int i = 0; i < 3; ++i) {
      sp.position[i] = target_.pos[i] ? target_.sp.position[i] : vio.position[i];
      sp.velocity[i] = target_.vel[i] ? target_.sp.velocity[i] : (target_.pos[i] ? 0.0 : vio.velocity[i]);
      sp.acceleration[i] = target_.acc[i] ? target_.sp.acceleration[i] : 0.0;
    }
    sp.yaw = target_.yaw ? target_.sp.yaw : vio.yaw;
    sp.yaw_rate = target_.yaw_rate ? target_.sp.yaw_rate : 0.0;
    if (d->landed) event("takeoff (following OFFBOARD setpoints)");
    d->setpoint = sp;
    d->have_setpoint = true;
    d->landed = false;
    activity_ = Activity::following;
    return;
  }
  if (activity_ != Activity::holding) {
    hold_ = sim::Setpoint();
    hold_.position = vio.position;
    hold_.yaw = vio.yaw;
    activity_ = Activity::holding;
  }
  if (entering_failsafe)
    event("offboard-loss failsafe: no setpoint for " + num((t - target_at_) * 1e-6) + " s (> " +
          num(o_.offboard_timeout_us * 1e-6) + " s): holding position f_i (" + num(hold_.position.x()) + ", " +
          num(hold_.position.y()) + ", " + num(hold_.position.z()) + "), mode AUTO.LOITER");
  if (!d->landed) {
    d->setpoint = hold_;
    d->have_setpoint = true;
  }
}

void SimFc::telemetry(const sim::SimDrone& d, int64_t t, const Send& send) {
  const uint32_t boot_ms = static_cast<uint32_t>(t / 1000);
  if (t >= next_heartbeat_at_) {
    mav::Heartbeat hb;
    hb.type = mav::kMavTypeQuadrotor;
    hb.autopilot = mav::kMavAutopilotPx4;
    hb.base_mode = base_mode();
    hb.custom_mode = custom_mode();
    hb.system_status = armed_ ? mav::kMavStateActive : 3;  // MAV_STATE_ACTIVE / MAV_STATE_STANDBY
    send(encoder_.encode(hb));
    status_->count("fc_heartbeats_sent");
    while (next_heartbeat_at_ <= t) next_heartbeat_at_ += o_.heartbeat_period_us;
  }
  const auto at = [&](int64_t k) { return static_cast<int64_t>(std::llround(static_cast<double>(k) * 1e6 / o_.telemetry_rate_hz)); };
  if (t < at(telemetry_k_)) return;
  while (at(telemetry_k_) <= t) ++telemetry_k_;
  const sim::VioSample vio = sim::vio_sample(d);
  const mav::Vec3 p = mav::fi_to_ned({vio.position.x(), vio.position.y(), vio.position.z()});
  const mav::Vec3 v = mav::fi_to_ned({vio.velocity.x(), vio.velocity.y(), vio.velocity.z()});
  mav::LocalPositionNed lp;
  lp.time_boot_ms = boot_ms;
  lp.x = static_cast<float>(p.x);
  lp.y = static_cast<float>(p.y);
  lp.z = static_cast<float>(p.z);
  lp.vx = static_cast<float>(v.x);
  lp.vy = static_cast<float>(v.y);
  lp.vz = static_cast<float>(v.z);
  send(encoder_.encode(lp));
  const mav::Euler e = mav::attitude_fi_to_ned({vio.roll, vio.pitch, vio.yaw});
  mav::Attitude att;
  att.time_boot_ms = boot_ms;
  att.roll = static_cast<float>(e.roll);
  att.pitch = static_cast<float>(e.pitch);
  att.yaw = static_cast<float>(e.yaw);
  // Body rates: roll / pitch from the change of the FLU angles since the last sample (small
  // angles: Euler rates ~ body rates), FRD = (x, -y, -z) of FLU; yaw from the dynamics.
  if (have_last_att_ && t > last_att_t_) {
    const double dt = (t - last_att_t_) * 1e-6;
    att.rollspeed = static_cast<float>((vio.roll - last_roll_) / dt);
    att.pitchspeed = static_cast<float>(-(vio.pitch - last_pitch_) / dt);
  }
  att.yawspeed = static_cast<float>(mav::yaw_rate_fi_to_ned(d.landed ? 0.0 : d.yaw_rate));
  have_last_att_ = true;
  last_roll_ = vio.roll;
  last_pitch_ = vio.pitch;
  last_att_t_ = t;
  send(encoder_.encode(att));
  status_->count("fc_telemetry_sent");
}

// ------------------------------------------------------------------------------- FcPort

FcPort::FcPort(const std::string& bind_addr, int port) : buf_(65536) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(port));
  text_ = bind_addr + ":" + std::to_string(port);
  if (port < 1 || port > 65535 || ::inet_pton(AF_INET, bind_addr.c_str(), &a.sin_addr) != 1)
    throw SocketError("bad UDP address " + text_ + " (expected an IPv4 address and a port 1..65535)");
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw SocketError("cannot open a UDP socket: " + std::string(std::strerror(errno)));
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    const std::string why = std::strerror(errno);
    ::close(fd_);
    fd_ = -1;
    throw SocketError("cannot bind UDP " + text_ + ": " + why);
  }
}

FcPort::~FcPort() {
  if (fd_ >= 0) ::close(fd_);
}

bool FcPort::drain(const std::function<void(const uint8_t*, std::size_t)>& on_data, app::Status* status,
                   const app::Log& log, int drone_id, std::string* error) {
  // At most this many datagrams per call, so a flood cannot stall the simulation.
  for (int i = 0; i < 1000; ++i) {
    sockaddr_in src{};
    socklen_t len = sizeof src;
    const ssize_t n = ::recvfrom(fd_, buf_.data(), buf_.size(), 0, reinterpret_cast<sockaddr*>(&src), &len);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) return true;
      if (errno == EINTR || errno == ECONNREFUSED) continue;
      *error = "recvfrom on UDP " + text_ + ": " + std::strerror(errno);
      return false;
    }
    if (!have_peer_) {
      peer_ = src;
      have_peer_ = true;
      log.event("drone " + std::to_string(drone_id) + " FC: peer " + address(src) + " (first datagram on " + text_ +
                "); sending to it");
    } else if (src.sin_addr.s_addr != peer_.sin_addr.s_addr || src.sin_port != peer_.sin_port) {
      app::count_and_log(*status, log, "fc_foreign_peer",
                         "drone " + std::to_string(drone_id) + " FC: datagram from " + address(src) + " dropped (the peer is " +
                             address(peer_) + ")");
      continue;
    }
    on_data(buf_.data(), static_cast<std::size_t>(n));
  }
  return true;
}

void FcPort::send(const std::vector<uint8_t>& bytes, app::Status* status, const app::Log& log) {
  if (!have_peer_) return;
  const ssize_t n = ::sendto(fd_, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&peer_), sizeof peer_);
  if (n != static_cast<ssize_t>(bytes.size()))
    app::count_and_log(*status, log, "fc_send_failed",
                       "sendto " + address(peer_) + " from " + text_ + ": " + (n < 0 ? std::strerror(errno) : "short write"));
}

}  // namespace fact::sim_fc
