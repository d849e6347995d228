// The core of fact-fc-bridge, free of sockets: LCM setpoints / odometry in, MAVLink frames out
// through a send callback; the flight controller's bytes in, fact::fc_state_t out.
#pragma once

#include "common/app.h"
#include "fact/fc_state_t.hpp"
#include "fact/mavlink.h"
#include "fact/odometry_t.hpp"
#include "fact/setpoint_t.hpp"

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace fact::bridge {

// Largest |value| forwarded to the flight controller, in the field's unit (m, m/s, m/s², rad,
// rad/s), for setpoints, odometry and the geofence's bounds: far beyond any drone's, and held by a
// float to 0.06. MAVLink carries floats, and a double that is finite but beyond a float's range
// (1e39) would reach the flight controller as ±inf (review, session 30).
constexpr double kLargestValue = 1e6;

// Setpoints outside this box (m, in f_i) are rejected.
struct Geofence {
  std::array<double, 3> min{-50, -50, -1};
  std::array<double, 3> max{50, 50, 20};
};

struct BridgeOptions {
  int drone_id = 0;
  mavlink::Endpoint self{1, mavlink::kCompIdOnboardComputer};  // our sysid / compid
  uint8_t target_system = 1;            // the flight controller's sysid
  uint8_t target_component = 1;         // and compid (MAV_COMP_ID_AUTOPILOT1)
  double stream_rate_hz = 50;           // setpoint stream rate (PX4 needs > 2 Hz)
  int64_t setpoint_timeout_us = 500000; // a setpoint older than this stops the stream
  // > 0: a setpoint stamped (utime) further than this from the app's clock when it arrives is
  // refused (rejected_stale): a replayed log's or a stuck publisher's. 0: not checked (fact-fc-bridge
  // sets setpoint_timeout_us, or 0 with --sim-clock, where the stamps are simulated time).
  int64_t max_stamp_skew_us = 0;
  int64_t heartbeat_timeout_us = 3000000;  // an FC heartbeat older than this stops the stream
  Geofence fence;
  bool arm = false;                     // send MAV_CMD_COMPONENT_ARM_DISARM(1)
  bool offboard = false;                // send MAV_CMD_DO_SET_MODE(custom, OFFBOARD)
  int command_tries = 5;                // give up after this many rounds of commands
  int64_t command_after_us = 1000000;   // setpoints must have streamed this long first
  int64_t command_interval_us = 1000000;  // between rounds of commands
  double state_rate_hz = 10;            // fc_state publication rate
};

// Every `now` is µs on one clock that does not jump (fact::app::monotonic_us in fact-fc-bridge):
// the stream's stop rules and schedules are differences on it. state()'s utime is that clock's;
// the app stamps fc_state with its wall clock when it publishes.
class Bridge {
 public:
  using Send = std::function<void(const std::vector<uint8_t>&)>;
  using PublishState = std::function<void(const fact::fc_state_t&)>;

  Bridge(const BridgeOptions& o, Send send, PublishState publish, app::Status* status, const app::Log& log);

  // stamp_clock: the app's clock (µs, fact::app::now_us) that setpoints are stamped on.
  void on_setpoint(const fact::setpoint_t& sp, const std::string& channel, int64_t now, int64_t stamp_clock);
  void on_odometry(const fact::odometry_t& od, const std::string& channel, int64_t now);
  // `datagram`: the bytes are one whole UDP datagram (MAVLink over UDP never splits a frame).
  void on_fc_bytes(const uint8_t* data, std::size_t n, int64_t now, bool datagram);
  // Heartbeat (1 Hz), the setpoint stream, arm / offboard commands, fc_state. Call often.
  void tick(int64_t now);
  // µs until tick() has something to do (>= 0).
  int64_t wait_us(int64_t now) const;

  bool streaming() const { return why_ == Why::streaming; }
  fact::fc_state_t state(int64_t now) const;

 private:
  enum class Why { streaming, no_setpoint, setpoint_stale, no_heartbeat, heartbeat_lost };

  void reject(const std::string& counter, const std::string& why);
  std::string check_setpoint(const fact::setpoint_t& sp, std::string* counter) const;
  void on_frame(const mavlink::Frame& f, int64_t now);
  void on_heartbeat(const mavlink::Heartbeat& hb, int64_t now);
  void update_stream_state(int64_t now);
  std::string reason_text(int64_t now) const;
  void send_heartbeat(int64_t now);
  void send_setpoint(int64_t now);
  void send_commands(int64_t now);
  void send_command(uint16_t command, float p1, float p2);
  void publish_state(int64_t now);
  uint32_t boot_ms(int64_t now) const;

  BridgeOptions o_;
  Send send_;
  PublishState publish_;
  app::Status* status_;
  app::Log log_;
  mavlink::Encoder encoder_;
  mavlink::Parser parser_;
  int64_t start_us_ = -1;

  // Setpoint stream.
  bool have_setpoint_ = false;
  fact::setpoint_t setpoint_{};
  int64_t setpoint_at_ = 0;  // receive time of the newest valid setpoint
  int64_t stream_period_us_;
  int64_t next_setpoint_at_ = 0;
  int64_t streaming_since_ = 0;
  Why why_ = Why::no_setpoint;

  // Odometry.
  bool have_odometry_seq_ = false;
  int64_t last_odometry_seq_ = 0;
  int64_t last_odometry_utime_ = 0;
  uint8_t reset_counter_ = 0;

  // Flight controller.
  bool fc_seen_ = false;
  int64_t fc_heartbeat_at_ = 0;
  mavlink::Heartbeat fc_heartbeat_{};
  bool position_valid_ = false, attitude_valid_ = false;
  int64_t position_at_ = 0, attitude_at_ = 0;
  mavlink::LocalPositionNed position_{};
  mavlink::Attitude attitude_{};

  // Commands.
  int command_rounds_ = 0;
  int64_t last_command_at_ = 0;
  bool commands_done_ = false;          // the FC showed the requested state once: no more requests
  bool left_state_logged_ = false;      // ... and it left that state since (a pilot's decision)

  int64_t next_heartbeat_at_ = 0;
  int64_t next_state_at_ = 0;
  int64_t setpoints_sent_ = 0, odometry_sent_ = 0;
  bool last_connected_ = false, last_armed_ = false, last_offboard_ = false;
};

}  // namespace fact::bridge
