// The simulated flight controller of fact-sim (--mavlink-port): one per drone, speaking the same
// MAVLink v2 (fact_mavlink) as a real PX4 over UDP, so the simulated loop is
//   planner -> fact-fc-bridge -> MAVLink -> this FC -> the drone's dynamics (lib/sim).
// It lives on the PX4 side of the frame boundary: its local NED frame is the NED of the drone's
// f_i (what PX4's EKF2 estimates from the ODOMETRY the bridge forwards), and it converts with
// fact/mavlink_frames.h only.
//
// A minimal PX4 model:
//   - modes: POSCTL (main 3, the start), OFFBOARD (main 6), AUTO.LOITER (main 4, sub 3: hold);
//     HEARTBEAT custom_mode = main << 16 | sub << 24, base_mode = CUSTOM_MODE_ENABLED | ARMED.
//   - COMMAND_LONG MAV_CMD_DO_SET_MODE (176): param1 must have CUSTOM_MODE_ENABLED, param2 the
//     main mode (3, 4 with param3 = 3, or 6). OFFBOARD only while setpoints are fresh
//     (one within the offboard timeout), as PX4 demands. Others are denied.
//   - MAV_CMD_COMPONENT_ARM_DISARM (400): param1 1 arms, 0 disarms; disarming only on the ground
//     (no forced disarm in the air: motors off is not modelled). There is no COMMAND_ACK (not in
//     fact_mavlink): the result shows in the HEARTBEAT.
//   - SET_POSITION_TARGET_LOCAL_NED (84), MAV_FRAME_LOCAL_NED only, type_mask honoured per axis
//     (see SimFc::control). Setpoints drive the drone only when armed and in OFFBOARD; armed in
//     another mode it holds its position (a landed drone stays landed).
//   - Offboard-loss failsafe: in OFFBOARD, no setpoint for longer than the offboard timeout
//     (0.5 s of sim time) -> the drone holds its position, the HEARTBEAT reports AUTO.LOITER, a
//     log line says why. Fresh setpoints clear it (back to OFFBOARD).
//   - Not modelled: COMMAND_ACK, auto-disarm, RC, geofence, land detector beyond "on the floor".
#pragma once

#include "common/app.h"
#include "fact/mavlink.h"
#include "fact/sim_dynamics.h"

