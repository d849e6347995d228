// fact-fc-bridge: one drone's link to its flight controller (PX4) over MAVLink v2.
//   in:  fact::setpoint_t on FACT_SETPOINT_<id> (f_i, ENU-like FLU), fact::odometry_t on
//        FACT_ODOMETRY_<id>; the FC's HEARTBEAT, LOCAL_POSITION_NED, ATTITUDE.
//   out: HEARTBEAT (1 Hz), SET_POSITION_TARGET_LOCAL_NED (MAV_FRAME_LOCAL_NED, --stream-rate)
//        while the setpoint and the FC heartbeat are fresh, ODOMETRY (#331) per odometry sample,
//        COMMAND_LONG arm / offboard only with --arm / --offboard; fact::fc_state_t on
//        FACT_FC_STATE_<id>, counters on FACT_STATUS.
// The FLU <-> NED conventions are in firmware_bridge/include/fact/mavlink_frames.h.
// Exit codes: 0 stopped by SIGINT/SIGTERM; 1 LCM or link failure; 2 bad flags.
#include "bridge.h"
#include "common/app.h"
#include "common/flags.h"
#include "link.h"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <poll.h>
#include <sys/resource.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace {

constexpr const char* kApp = "fact-fc-bridge";
using fact::app::FlagError;

// Every parameter of the app, with its unit.
struct Options {
  fact::app::CommonFlags common;        // --drone-id (default 0), --lcm-url, status, --sim-clock
  std::string udp;                      // LOCAL_PORT:REMOTE_HOST:REMOTE_PORT
  std::string serial;                   // device path
  int baud = 921600;                    // serial rate, bit/s
  int sysid = 1, compid = 191;          // our MAVLink ids
  int target_system = 1, target_component = 1;  // the flight controller's
  double stream_rate = 50;              // Hz
  double setpoint_timeout = 0.5;        // s
  double heartbeat_timeout = 3.0;       // s
  std::string geofence = "-50,50,-50,50,-1,20";  // m, f_i: XMIN,XMAX,YMIN,YMAX,ZMIN,ZMAX
  bool arm = false, offboard = false;
  int command_tries = 5;
  double state_rate = 10;               // Hz
  std::string setpoint_channel, odometry_channel, state_channel;
  std::string dump;                     // file: every byte sent to the FC is appended
};

void add_flags(CLI::App& app, Options& o) {
  o.common.drone_id = 0;
  fact::app::add_common_flags(app, &o.common, fact::app::DroneIdFlag::optional);
  app.add_option("--udp", o.udp, "MAVLink over UDP: bind LOCAL_PORT, send to REMOTE_HOST:REMOTE_PORT (PX4 SITL: 14540:127.0.0.1:14580); "
                 "only datagrams from REMOTE_HOST:REMOTE_PORT are read (others: foreign_datagrams)")
      ->type_name("LOCAL_PORT:REMOTE_HOST:REMOTE_PORT");
  app.add_option("--serial", o.serial, "MAVLink over a serial port (raw 8N1)")->type_name("DEVICE");
  app.add_option("--baud", o.baud, "Serial rate in bit/s (" + fact::bridge::supported_bauds() + ")")->capture_default_str()
      ->check(fact::app::decimal_integer());
  app.add_option("--sysid", o.sysid, "Our MAVLink system id (1..255)")->capture_default_str()
      ->check(fact::app::decimal_integer());
  app.add_option("--compid", o.compid, "Our MAVLink component id (1..255; 191 = ONBOARD_COMPUTER)")->capture_default_str()
      ->check(fact::app::decimal_integer());
  app.add_option("--target-system", o.target_system, "The flight controller's system id (1..255)")->capture_default_str()
      ->check(fact::app::decimal_integer());
  app.add_option("--target-component", o.target_component, "The flight controller's component id (1..255)")->capture_default_str()
      ->check(fact::app::decimal_integer());
  app.add_option("--stream-rate", o.stream_rate, "Setpoint stream rate in Hz (PX4 needs > 2 Hz; at most 500)")->capture_default_str();
  app.add_option("--setpoint-timeout", o.setpoint_timeout, "s (0.01..60): an older setpoint stops the stream")->capture_default_str();
  app.add_option("--heartbeat-timeout", o.heartbeat_timeout, "s (0.01..60): an older FC heartbeat stops the stream")->capture_default_str();
  app.add_option("--geofence", o.geofence, "Setpoint box in f_i, m: XMIN,XMAX,YMIN,YMAX,ZMIN,ZMAX")->capture_default_str();
  app.add_flag("--arm", o.arm, "Request arming (COMMAND_LONG 400) once setpoints have streamed for 1 s");
  app.add_flag("--offboard", o.offboard, "Request PX4 OFFBOARD mode (COMMAND_LONG 176) once setpoints have streamed for 1 s");
  app.add_option("--command-tries", o.command_tries, "Arm / offboard requests: rounds (1 s apart) before giving up")->capture_default_str()
      ->check(fact::app::decimal_integer());
  app.add_option("--state-rate", o.state_rate, "fc_state publication rate in Hz (0.01..100)")->capture_default_str();
  app.add_option("--setpoint-channel", o.setpoint_channel, "Input (default FACT_SETPOINT_<id>)")->type_name("CHANNEL");
  app.add_option("--odometry-channel", o.odometry_channel, "Input (default FACT_ODOMETRY_<id>)")->type_name("CHANNEL");
  app.add_option("--state-channel", o.state_channel, "Output (default FACT_FC_STATE_<id>)")->type_name("CHANNEL");
  app.add_option("--dump", o.dump, "Append every byte sent to the flight controller to FILE")->type_name("FILE");
  app.footer(
      "Frames: f_i is taken as ENU-like (x east, y north, z up), MAVLink local NED = (y, x, -z),\n"
      "yaw_ned = pi/2 - yaw; body FLU -> FRD = (x, -y, -z). ODOMETRY: frame LOCAL_NED, child frame\n"
      "BODY_FRD (velocity rotated into the body), covariances unknown (NaN), estimator VIO.\n"
      "Setpoints stream only while the newest valid setpoint and the FC heartbeat are fresh; then\n"
      "the bridge stops sending so that PX4's offboard-loss failsafe engages, and logs why.\n"
      "Rejected (counted on FACT_STATUS, logged, never sent): NaN/inf, |value| > 1e6, outside the\n"
      "geofence, another drone's id, undecodable LCM; malformed MAVLink and NaN/inf values from the\n"
      "FC counted by reason, UDP datagrams from another address or port than the FC's ignored.\n"
      "Exit codes: 0 stopped by SIGINT/SIGTERM; 1 LCM or link failure; 2 bad flags.");
}

