// fact-sim's simulated flight controllers (--mavlink-port) as real processes:
//   - the whole simulated loop: this test plays the planner (fact::setpoint_t on LCM along a
//     commanded trajectory, timed by the simulation clock) -> fact-fc-bridge (--arm --offboard,
//     --sim-clock) -> MAVLink v2 over UDP 127.0.0.1 -> fact-sim's FC -> dynamics; ground truth
//     (FACT_TRUTH) shows the trajectory flown, and stopping the setpoints makes the drone hover
//     (offboard-loss failsafe) where it was;
//   - this test as the bridge, raw MAVLink on UDP: HEARTBEAT fields, OFFBOARD refused without
//     setpoints, no motion while disarmed, arming, a velocity-only type_mask, the failsafe stopping
//     a velocity command that would otherwise fly on, and NaN / wrong frame / wrong target / bad
//     CRC / foreign peer rejected and counted;
//   - --fc-auto-arm; bad flags exit 2, a busy port exits 1.
//
// udpm must never leave the machine: main() re-executes this program through
// scripts/netns-run.sh (FACT_NETNS_RUN) unless only lo is visible. Paths come from
// FACT_SIM_BINARY, FACT_FC_BRIDGE_BINARY, FACT_NETNS_RUN.
#include "app_process.h"
#include "common/app.h"
#include "private_netns.h"
#include "test_time.h"
#include "fact/fc_state_t.hpp"
#include "fact/mavlink.h"
#include "fact/mavlink_frames.h"
#include "fact/odometry_t.hpp"
#include "fact/setpoint_t.hpp"
#include "fact/sim_clock_t.hpp"
#include "fact/truth_t.hpp"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
namespace mav = fact::mavlink;
constexpr double kPi = 3.14159265358979323846;
constexpr int64_t kEpoch = 1700000000000000LL;  // fact-sim's default --epoch-utime

using fact::test::only_loopback;

std::string url(int port) { return "udpm://239.255.76.67:" + std::to_string(port) + "?ttl=0"; }

double wall_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
// The wall time at which to give up waiting: `seconds` × FACT_TEST_TIME_SCALE from now.
double deadline_s(double seconds) { return wall_s() + fact::test::scaled_s(seconds); }

// Two drones, ids 2 and 3, at fixed starts with non-zero yaw (so f_i differs from the world), in
// an 8 x 8 x 3 m room without obstacles.
std::string write_world() {
  char tmpl[] = "/tmp/fact-simfc-world-XXXXXX";
  const int fd = mkstemp(tmpl);
  const std::string text =
      R"({"format": "fact-world-v1", "room": {"size": [8, 8, 3]},
          "drones": {"ids": [2, 3], "start": [{"position": [-1.5, -1.0, 0], "yaw": 0.6},
                                             {"position": [1.0, 1.5, 0], "yaw": -2.2}]}})";
  if (fd >= 0) {
    if (write(fd, text.data(), text.size()) != static_cast<ssize_t>(text.size())) std::perror("write world");
    close(fd);
  }
  return tmpl;
}

// A child process, stderr in a temporary file (removed with it), stdout discarded.
class Process : private fact::test::TempFile, public fact::test::AppProcess {
 public:
  Process(const std::string& binary, const std::vector<std::string>& args)
      : TempFile("fact-simfc-test"),
        AppProcess(fact::test::command_line(binary, args), "/dev/null", TempFile::path()) {}
  // The exit code once it exits (AppProcess::wait_for; −1 if it is still running after timeout_s).
  int wait(double timeout_s = 10) { return wait_s(timeout_s); }
  int stop() { return AppProcess::stop(SIGINT, std::chrono::seconds(10)); }
};

