// fact_fc_bridge_peer: drives fact-fc-bridge for the node-mavlink decode test and the benchmark.
//   - LCM: publishes a fixed setpoint (plus, once each, a NaN setpoint, one outside the default
//     geofence and one of another drone, which must never reach the wire) and odometry samples
//     whose values follow from the sample index k (the decoder recomputes them):
//       utime = 1e9 + 10000 k µs; seq = k (k < 100), k - 100 after (a VIO reset at k = 100);
//       position = (0.01 k, 1 - 0.02 k, 1.5) m, velocity = (0.3, -0.2, 0.05) m/s (f_i);
//       yaw = 0.2 + 0.001 k, roll = 0.05, pitch = -0.03 rad.
//     The setpoint: position (1, 2, 3) m, velocity (0.5, -0.25, 0.1) m/s, acceleration
//     (0.1, 0.2, -0.3) m/s², yaw 0.3 rad, yaw_rate 0.1 rad/s (f_i).
//   - A fake flight controller on UDP 127.0.0.1:--fc-port: HEARTBEAT (PX4, quadrotor, disarmed,
//     not offboard) at 5 Hz to the bridge's port; everything the bridge sends is appended to
//     --capture FILE.
// Runs for --duration seconds. Exit 0, or 1 when LCM or the socket fails.
#include "common/app.h"
#include "fact/mavlink.h"
#include "fact/odometry_t.hpp"
#include "fact/setpoint_t.hpp"

#include <CLI/CLI.hpp>
#include <arpa/inet.h>
#include <lcm/lcm-cpp.hpp>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <string>
#include <thread>

namespace mav = fact::mavlink;

namespace {

int64_t mono_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

fact::setpoint_t fixed_setpoint(int drone_id) {
  fact::setpoint_t s{};
  s.utime = 0;
  s.drone_id = drone_id;
  const double p[3] = {1, 2, 3}, v[3] = {0.5, -0.25, 0.1}, a[3] = {0.1, 0.2, -0.3};
  for (int i = 0; i < 3; ++i) {
    s.position[i] = p[i];
    s.velocity[i] = v[i];
    s.acceleration[i] = a[i];
  }
  s.yaw = 0.3;
  s.yaw_rate = 0.1;
  return s;
}

fact::odometry_t odometry_sample(int drone_id, int64_t k) {
  fact::odometry_t o{};
  o.utime = 1000000000 + 10000 * k;
  o.drone_id = drone_id;
  o.seq = k < 100 ? k : k - 100;
  o.position[0] = 0.01 * static_cast<double>(k);
  o.position[1] = 1 - 0.02 * static_cast<double>(k);
  o.position[2] = 1.5;
  o.velocity[0] = 0.3;
  o.velocity[1] = -0.2;
  o.velocity[2] = 0.05;
  o.yaw = 0.2 + 0.001 * static_cast<double>(k);
  o.roll = 0.05;
  o.pitch = -0.03;
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  std::string lcm_url, capture;
  int drone_id = 0, fc_port = 14601, bridge_port = 14600;
  double duration = 3, setpoint_rate = 20, odometry_rate = 50;
  CLI::App app{"LCM publisher and fake flight controller for fact-fc-bridge tests", "fact_fc_bridge_peer"};
  app.add_option("--lcm-url", lcm_url)->required();
  app.add_option("--drone-id", drone_id);
  app.add_option("--fc-port", fc_port, "UDP port of the fake FC on 127.0.0.1");
  app.add_option("--bridge-port", bridge_port, "the bridge's UDP port on 127.0.0.1");
  app.add_option("--capture", capture, "append the bridge's bytes to FILE");
  app.add_option("--duration", duration, "s");
  app.add_option("--setpoint-rate", setpoint_rate, "Hz");
  app.add_option("--odometry-rate", odometry_rate, "Hz");
  CLI11_PARSE(app, argc, argv);

  lcm::LCM lcm(lcm_url);
  if (!lcm.good()) {
    std::cerr << "peer: cannot open LCM " << lcm_url << "\n";
    return 1;
  }
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK, 0);
  sockaddr_in local{}, bridge{};
  local.sin_family = bridge.sin_family = AF_INET;
  local.sin_addr.s_addr = bridge.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  local.sin_port = htons(static_cast<uint16_t>(fc_port));
  bridge.sin_port = htons(static_cast<uint16_t>(bridge_port));
  if (fd < 0 || ::bind(fd, reinterpret_cast<sockaddr*>(&local), sizeof local) != 0) {
    std::perror("peer: UDP bind");
    return 1;
  }
  std::FILE* out = capture.empty() ? nullptr : std::fopen(capture.c_str(), "ab");

  mav::Encoder fc({1, mav::kCompIdAutopilot});
  mav::Heartbeat hb;
  hb.type = mav::kMavTypeQuadrotor;
  hb.autopilot = mav::kMavAutopilotPx4;
  hb.base_mode = mav::kModeFlagCustomModeEnabled;
  hb.custom_mode = 0x00030000;  // PX4 main mode POSCTL: not offboard
  hb.system_status = 3;         // MAV_STATE_STANDBY

  const std::string sp_channel = "FACT_SETPOINT_" + std::to_string(drone_id);
  const std::string od_channel = "FACT_ODOMETRY_" + std::to_string(drone_id);
  const int64_t start = mono_us(), end = start + static_cast<int64_t>(duration * 1e6);
  const int64_t sp_period = static_cast<int64_t>(1e6 / setpoint_rate), od_period = static_cast<int64_t>(1e6 / odometry_rate);
  int64_t next_hb = start, next_sp = start, next_od = start + 2000;
  int64_t k = 0, sp_count = 0;
  uint8_t buf[2048];
  while (mono_us() < end) {
    const int64_t now = mono_us();
    if (now >= next_hb) {
      const auto bytes = fc.encode(hb);
      ::sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<sockaddr*>(&bridge), sizeof bridge);
      next_hb += 200000;
    }
    if (now >= next_sp) {
      fact::setpoint_t s = fixed_setpoint(drone_id);
      s.utime = fact::app::now_us();  // stamped on the wall clock, as the planner does (the bridge checks it)
      if (sp_count == 10) s.position[1] = std::numeric_limits<double>::quiet_NaN();  // must be rejected
      if (sp_count == 11) s.position[2] = 80;                                           // outside the geofence
      if (sp_count == 12) s.drone_id = drone_id + 1;                                    // another drone
      lcm.publish(sp_channel, &s);
      ++sp_count;
      next_sp += sp_period;
    }
    if (now >= next_od) {
      const fact::odometry_t o = odometry_sample(drone_id, k++);
      lcm.publish(od_channel, &o);
      next_od += od_period;
    }
    for (;;) {
      const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
      if (n <= 0) break;
      if (out) std::fwrite(buf, 1, static_cast<std::size_t>(n), out);
    }
    std::this_thread::sleep_for(std::chrono::microseconds(1000));
  }
  if (out) std::fclose(out);
  std::cerr << "peer: published " << sp_count << " setpoints and " << k << " odometry samples\n";
  ::close(fd);
  return 0;
}