void check_id(const char* flag, int v) {
  if (v < 1 || v > 255) throw FlagError(std::string(flag) + ": expected 1..255, got " + std::to_string(v));
}

fact::bridge::Geofence parse_geofence(const std::string& text) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, ',')) {
    std::size_t used = 0;
    double d = NAN;
    try {
      d = std::stod(part, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != part.size() || part.empty() || !std::isfinite(d))
      throw FlagError("--geofence: '" + part + "' in '" + text + "' is not a finite number");
    if (std::abs(d) > fact::bridge::kLargestValue)
      throw FlagError("--geofence: '" + part + "' in '" + text + "' is beyond ±1e+06 m");
    v.push_back(d);
  }
  // (getline yields no field after a trailing comma, which "1,2,3,4,5,6," slipped through)
  if (v.size() != 6 || text.back() == ',')
    throw FlagError("--geofence: expected 6 numbers XMIN,XMAX,YMIN,YMAX,ZMIN,ZMAX, got '" + text + "'");
  fact::bridge::Geofence g;
  for (int i = 0; i < 3; ++i) {
    g.min[i] = v[2 * i];
    g.max[i] = v[2 * i + 1];
    if (!(g.min[i] < g.max[i])) throw FlagError("--geofence: min >= max on axis " + std::to_string(i) + " in '" + text + "'");
  }
  return g;
}