// LCM side: the simulation clock, ground truth, fc_state, both apps' status; relays the sim's raw
// VIO of `relay_id` to FACT_ODOMETRY_<id> (what fact-vio-relay does) so the bridge forwards ODOMETRY.
class Lcm {
 public:
  Lcm(const std::string& u, int relay_id) : lcm(u + "&recv_buf_size=2097152"), relay_id_(relay_id) {
    lcm.subscribe("FACT_SIM_CLOCK", &Lcm::on_clock, this);
    lcm.subscribe("FACT_TRUTH", &Lcm::on_truth, this)->setQueueCapacity(10000);
    lcm.subscribe("FACT_FC_STATE_.*", &Lcm::on_state, this)->setQueueCapacity(10000);
    lcm.subscribe("FACT_STATUS", &Lcm::on_status, this)->setQueueCapacity(10000);
    if (relay_id >= 0) lcm.subscribe("FACT_VIO_RAW_" + std::to_string(relay_id), &Lcm::on_vio, this)->setQueueCapacity(10000);
  }
  void on_clock(const lcm::ReceiveBuffer*, const std::string&, const fact::sim_clock_t* m) { sim_utime = std::max(sim_utime, m->utime); }
  void on_truth(const lcm::ReceiveBuffer*, const std::string&, const fact::truth_t* m) { truth.push_back(*m); }
  void on_state(const lcm::ReceiveBuffer*, const std::string&, const fact::fc_state_t* m) { states.push_back(*m); }
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const fact::app_status_t* m) {
    if (m->app == "fact-sim") sim_status = *m, have_sim_status = true;
    if (m->app == "fact-fc-bridge") bridge_status = *m, have_bridge_status = true;
  }
  void on_vio(const lcm::ReceiveBuffer*, const std::string&, const fact::odometry_t* m) {
    lcm.publish("FACT_ODOMETRY_" + std::to_string(relay_id_), m);
  }
  void pump(int timeout_ms = 1) {
    if (lcm.handleTimeout(timeout_ms) > 0)
      while (lcm.handleTimeout(0) > 0) {
      }
  }
  double sim_s() const { return sim_utime < 0 ? -1 : (sim_utime - kEpoch) * 1e-6; }
  static int64_t counter(const fact::app_status_t& s, const std::string& name) {
    return fact::app::counter_value(s, name).value_or(-1);
  }
  int64_t sim_counter(const std::string& name) const { return counter(sim_status, name); }
  int64_t bridge_counter(const std::string& name) const { return counter(bridge_status, name); }

  lcm::LCM lcm;
  int64_t sim_utime = -1;
  std::vector<fact::truth_t> truth;
  std::vector<fact::fc_state_t> states;
  fact::app_status_t sim_status, bridge_status;
  bool have_sim_status = false, have_bridge_status = false;

 private:
  int relay_id_;
};

struct V3 {
  double x = 0, y = 0, z = 0;
};
V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 operator*(double k, V3 a) { return {k * a.x, k * a.y, k * a.z}; }
double norm(V3 a) { return std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }

// A drone's truth sample: world position, and f_i -> world.
struct TruthOf {
  bool found = false;
  V3 p, origin;
  double frame_yaw = 0, yaw = 0;
  V3 to_world(V3 f) const {
    const double c = std::cos(frame_yaw), s = std::sin(frame_yaw);
    return {origin.x + c * f.x - s * f.y, origin.y + s * f.x + c * f.y, origin.z + f.z};
  }
};
TruthOf truth_of(const fact::truth_t& t, int id) {
  TruthOf r;
  for (int i = 0; i < t.num_drones; ++i) {
    const auto k = static_cast<size_t>(i);
    if (t.drone_ids[k] != id) continue;
    r.found = true;
    r.p = {t.position[k][0], t.position[k][1], t.position[k][2]};
    r.origin = {t.frame_origin[k][0], t.frame_origin[k][1], t.frame_origin[k][2]};
    r.frame_yaw = t.frame_yaw[k];
    r.yaw = t.yaw[k];
  }
  return r;
}

// The commanded trajectory (f_i), tau seconds after the FC reported armed + OFFBOARD:
//   [0, 2) take off to 1.2 m; [2, 3) hold; [3, 11) a 1 m square (4 sides of 2 s);
//   [11, 12) hold at (0, 0, 1.2); from 12 a 3 s line towards (1.5, 0, 1.2) (cut at 13.5).
// Each leg is a cosine blend (zero velocity at its ends), with velocity and acceleration
// feed-forward. Yaw 0.3 rad throughout.
struct Cmd {
  V3 p, v, a;
};
Cmd blend(V3 from, V3 to, double tau, double T) {
  const double u = std::clamp(tau / T, 0.0, 1.0);
  const double s = (1 - std::cos(kPi * u)) / 2, ds = kPi / (2 * T) * std::sin(kPi * u),
               dds = kPi * kPi / (2 * T * T) * std::cos(kPi * u);
  const V3 d = to - from;
  if (tau >= T) return {to, {}, {}};
  return {from + s * d, ds * d, dds * d};
}
constexpr double kHeight = 1.2, kYaw = 0.3, kStopTau = 13.5;
Cmd trajectory(double tau) {
  const V3 o{0, 0, 0}, h{0, 0, kHeight}, c1{1, 0, kHeight}, c2{1, 1, kHeight}, c3{0, 1, kHeight}, end{1.5, 0, kHeight};
  if (tau < 0) return {o, {}, {}};
  if (tau < 2) return blend(o, h, tau, 2);
  if (tau < 3) return {h, {}, {}};
  if (tau < 5) return blend(h, c1, tau - 3, 2);
  if (tau < 7) return blend(c1, c2, tau - 5, 2);
  if (tau < 9) return blend(c2, c3, tau - 7, 2);
  if (tau < 11) return blend(c3, h, tau - 9, 2);
  if (tau < 12) return {h, {}, {}};
  return blend(h, end, tau - 12, 3);
}