#include <netinet/in.h>

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace fact::sim_fc {

// PX4 custom main / sub modes used here.
constexpr uint32_t kMainPosctl = 3;
constexpr uint32_t kMainAuto = 4;
constexpr uint32_t kSubAutoLoiter = 3;
constexpr uint32_t kMainOffboard = 6;

// POSITION_TARGET_TYPEMASK bits (set = ignore the field).
constexpr uint16_t kIgnoreX = 1, kIgnoreY = 2, kIgnoreZ = 4;
constexpr uint16_t kIgnoreVx = 8, kIgnoreVy = 16, kIgnoreVz = 32;
constexpr uint16_t kIgnoreAx = 64, kIgnoreAy = 128, kIgnoreAz = 256;
constexpr uint16_t kForceSet = 512, kIgnoreYaw = 1024, kIgnoreYawRate = 2048;

struct FcOptions {
  uint8_t sysid = 1;                       // the bridge's --target-system default
  uint8_t compid = mavlink::kCompIdAutopilot;  // the bridge's --target-component default
  double telemetry_rate_hz = 30;           // LOCAL_POSITION_NED + ATTITUDE (sim time)
  int64_t heartbeat_period_us = 1000000;   // HEARTBEAT at 1 Hz (sim time)
  int64_t offboard_timeout_us = 500000;    // offboard-loss failsafe after this long without a setpoint
  bool auto_arm = false;                   // start armed in OFFBOARD (--fc-auto-arm)
};

// One drone's flight controller: bytes in, control, bytes out. No I/O; times are sim µs.
// Counters (prefix fc_) go to the shared status, events to the log (rejections rate-limited).
class SimFc {
 public:
  using Send = std::function<void(const std::vector<uint8_t>&)>;

  SimFc(int drone_id, const FcOptions& o, app::Status* status, const app::Log* log);

  // Bytes from the peer (the bridge) received at sim time t. `drone` is read for the ground test
  // of a disarm command.
  void on_bytes(const uint8_t* data, std::size_t n, const sim::SimDrone& drone, int64_t t);

  // Before each physics step: sets the drone's setpoint as the mode demands. Following a
  // setpoint, each axis takes (f_i, converted from NED):
  //   position used -> position; ignored -> the current VIO position (no position error);
  //   velocity used -> feed-forward; ignored -> 0 with the position used, else the current VIO
  //     velocity (no velocity error: acceleration only);
  //   acceleration used -> feed-forward; ignored -> 0;
  //   yaw ignored -> the current VIO yaw; yaw rate ignored -> 0.
  // Holding (armed, not following): the VIO position and yaw captured when the hold began.
  void control(sim::SimDrone* drone, int64_t t);

  // Sends what is due at sim time t: HEARTBEAT (1 Hz), LOCAL_POSITION_NED and ATTITUDE
  // (telemetry rate) from the drone's VIO, in the NED of f_i.
  void telemetry(const sim::SimDrone& drone, int64_t t, const Send& send);

  bool armed() const { return armed_; }
  bool failsafe() const { return failsafe_; }
  uint32_t custom_mode() const;  // as reported in the HEARTBEAT
  uint8_t base_mode() const;

 private:
  enum class Activity { idle, following, holding };
  struct Target {
    sim::Setpoint sp;                        // f_i
    bool pos[3], vel[3], acc[3];             // used, per f_i axis
    bool yaw = true, yaw_rate = true;
  };

  void on_frame(const mavlink::Frame& f, const sim::SimDrone& drone, int64_t t);
  void on_setpoint(const mavlink::SetPositionTargetLocalNed& m, int64_t t);
  void on_command(const mavlink::CommandLong& c, const sim::SimDrone& drone, int64_t t);
  bool for_us(uint8_t system, uint8_t component) const;
  void reject(const std::string& counter, const std::string& why);
  void event(const std::string& line) const;
  bool setpoint_fresh(int64_t t) const { return have_target_ && t - target_at_ <= o_.offboard_timeout_us; }

  int id_;
  FcOptions o_;
  app::Status* status_;
  const app::Log* log_;
  mavlink::Parser parser_;
  mavlink::Encoder encoder_;

  bool armed_ = false;
  uint32_t main_mode_ = kMainPosctl, sub_mode_ = 0;  // the selected mode
  bool failsafe_ = false;
  Target target_;
  bool have_target_ = false;
  int64_t target_at_ = 0;
  Activity activity_ = Activity::idle;
  sim::Setpoint hold_;

  int64_t next_heartbeat_at_ = 0;
  int64_t telemetry_k_ = 0;
  bool have_last_att_ = false;
  double last_roll_ = 0, last_pitch_ = 0;
  int64_t last_att_t_ = 0;
};

// A socket failure (bind, bad address): fact-sim exits 1.
struct SocketError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The UDP socket a SimFc talks through: bound at ADDR:PORT, non-blocking. Like PX4 SITL, it
// learns its peer from the first datagram it receives and sends only to it; datagrams from other
// addresses are dropped and counted (fc_foreign_peer).
class FcPort {
 public:
  FcPort(const std::string& bind_addr, int port);  // throws SocketError
  ~FcPort();
  FcPort(const FcPort&) = delete;
  FcPort& operator=(const FcPort&) = delete;

  // Reads every pending datagram without blocking; on_data for those from the peer. Returns false
  // (with *error) when the socket failed.
  bool drain(const std::function<void(const uint8_t*, std::size_t)>& on_data, app::Status* status,
             const app::Log& log, int drone_id, std::string* error);
  // Sends to the peer (nothing before one is known). Failures counted (fc_send_failed).
  void send(const std::vector<uint8_t>& bytes, app::Status* status, const app::Log& log);
  bool has_peer() const { return have_peer_; }
  std::string describe() const { return text_; }

 private:
  int fd_ = -1;
  std::string text_;
  sockaddr_in peer_{};
  bool have_peer_ = false;
  std::vector<uint8_t> buf_;
};

}  // namespace fact::sim_fc