fact::bridge::BridgeOptions check(Options& o) {
  fact::app::check_common_flags(o.common, fact::app::DroneIdFlag::optional);
  if (o.udp.empty() == o.serial.empty()) throw FlagError("give exactly one of --udp and --serial");
  if (!o.serial.empty()) {
    try {
      fact::bridge::check_baud(o.baud);
    } catch (const fact::bridge::LinkSpecError& e) {
      throw FlagError(e.what());
    }
  }
  if (!o.udp.empty()) {
    try {
      fact::bridge::parse_udp_spec(o.udp);
    } catch (const fact::bridge::LinkSpecError& e) {
      throw FlagError(e.what());
    }
  }
  check_id("--sysid", o.sysid);
  check_id("--compid", o.compid);
  check_id("--target-system", o.target_system);
  check_id("--target-component", o.target_component);
  fact::app::check_positive("--stream-rate", o.stream_rate);
  if (o.stream_rate <= 2 || o.stream_rate > 500)
    throw FlagError("--stream-rate: expected more than 2 Hz (PX4's offboard minimum) and at most 500, got " + std::to_string(o.stream_rate));
  // Timeouts below 10 ms stop the stream between two setpoints; beyond a minute they stream a
  // dead planner's setpoint that long. A state rate above 100 Hz floods the bus and, like a rate
  // whose period rounds to 0 µs, keeps the loop busy (review, session 30).
  fact::app::check_range("--setpoint-timeout", o.setpoint_timeout, 0.01, 60, "s");
  fact::app::check_range("--heartbeat-timeout", o.heartbeat_timeout, 0.01, 60, "s");
  fact::app::check_range("--state-rate", o.state_rate, 0.01, 100, "Hz");
  if (o.command_tries < 1) throw FlagError("--command-tries: expected >= 1, got " + std::to_string(o.command_tries));
  const int id = o.common.drone_id;
  if (o.setpoint_channel.empty()) o.setpoint_channel = fact::app::channel("FACT_SETPOINT", id);
  if (o.odometry_channel.empty()) o.odometry_channel = fact::app::channel("FACT_ODOMETRY", id);
  if (o.state_channel.empty()) o.state_channel = fact::app::channel("FACT_FC_STATE", id);

  fact::bridge::BridgeOptions b;
  b.drone_id = id;
  b.self = {static_cast<uint8_t>(o.sysid), static_cast<uint8_t>(o.compid)};
  b.target_system = static_cast<uint8_t>(o.target_system);
  b.target_component = static_cast<uint8_t>(o.target_component);
  b.stream_rate_hz = o.stream_rate;
  b.setpoint_timeout_us = std::llround(o.setpoint_timeout * 1e6);
  // Setpoints stamped further from this clock than the timeout are refused, except in simulated
  // time (there a stamp's lag is real latency times the simulation's rate).
  b.max_stamp_skew_us = o.common.sim_clock ? 0 : b.setpoint_timeout_us;
  b.heartbeat_timeout_us = std::llround(o.heartbeat_timeout * 1e6);
  b.fence = parse_geofence(o.geofence);
  b.arm = o.arm;
  b.offboard = o.offboard;
  b.command_tries = o.command_tries;
  b.state_rate_hz = o.state_rate;
  return b;
}

// The LCM side: decodes inputs and hands them to the bridge.
class Inputs {
 public:
  Inputs(fact::bridge::Bridge& b, fact::app::Status& s, const fact::app::Log& l) : bridge_(b), status_(s), log_(l) {}
  void on_setpoint(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    fact::setpoint_t m;
    if (fact::app::decode(rbuf, channel, &m, &status_, log_))
      bridge_.on_setpoint(m, channel, fact::app::monotonic_us(), fact::app::now_us());
  }
  void on_odometry(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    fact::odometry_t m;
    if (fact::app::decode(rbuf, channel, &m, &status_, log_)) bridge_.on_odometry(m, channel, fact::app::monotonic_us());
  }

 private:
  fact::bridge::Bridge& bridge_;
  fact::app::Status& status_;
  const fact::app::Log& log_;
};