fact::setpoint_t to_setpoint(const Cmd& c, int id, int64_t utime) {
  fact::setpoint_t s{};
  s.utime = utime;
  s.drone_id = id;
  const V3* src[3] = {&c.p, &c.v, &c.a};
  double* dst[3] = {s.position, s.velocity, s.acceleration};
  for (int i = 0; i < 3; ++i) {
    dst[i][0] = src[i]->x;
    dst[i][1] = src[i]->y;
    dst[i][2] = src[i]->z;
  }
  s.yaw = kYaw;
  s.yaw_rate = 0;
  return s;
}

// The first "(x, y, z)" after `key` in text.
bool parse_triple(const std::string& text, const std::string& key, V3* out) {
  const auto at = text.find(key);
  if (at == std::string::npos) return false;
  return std::sscanf(text.c_str() + at + key.size(), " (%lf, %lf, %lf)", &out->x, &out->y, &out->z) == 3;
}

TEST(SimFc, BridgeLoopFliesACommandedSquareAndHoversWhenSetpointsStop) {
  ASSERT_TRUE(only_loopback());
  const std::string world = write_world();
  const int kId = 3, kBase = 15300;
  Lcm side(url(7831), kId);
  ASSERT_TRUE(side.lcm.good());
  Process sim(FACT_SIM_BINARY, {"--world", world, "--rate", "2", "--duration", "60", "--camera-rate", "1", "--truth-rate",
                                "50", "--seed", "5", "--mavlink-port", std::to_string(kBase), "--lcm-url", url(7831)});
  ASSERT_TRUE(sim.started());
  Process bridge(FACT_FC_BRIDGE_BINARY,
                 {"--drone-id", std::to_string(kId), "--lcm-url", url(7831), "--udp",
                  "15400:127.0.0.1:" + std::to_string(kBase + kId), "--sim-clock", "--arm", "--offboard",
                  "--status-period", "0.5"});
  ASSERT_TRUE(bridge.started());

  // Plays the planner: a setpoint every 40 ms of sim time (25 Hz), along trajectory(sim - T0)
  // where T0 is when the bridge's fc_state first shows armed + OFFBOARD; (0, 0, 0) before.
  double t0 = -1, next_pub = 0;
  const double wall_end = deadline_s(40);
  while (wall_s() < wall_end) {
    side.pump(2);
    const double now = side.sim_s();
    if (now < 0) continue;
    if (t0 < 0)
      for (const auto& s : side.states)
        if (s.armed && s.offboard) {
          t0 = now;
          break;
        }
    const double tau = t0 < 0 ? -1 : now - t0;
    if (tau > kStopTau + 4.5) break;
    if (now >= next_pub && tau <= kStopTau) {
      const fact::setpoint_t sp = to_setpoint(trajectory(tau), kId, side.sim_utime);
      side.lcm.publish("FACT_SETPOINT_" + std::to_string(kId), &sp);
      next_pub = now + 0.04;
    }
  }
  ASSERT_GE(t0, 0) << "the flight controller never reported armed + OFFBOARD\n" << sim.err() << bridge.err();
  ASSERT_GT(side.sim_s() - t0, kStopTau + 4.4) << "timed out at sim " << side.sim_s() << " s\n" << sim.err();
  EXPECT_EQ(bridge.stop(), 0);
  EXPECT_EQ(sim.stop(), 0);
  for (int i = 0; i < 50; ++i) side.pump(2);  // the final status messages
  fs::remove(world);
  const std::string sim_log = sim.err(), bridge_log = bridge.err();

  // Tracking: truth against the commanded trajectory mapped into the world through f_i.
  double max_err = 0, sum_sq = 0, final_err = -1, max_takeoff_err = 0, yaw_err = 0;
  int n = 0;
  V3 hold_world;
  std::vector<std::pair<double, V3>> after_stop;  // (tau, world position)
  for (const auto& t : side.truth) {
    const double tau = (t.utime - kEpoch) * 1e-6 - t0;
    const TruthOf d = truth_of(t, kId), other = truth_of(t, 2);
    ASSERT_TRUE(d.found && other.found);
    ASSERT_EQ(other.p.z, 0.0) << "drone 2 has no peer: it must stay on the floor";
    const double e = norm(d.p - d.to_world(trajectory(tau).p));
    if (tau >= 0 && tau < 3) max_takeoff_err = std::max(max_takeoff_err, e);
    if (tau >= 3 && tau <= 12) {
      max_err = std::max(max_err, e);
      sum_sq += e * e;
      ++n;
    }
    if (std::abs(tau - 12) < 0.011) {
      final_err = e;
      yaw_err = std::remainder(d.yaw - d.frame_yaw - kYaw, 2 * kPi);
    }
    if (tau > kStopTau) after_stop.push_back({tau, d.p});
  }
  ASSERT_GT(n, 400) << side.truth.size() << " truth messages";
  const double rms = std::sqrt(sum_sq / n);
  std::printf("[ figures  ] square + hold: max tracking error %.3f m, RMS %.3f m (%d truth samples); takeoff max %.3f m; "
              "final error %.3f m; yaw error %.3f rad\n",
              max_err, rms, n, max_takeoff_err, final_err, yaw_err);
  EXPECT_LE(max_err, 0.15);
  EXPECT_LE(rms, 0.08);
  EXPECT_GE(final_err, 0);
  EXPECT_LE(final_err, 0.1);
  EXPECT_LE(std::abs(yaw_err), 0.05);

  // Setpoints stopped at kStopTau (moving at 0.79 m/s): the bridge stops streaming after 0.5 s,
  // the FC's failsafe 0.5 s later holds the drone where it is — it hovers there, it does not drift.
  EXPECT_NE(bridge_log.find("streaming stopped: setpoint stale"), std::string::npos) << bridge_log;
  EXPECT_NE(sim_log.find("drone 3 FC: offboard-loss failsafe"), std::string::npos) << sim_log;
  V3 hold_fi;
  ASSERT_TRUE(parse_triple(sim_log, "holding position f_i", &hold_fi)) << sim_log;
  ASSERT_FALSE(side.truth.empty());
  hold_world = truth_of(side.truth.back(), kId).to_world(hold_fi);
  double max_from_hold = 0, spread = 0;
  V3 first_rest;
  bool have_rest = false;
  for (const auto& [tau, p] : after_stop) {
    if (tau < kStopTau + 2.5) continue;  // failsafe at ~ +1 s, then settled
    if (!have_rest) first_rest = p, have_rest = true;
    max_from_hold = std::max(max_from_hold, norm(p - hold_world));
    spread = std::max(spread, norm(p - first_rest));
  }
  ASSERT_TRUE(have_rest);
  std::printf("[ figures  ] failsafe hold at f_i (%.3f, %.3f, %.3f): over the last 2 s max %.3f m from it, moved %.3f m\n",
              hold_fi.x, hold_fi.y, hold_fi.z, max_from_hold, spread);
  EXPECT_GT(hold_fi.x, 0.75) << "the hold is after the last setpoint";
  EXPECT_LT(hold_fi.x, 1.4);
  EXPECT_NEAR(hold_fi.z, kHeight, 0.1);
  EXPECT_LE(max_from_hold, 0.1);
  EXPECT_LE(spread, 0.06);  // VIO drift (0.01 m/sqrt(s) per axis) moves a VIO hold a little
  bool saw_loiter = false;
  for (const auto& s : side.states) {
    const double tau = (s.utime - kEpoch) * 1e-6 - t0;
    if (tau > kStopTau + 1.5 && s.connected) {
      EXPECT_TRUE(s.armed);
      EXPECT_FALSE(s.offboard);
      EXPECT_EQ(mav::px4_main_mode(static_cast<uint32_t>(s.custom_mode)), 4u);  // AUTO (.LOITER)
      saw_loiter = true;
    }
    // The FC's LOCAL_POSITION_NED / ATTITUDE, converted back by the bridge, is the drone's VIO.
    if (std::abs(tau - 12) < 0.05 && s.position_valid) {
      EXPECT_NEAR(s.position[0], 0, 0.1);
      EXPECT_NEAR(s.position[1], 0, 0.1);
      EXPECT_NEAR(s.position[2], kHeight, 0.1);
      EXPECT_NEAR(s.yaw, kYaw, 0.05);
      EXPECT_LT(s.position_age_ms, 100);
    }
  }
  EXPECT_TRUE(saw_loiter);

  // Counters: the FC took the bridge's setpoints, commands and odometry; nothing was malformed.
  ASSERT_TRUE(side.have_sim_status && side.have_bridge_status);
  EXPECT_EQ(side.sim_status.state, "stopped");
  EXPECT_GE(side.sim_counter("fc_setpoints"), 600);
  EXPECT_GE(side.sim_counter("fc_commands"), 2);
  EXPECT_GE(side.sim_counter("fc_odometry"), 1000);
  EXPECT_GE(side.sim_counter("fc_peer_heartbeats"), 10);
  EXPECT_EQ(side.sim_counter("fc_failsafe"), 1);
  for (const char* c : {"fc_rejected_nan", "fc_rejected_frame", "fc_rejected_type_mask", "fc_not_for_us",
                        "fc_mavlink_bad_crc", "fc_foreign_peer", "fc_send_failed"})
    EXPECT_EQ(side.sim_counter(c), 0) << c;
  EXPECT_GE(side.bridge_counter("fc_heartbeats"), 10);
  EXPECT_EQ(side.bridge_counter("mavlink_bad_crc"), 0);
  EXPECT_EQ(side.bridge_counter("mavlink_unknown_id"), 0);
  EXPECT_NE(sim_log.find("drone 3 FC: armed"), std::string::npos) << sim_log;
  EXPECT_NE(sim_log.find("drone 3 FC: mode OFFBOARD"), std::string::npos) << sim_log;
  EXPECT_NE(sim_log.find("drone 3 FC: peer 127.0.0.1:15400"), std::string::npos) << sim_log;
}

// This test as the bridge: a UDP socket talking raw MAVLink to drone 2's FC.
class RawPeer {
 public:
  RawPeer(int local_port, int fc_port) : enc_({1, mav::kCompIdOnboardComputer}) {
    fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(static_cast<uint16_t>(local_port));
    ok_ = fd_ >= 0 && ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    fc_ = a;
    fc_.sin_port = htons(static_cast<uint16_t>(fc_port));
  }
  ~RawPeer() { ::close(fd_); }
  bool ok() const { return ok_; }
  void send_bytes(const std::vector<uint8_t>& b) {
    ::sendto(fd_, b.data(), b.size(), 0, reinterpret_cast<sockaddr*>(&fc_), sizeof fc_);
  }
  template <class M>
  void send(const M& m) {
    send_bytes(enc_.encode(m));
  }
  void poll() {
    uint8_t buf[4096];
    for (;;) {
      const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
      if (n <= 0) break;
      parser_.feed(buf, static_cast<std::size_t>(n), [&](const mav::Frame& f) { on_frame(f); },
                   [&](const mav::Rejection& r) { rejections.push_back(r.detail); });
    }
  }
  void on_frame(const mav::Frame& f) {
    ++frames;
    sysid = f.sysid;
    compid = f.compid;
    mav::Heartbeat hb;
    mav::LocalPositionNed lp;
    mav::Attitude att;
    if (mav::decode(f, &hb)) heartbeat = hb, ++heartbeats;
    if (mav::decode(f, &lp)) position = lp, ++positions;
    if (mav::decode(f, &att)) attitude = att, ++attitudes;
  }
  mav::Heartbeat heartbeat;
  mav::LocalPositionNed position;
  mav::Attitude attitude;
  int frames = 0, heartbeats = 0, positions = 0, attitudes = 0;
  uint8_t sysid = 0, compid = 0;
  std::vector<std::string> rejections;