// Poll loop over the LCM socket and the link until a stop request or a failure (returns 1).
int run(lcm::LCM& lcm, fact::bridge::Link& link, fact::bridge::Bridge& bridge, fact::app::Status& status,
        const fact::app::Log& log) {
  std::vector<uint8_t> buf(65536);  // a whole UDP datagram (recvfrom drops what does not fit)
  while (!fact::app::stop_requested()) {
    // The bridge's timeouts and schedule run on the monotonic clock; the status stamps wall time.
    const int64_t now = fact::app::monotonic_us();
    bridge.tick(now);
    status.tick(fact::app::now_us());
    pollfd fds[2] = {{lcm.getFileno(), POLLIN, 0}, {link.fd(), POLLIN, 0}};
    const int timeout_ms = static_cast<int>((bridge.wait_us(now) + 999) / 1000);
    const int n = ::poll(fds, 2, timeout_ms);
    if (n < 0 && errno != EINTR) {
      log.event(std::string("error: poll failed: ") + std::strerror(errno));
      return 1;
    }
    if (n <= 0) continue;
    if (fds[0].revents & POLLIN) {
      if (lcm.handle() != 0) {
        log.event("error: LCM failed while handling a message");
        return 1;
      }
    }
    if (fds[1].revents & (POLLIN | POLLERR | POLLHUP)) {
      std::string error;
      const long got = link.receive(buf.data(), buf.size(), &error);
      if (got < 0) {
        log.event("error: " + error);
        return 1;
      }
      if (got > 0) bridge.on_fc_bytes(buf.data(), static_cast<std::size_t>(got), fact::app::monotonic_us(), link.datagrams());
      if (const std::string ignored = link.take_ignored(); !ignored.empty())
        fact::app::count_and_log(status, log, "foreign_datagrams", ignored);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  CLI::App app{"Sends one drone's LCM setpoints and odometry to its flight controller (PX4) as MAVLink v2\n"
               "over UDP or serial, and publishes what the flight controller reports.",
               kApp};
  add_flags(app, options);
  app.get_formatter()->column_width(40);
  fact::bridge::BridgeOptions bridge_options;
  if (const int code = fact::app::parse_flags(app, argc, argv, kApp, [&] { bridge_options = check(options); }); code >= 0) return code;

  const fact::app::Log log(kApp, options.common.drone_id);
  std::unique_ptr<fact::bridge::Link> link;
  try {
    link = options.udp.empty() ? fact::bridge::open_serial(options.serial, options.baud)
                               : fact::bridge::open_udp(fact::bridge::parse_udp_spec(options.udp));
  } catch (const std::exception& e) {
    log.event(std::string("error: ") + e.what());
    return 1;
  }
  std::FILE* dump = nullptr;
  if (!options.dump.empty()) {
    dump = std::fopen(options.dump.c_str(), "ab");
    if (!dump) {
      log.event("error: cannot open --dump file '" + options.dump + "': " + std::strerror(errno));
      return 1;
    }
  }
  lcm::LCM lcm(options.common.lcm_url);
  if (!fact::app::lcm_opened(lcm, options.common.lcm_url, log)) return 1;
  fact::app::install_stop_handler();
  if (!fact::app::start_clock(lcm, options.common, log)) return 1;

  fact::app::Status status(&lcm, options.common.status_channel, kApp, options.common.drone_id);
  status.set_period_us(std::llround(options.common.status_period * 1e6));
  auto send = [&](const std::vector<uint8_t>& bytes) {
    std::string error;
    if (!link->send(bytes, &error)) fact::app::count_and_log(status, log, "send_failed", "send failed: " + error);
    if (dump && (std::fwrite(bytes.data(), 1, bytes.size(), dump) != bytes.size() || std::fflush(dump) != 0))
      fact::app::count_and_log(status, log, "dump_failed",
                               "--dump: cannot write to '" + options.dump + "': " + std::strerror(errno));
  };
  auto publish = [&](const fact::fc_state_t& s) {  // stamped on the app clock (the bridge's is monotonic)
    fact::fc_state_t stamped = s;
    stamped.utime = fact::app::now_us();
    lcm.publish(options.state_channel, &stamped);
  };
  fact::bridge::Bridge bridge(bridge_options, send, publish, &status, log);
  status.count("foreign_datagrams", 0);
  if (dump) status.count("dump_failed", 0);
  Inputs inputs(bridge, status, log);
  lcm.subscribe(options.setpoint_channel, &Inputs::on_setpoint, &inputs);
  lcm.subscribe(options.odometry_channel, &Inputs::on_odometry, &inputs);
  log.event("MAVLink over " + link->describe() + "; sysid " + std::to_string(options.sysid) + " compid " +
            std::to_string(options.compid) + " -> FC " + std::to_string(options.target_system) + "/" +
            std::to_string(options.target_component) + "; setpoints " + options.setpoint_channel + ", odometry " +
            options.odometry_channel + ", state " + options.state_channel + (options.arm ? "; --arm" : "") +
            (options.offboard ? "; --offboard" : ""));
  const int64_t started = fact::app::monotonic_us();
  const int rc = run(lcm, *link, bridge, status, log);
  status.set_state(rc == 0 ? "stopped" : "failed");
  status.publish(fact::app::now_us());
  if (dump) std::fclose(dump);
  rusage use{};
  ::getrusage(RUSAGE_SELF, &use);
  const double cpu_s = use.ru_utime.tv_sec + use.ru_stime.tv_sec + 1e-6 * (use.ru_utime.tv_usec + use.ru_stime.tv_usec);
  const double wall_s = 1e-6 * static_cast<double>(fact::app::monotonic_us() - started);
  std::ostringstream line;
  line << (rc == 0 ? "stopped" : "exiting after a failure") << "; cpu_s=" << cpu_s << " wall_s=" << wall_s
       << " setpoints_sent=" << status.value("setpoints_sent") << " odometry_sent=" << status.value("odometry_sent");
  log.event(line.str());
  return rc;
}