 private:
  int fd_ = -1;
  bool ok_ = false;
  sockaddr_in fc_{};
  mav::Encoder enc_;
  mav::Parser parser_;
};

mav::SetPositionTargetLocalNed ned_setpoint(float x, float y, float z) {
  mav::SetPositionTargetLocalNed m;
  m.x = x;
  m.y = y;
  m.z = z;
  m.yaw = static_cast<float>(kPi / 2);  // f_i yaw 0
  m.type_mask = 0;
  m.target_system = 1;
  m.target_component = 1;
  m.coordinate_frame = mav::kFrameLocalNed;
  return m;
}

mav::CommandLong command(uint16_t cmd, float p1, float p2 = 0, float p3 = 0) {
  mav::CommandLong c;
  c.command = cmd;
  c.param = {p1, p2, p3, 0, 0, 0, 0};
  c.target_system = 1;
  c.target_component = 1;
  return c;
}

TEST(SimFc, RawMavlinkCommandsTypeMaskFailsafeAndRejections) {
  ASSERT_TRUE(only_loopback());
  const std::string world = write_world();
  const int kBase = 15500;
  Lcm side(url(7832), -1);
  Process sim(FACT_SIM_BINARY, {"--world", world, "--rate", "2", "--duration", "60", "--camera-rate", "1", "--truth-rate",
                                "50", "--seed", "6", "--mavlink-port", std::to_string(kBase), "--lcm-url", url(7832)});
  ASSERT_TRUE(sim.started());
  RawPeer peer(15600, kBase + 2);
  ASSERT_TRUE(peer.ok());
  // Runs until `sim_s` seconds of simulation time, calling every(now) each ~2 ms of wall time.
  auto run_until = [&](double until, const std::function<void(double)>& every) {
    const double wall_end = deadline_s(20);
    while (wall_s() < wall_end && side.sim_s() < until) {
      side.pump(2);
      peer.poll();
      if (side.sim_s() >= 0 && every) every(side.sim_s());
    }
  };
  double next = 0;
  auto periodic = [&](double now, double period, const std::function<void()>& f) {
    if (now >= next) f(), next = now + period;
  };
  mav::Heartbeat ours;
  ours.type = mav::kMavTypeOnboardController;
  ours.autopilot = mav::kMavAutopilotInvalid;
  run_until(0.2, nullptr);
  // a) First datagram: the FC learns us and answers with HEARTBEAT and telemetry.
  peer.send(ours);
  run_until(1.2, nullptr);
  ASSERT_GE(peer.heartbeats, 1) << sim.err();
  EXPECT_EQ(peer.sysid, 1);
  EXPECT_EQ(peer.compid, 1);
  EXPECT_EQ(peer.heartbeat.type, mav::kMavTypeQuadrotor);
  EXPECT_EQ(peer.heartbeat.autopilot, mav::kMavAutopilotPx4);
  EXPECT_EQ(peer.heartbeat.base_mode, mav::kModeFlagCustomModeEnabled);  // disarmed
  EXPECT_EQ(mav::px4_main_mode(peer.heartbeat.custom_mode), 3u);         // POSCTL
  EXPECT_GE(peer.positions, 25);  // 30 Hz for about a second
  EXPECT_LE(peer.positions, 36);
  EXPECT_NEAR(peer.position.z, 0, 0.05);
  // Drone 2's f_i yaw 0 is its world heading at start: NED yaw pi/2 (f_i x = east).
  EXPECT_NEAR(peer.attitude.yaw, kPi / 2, 0.05);
  EXPECT_TRUE(peer.rejections.empty());

  // b) OFFBOARD without setpoints: refused.
  peer.send(command(mav::kCmdDoSetMode, 1, 6));
  // c) Setpoints while disarmed (1 m up): the drone stays on the floor.
  const auto up = ned_setpoint(0, 0, -1.0f);
  next = 0;
  run_until(2.5, [&](double now) { periodic(now, 0.05, [&] { peer.send(up); }); });
  EXPECT_EQ(mav::px4_main_mode(peer.heartbeat.custom_mode), 3u) << sim.err();
  ASSERT_FALSE(side.truth.empty());
  EXPECT_EQ(truth_of(side.truth.back(), 2).p.z, 0.0);
  // d) OFFBOARD + arm while streaming: it takes off to 1 m.
  peer.send(command(mav::kCmdDoSetMode, 1, 6));
  peer.send(command(mav::kCmdComponentArmDisarm, 1));
  run_until(5.5, [&](double now) { periodic(now, 0.05, [&] { peer.send(up); }); });
  EXPECT_EQ(peer.heartbeat.base_mode, mav::kModeFlagCustomModeEnabled | mav::kModeFlagSafetyArmed) << sim.err();
  EXPECT_EQ(mav::px4_main_mode(peer.heartbeat.custom_mode), 6u);
  const TruthOf up_state = truth_of(side.truth.back(), 2);
  EXPECT_NEAR(up_state.p.z, 1.0, 0.05);
  EXPECT_NEAR(peer.position.z, -1.0, 0.05);  // LOCAL_POSITION_NED: 1 m up

  // e) Velocity only (position and acceleration ignored): 0.5 m/s north = +y of f_i, for 1 s.
  auto vel = ned_setpoint(std::nanf(""), std::nanf(""), std::nanf(""));  // ignored: NaN allowed
  vel.type_mask = 1 | 2 | 4 | 64 | 128 | 256;
  vel.vx = 0.5f;
  next = 0;
  double v_start = -1;
  V3 p_start;
  run_until(7.5, [&](double now) {
    periodic(now, 0.05, [&] { peer.send(vel); });
    if (v_start < 0 && now >= 6.5 && !side.truth.empty()) v_start = now, p_start = truth_of(side.truth.back(), 2).p;
  });
  const TruthOf v_state = truth_of(side.truth.back(), 2);
  const double c = std::cos(v_state.frame_yaw), s = std::sin(v_state.frame_yaw);
  const V3 dp = v_state.p - p_start;
  const double dt = side.sim_s() - v_start;
  const double vx_fi = (c * dp.x + s * dp.y) / dt, vy_fi = (-s * dp.x + c * dp.y) / dt;
  std::printf("[ figures  ] velocity-only setpoint 0.5 m/s north: f_i velocity (%.3f, %.3f, %.3f) m/s\n", vx_fi, vy_fi,
              dp.z / dt);
  EXPECT_NEAR(vy_fi, 0.5, 0.05);
  EXPECT_NEAR(vx_fi, 0.0, 0.05);
  EXPECT_NEAR(dp.z / dt, 0.0, 0.05);

  // f) Stop: a velocity command would fly on; the failsafe holds the drone instead.
  // The failsafe engages 0.5 s after the last setpoint (sim 8.0); braking from 0.5 m/s settles in ~2 s.
  run_until(10.0, nullptr);
  const V3 held = truth_of(side.truth.back(), 2).p;
  run_until(11.5, nullptr);
  const V3 later = truth_of(side.truth.back(), 2).p;
  std::printf("[ figures  ] after the failsafe: moved %.3f m in 1.5 s (0.75 m if it flew on)\n", norm(later - held));
  EXPECT_LE(norm(later - held), 0.06);  // VIO drift (0.01 m/sqrt(s) per axis) moves a VIO hold a little
  EXPECT_EQ(mav::px4_main_mode(peer.heartbeat.custom_mode), 4u) << sim.err();
  EXPECT_EQ(peer.heartbeat.custom_mode >> 24, 3u);  // AUTO.LOITER
  EXPECT_NE(peer.heartbeat.base_mode & mav::kModeFlagSafetyArmed, 0);

  // g) Rejected and counted: NaN in a used field, a body frame, another system, a bad CRC, a
  //    stranger's datagram; a disarm in the air is denied; ODOMETRY is counted.
  auto nan = ned_setpoint(0, 0, -1);
  nan.x = std::nanf("");
  peer.send(nan);
  auto body = ned_setpoint(0, 0, -1);
  body.coordinate_frame = 8;  // MAV_FRAME_BODY_NED
  peer.send(body);
  auto other = ned_setpoint(0, 0, -1);
  other.target_system = 7;
  peer.send(other);
  mav::Encoder enc({1, 191});
  auto bad = enc.encode(ned_setpoint(0, 0, -1));
  bad[14] ^= 0x10;
  peer.send_bytes(bad);
  peer.send(command(mav::kCmdComponentArmDisarm, 0));
  mav::Odometry od;
  peer.send(od);
  {
    RawPeer stranger(15601, kBase + 2);
    stranger.send(ned_setpoint(0, 0, -2));
    run_until(12.5, nullptr);
  }
  const V3 final_p = truth_of(side.truth.back(), 2).p;
  EXPECT_LE(norm(final_p - held), 0.06) << "a rejected setpoint moved the drone";
  EXPECT_EQ(sim.stop(), 0) << sim.err();
  for (int i = 0; i < 50; ++i) side.pump(2);
  fs::remove(world);
  const std::string log = sim.err();
  ASSERT_TRUE(side.have_sim_status);
  EXPECT_EQ(side.sim_status.state, "stopped");
  EXPECT_EQ(side.sim_counter("fc_rejected_nan"), 1);
  EXPECT_EQ(side.sim_counter("fc_rejected_frame"), 1);
  EXPECT_EQ(side.sim_counter("fc_not_for_us"), 1);
  EXPECT_EQ(side.sim_counter("fc_mavlink_bad_crc"), 1);
  EXPECT_EQ(side.sim_counter("fc_foreign_peer"), 1);
  EXPECT_EQ(side.sim_counter("fc_command_denied"), 2);  // OFFBOARD without setpoints, disarm in the air
  EXPECT_EQ(side.sim_counter("fc_commands"), 2);
  EXPECT_EQ(side.sim_counter("fc_odometry"), 1);
  EXPECT_EQ(side.sim_counter("fc_failsafe"), 1);
  EXPECT_GE(side.sim_counter("fc_setpoints"), 115);  // 20 Hz over 1.3 + 3 + 2 s of sim time
  EXPECT_NE(log.find("SET_POSITION_TARGET_LOCAL_NED x = nan is not finite"), std::string::npos) << log;
  EXPECT_NE(log.find("only MAV_FRAME_LOCAL_NED (1) is supported"), std::string::npos) << log;
  EXPECT_NE(log.find("OFFBOARD refused: no setpoint"), std::string::npos) << log;
  EXPECT_NE(log.find("disarm refused in the air"), std::string::npos) << log;
  EXPECT_NE(log.find("bad CRC on msgid 84"), std::string::npos) << log;
  EXPECT_NE(log.find("datagram from 127.0.0.1:15601 dropped"), std::string::npos) << log;
  EXPECT_NE(log.find("drone 2 FC: offboard-loss failsafe"), std::string::npos) << log;
}

TEST(SimFc, AutoArmStartsArmedInOffboard) {
  ASSERT_TRUE(only_loopback());
  const std::string world = write_world();
  Lcm side(url(7833), -1);
  Process sim(FACT_SIM_BINARY, {"--world", world, "--rate", "2", "--duration", "60", "--camera-rate", "1", "--truth-rate",
                                "50", "--mavlink-port", "15700", "--fc-auto-arm", "--lcm-url", url(7833)});
  ASSERT_TRUE(sim.started());
  RawPeer peer(15800, 15703);
  ASSERT_TRUE(peer.ok());
  const auto up = ned_setpoint(0, 0, -0.8f);
  double next = 0;
  const double wall_end = deadline_s(15);
  while (wall_s() < wall_end && side.sim_s() < 3.0) {
    side.pump(2);
    peer.poll();
    if (side.sim_s() >= 0 && side.sim_s() >= next) peer.send(up), next = side.sim_s() + 0.05;
  }
  EXPECT_EQ(sim.stop(), 0);
  fs::remove(world);
  ASSERT_GE(peer.heartbeats, 2) << sim.err();
  EXPECT_EQ(peer.heartbeat.base_mode, mav::kModeFlagCustomModeEnabled | mav::kModeFlagSafetyArmed);
  EXPECT_EQ(mav::px4_main_mode(peer.heartbeat.custom_mode), 6u);
  ASSERT_FALSE(side.truth.empty());
  EXPECT_GT(truth_of(side.truth.back(), 3).p.z, 0.6) << sim.err();  // no arm / mode commands needed
  EXPECT_EQ(truth_of(side.truth.back(), 2).p.z, 0.0);
}

TEST(SimFcFlags, BadFlagsExitTwoAndABusyPortExitsOne) {
  auto run = [](const std::vector<std::string>& args, std::string* err) {
    Process p(FACT_SIM_BINARY, args);
    const int rc = p.wait();
    *err = p.err();
    return rc;
  };
  std::string err;
  EXPECT_EQ(run({"--lcm-url", "memq://", "--mavlink-port", "70000"}, &err), 2);
  EXPECT_NE(err.find("--mavlink-port: expected 0 (off) or a port"), std::string::npos) << err;
  EXPECT_EQ(run({"--lcm-url", "memq://", "--fc-auto-arm"}, &err), 2);
  EXPECT_NE(err.find("--fc-auto-arm needs --mavlink-port"), std::string::npos) << err;
  EXPECT_EQ(run({"--lcm-url", "memq://", "--mavlink-port", "15900", "--script", "hover"}, &err), 2);
  EXPECT_NE(err.find("exclude each other"), std::string::npos) << err;
  EXPECT_EQ(run({"--lcm-url", "memq://", "--mavlink-port", "15900", "--mavlink-bind", "localhost"}, &err), 2);
  EXPECT_NE(err.find("--mavlink-bind: expected an IPv4 address"), std::string::npos) << err;
  EXPECT_EQ(run({"--lcm-url", "memq://", "--mavlink-port", "65534", "--drones", "4"}, &err), 2);
  EXPECT_NE(err.find("drone 2 would need UDP port 65536"), std::string::npos) << err;
  RawPeer busy(15902, 1);  // holds 127.0.0.1:15902 = drone 2's port with --mavlink-port 15900
  ASSERT_TRUE(busy.ok());
  EXPECT_EQ(run({"--lcm-url", "memq://", "--drones", "4", "--mavlink-port", "15900", "--duration", "1"}, &err), 1);
  EXPECT_NE(err.find("cannot bind UDP 127.0.0.1:15902"), std::string::npos) << err;
}

}  // namespace

int main(int argc, char** argv) { return fact::test::main_in_private_netns(argc, argv, FACT_NETNS_RUN); }
