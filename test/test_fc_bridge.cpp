// fact-fc-bridge as a real process. This program is the rest of the loop: it publishes setpoints
// (LCM udpm), plays the flight controller on UDP 127.0.0.1 (HEARTBEAT, LOCAL_POSITION_NED,
// ATTITUDE, malformed frames) and decodes what the bridge sends with fact_mavlink. Checks:
// streaming stops when setpoints go stale or the FC heartbeat is lost (and restarts), NaN /
// geofence / foreign / undecodable setpoints never reach the wire and are counted, malformed
// MAVLink is counted by reason, fc_state carries the FC's state converted back to f_i, the serial
// link works on a pseudo-terminal, and bad flags exit 2 with the reason.
//
// udpm must never leave the machine: main() re-executes this program through
// scripts/netns-run.sh (FACT_NETNS_RUN) unless only lo is visible in /proc/net/dev.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <pty.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "common/app.h"
#include "fact/app_status_t.hpp"
#include "fact/fc_state_t.hpp"
#include "fact/mavlink.h"
#include "fact/mavlink_frames.h"
#include "fact/odometry_t.hpp"
#include "fact/setpoint_t.hpp"
#include "app_process.h"
#include "private_netns.h"
#include "test_time.h"

namespace {

namespace fs = std::filesystem;
namespace mav = fact::mavlink;
constexpr double kPi = 3.14159265358979323846;
const std::string kUrl = "udpm://239.255.76.67:7667?ttl=0";

using fact::test::only_loopback;

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// The bridge process, stdout and stderr in one temporary file (removed with it).
class Process : private fact::test::TempFile, public fact::test::AppProcess {
 public:
  explicit Process(const std::vector<std::string>& args)
      : TempFile("fc-bridge-test"),
        AppProcess(fact::test::command_line(FACT_FC_BRIDGE_BINARY, args), TempFile::path(), TempFile::path()) {}
  // The exit code once it exits (AppProcess::wait_for; −1 if it is still running after 20 s).
  int wait() { return wait_s(20); }
  int stop() { return AppProcess::stop(SIGINT); }
  std::string log() const { return err(); }
};

int run_to_exit(const std::vector<std::string>& args, std::string* log) {
  Process p(args);
  const int rc = p.wait();
  *log = p.log();
  return rc;
}

struct Received {
  double t;  // s, steady clock
  mav::Frame frame;
};

// The fake flight controller: a UDP socket on 127.0.0.1:port, talking to the bridge's port.
class FakeFc {
 public:
  FakeFc(int port, int bridge_port) : encoder_({1, mav::kCompIdAutopilot}) {
    fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(static_cast<uint16_t>(port));
    ok_ = fd_ >= 0 && ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    bridge_ = a;
    bridge_.sin_port = htons(static_cast<uint16_t>(bridge_port));
  }
  ~FakeFc() { ::close(fd_); }
  bool ok() const { return ok_; }
  void send_bytes(const std::vector<uint8_t>& b) {
    ::sendto(fd_, b.data(), b.size(), 0, reinterpret_cast<sockaddr*>(&bridge_), sizeof bridge_);
  }
  template <class M>
  void send(const M& m) {
    send_bytes(encoder_.encode(m));
  }
  void heartbeat(uint8_t base_mode = mav::kModeFlagCustomModeEnabled, uint32_t custom_mode = 0x00030000) {
    mav::Heartbeat hb;
    hb.type = mav::kMavTypeQuadrotor;
    hb.autopilot = mav::kMavAutopilotPx4;
    hb.base_mode = base_mode;
    hb.custom_mode = custom_mode;
    hb.system_status = 4;
    send(hb);
  }
  void poll() {
    uint8_t buf[4096];
    for (;;) {
      const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
      if (n <= 0) break;
      const double t = now_s();
      parser_.feed(buf, static_cast<std::size_t>(n), [&](const mav::Frame& f) { frames.push_back({t, f}); },
                   [&](const mav::Rejection& r) { rejections.push_back(r.detail); });
    }
  }
  int count(uint32_t msgid, double from = 0, double to = 1e300) const {
    int n = 0;
    for (const auto& r : frames)
      if (r.frame.msgid == msgid && r.t >= from && r.t < to) ++n;
    return n;
  }
  std::vector<Received> frames;
  std::vector<std::string> rejections;

 private:
  int fd_ = -1;
  bool ok_ = false;
  sockaddr_in bridge_{};
  mav::Encoder encoder_;
  mav::Parser parser_;
};

// LCM side: publishes setpoints, hears fc_state and the bridge's status.
class LcmSide {
 public:
  LcmSide() : lcm(kUrl) {
    lcm.subscribe("FACT_FC_STATE_0", &LcmSide::on_state, this);
    lcm.subscribe("FACT_STATUS", &LcmSide::on_status, this);
  }
  void on_state(const lcm::ReceiveBuffer*, const std::string&, const fact::fc_state_t* m) { states.push_back(*m); }
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const fact::app_status_t* m) {
    if (m->app == "fact-fc-bridge") status = *m, have_status = true;
  }
  void pump() {
    while (lcm.handleTimeout(0) > 0) {
    }
  }
  int64_t counter(const std::string& name) const { return fact::app::counter_value(status, name).value_or(-1); }
  lcm::LCM lcm;
  std::vector<fact::fc_state_t> states;
  fact::app_status_t status;
  bool have_status = false;
};

// Setpoints are stamped on the wall clock, as the planner stamps them, moved by this much when a
// test steps the bridge's clock (a planner on the same computer sees the same step).
int64_t g_stamp_shift_us = 0;

fact::setpoint_t setpoint(double x, double y, double z, double yaw = 0.5) {
  fact::setpoint_t s{};
  s.utime = fact::app::now_us() + g_stamp_shift_us;
  s.drone_id = 0;
  s.position[0] = x;
  s.position[1] = y;
  s.position[2] = z;
  s.velocity[0] = 0.1;
  s.yaw = yaw;
  return s;
}

void publish_sp(LcmSide& side, const fact::setpoint_t& s) { side.lcm.publish("FACT_SETPOINT_0", &s); }

// Waits for the bridge's first status (it publishes it once it has subscribed), at most
// 5 s × FACT_TEST_TIME_SCALE. Returns whether it came.
bool bridge_up(LcmSide& side) {
  const double end = now_s() + fact::test::scaled_s(5);
  while (!side.have_status && now_s() < end) {
    side.pump();
    ::usleep(1000);
  }
  return side.have_status;
}

// Runs `every` about each ms for `seconds`, polling the FC socket and LCM.
void run_for(double seconds, FakeFc& fc, LcmSide& side, const std::function<void(double t)>& every) {
  const double start = now_s();
  while (now_s() - start < seconds) {
    every(now_s());
    fc.poll();
    side.pump();
    ::usleep(1000);
  }
}

std::vector<std::string> bridge_args(int port, int fc_port, const std::vector<std::string>& more) {
  std::vector<std::string> a = {"--drone-id", "0", "--lcm-url", kUrl, "--udp",
                                std::to_string(port) + ":127.0.0.1:" + std::to_string(fc_port), "--status-period", "0.2"};
  a.insert(a.end(), more.begin(), more.end());
  return a;
}

}  // namespace

TEST(FcBridge, StreamingStopsOnStaleSetpointOrLostHeartbeatAndResumes) {
  ASSERT_TRUE(only_loopback());
  FakeFc fc(15101, 15100);
  ASSERT_TRUE(fc.ok());
  LcmSide side;
  Process bridge(bridge_args(15100, 15101, {"--setpoint-timeout", "0.3", "--heartbeat-timeout", "0.6"}));
  ASSERT_TRUE(bridge_up(side)) << bridge.log();
  double next_hb = 0, next_sp = 0;
  bool send_sp = true, send_hb = true;
  auto every = [&](double t) {
    if (send_hb && t >= next_hb) fc.heartbeat(), next_hb = t + 0.1;
    if (send_sp && t >= next_sp) publish_sp(side, setpoint(1, 2, 3)), next_sp = t + 0.05;
  };
  const double t0 = now_s();
  run_for(1.0, fc, side, every);  // A: both fresh
  const double a_end = now_s();
  // Streaming is checked as at least 20 Hz (the setpoint stream's floor in the planner's figures;
  // PX4's offboard mode needs more than 2 Hz) of the nominal --stream-rate 50 Hz: the old floor,
  // 72 % of nominal, failed once under qemu-aarch64 on a loaded machine (15 of 25 and 12 of 20).
  // The stream's rate is a benchmark figure (bench/bridge_bench.sh), not a test.
  EXPECT_GE(fc.count(84, a_end - 0.5, a_end), 10);
  send_sp = false;                  // B: setpoints stop
  const double b_start = now_s();
  run_for(1.0, fc, side, every);
  EXPECT_EQ(fc.count(84, b_start + 0.3 + 0.12, now_s()), 0) << "still streaming on a stale setpoint";
  send_sp = true;                   // C: setpoints again
  run_for(0.8, fc, side, every);
  const double c_end = now_s();
  EXPECT_GE(fc.count(84, c_end - 0.4, c_end), 8);  // 20 Hz again
  send_hb = false;                  // D: FC heartbeat lost
  const double d_start = now_s();
  run_for(1.3, fc, side, every);
  EXPECT_EQ(fc.count(84, d_start + 0.6 + 0.15, now_s()), 0) << "still streaming without the FC heartbeat";
  EXPECT_GE(fc.count(0, d_start + 0.5, now_s()), 1) << "our own HEARTBEAT must go on";
  EXPECT_EQ(bridge.stop(), 0);
  const std::string log = bridge.log();
  EXPECT_NE(log.find("streaming stopped: setpoint stale"), std::string::npos) << log;
  EXPECT_NE(log.find("streaming stopped: flight-controller heartbeat lost"), std::string::npos) << log;
  bool saw_stale = false, saw_lost = false, saw_streaming = false;
  for (const auto& s : side.states) {
    saw_stale |= !s.streaming && s.reason.find("setpoint stale") != std::string::npos;
    saw_lost |= !s.streaming && s.reason.find("heartbeat lost") != std::string::npos && !s.connected;
    saw_streaming |= s.streaming && s.connected && s.reason == "streaming";
  }
  EXPECT_TRUE(saw_stale && saw_lost && saw_streaming) << side.states.size() << " fc_state messages";
  // Every SET_POSITION_TARGET_LOCAL_NED carries the f_i setpoint (1, 2, 3) in NED.
  for (const auto& r : fc.frames) {
    mav::SetPositionTargetLocalNed m;
    if (!mav::decode(r.frame, &m)) continue;
    EXPECT_FLOAT_EQ(m.x, 2);
    EXPECT_FLOAT_EQ(m.y, 1);
    EXPECT_FLOAT_EQ(m.z, -3);
    EXPECT_FLOAT_EQ(m.yaw, static_cast<float>(kPi / 2 - 0.5));
  }
  (void)t0;
}

#ifdef FACT_CLOCK_SHIFT_LIBRARY
// The bridge's wall clock steps back an hour while it streams (clock_shift.c, preloaded into the
// bridge alone), then the planner dies: the stream goes on through the step and still stops once
// the setpoint is stale (review, session 30: with the stop rules on the wall clock the step
// stopped the stream for the hour, and a dead planner's setpoint would have streamed on).
TEST(FcBridge, WallClockStepNeitherStopsTheStreamNorKeepsAStaleSetpoint) {
  ASSERT_TRUE(only_loopback());
  FakeFc fc(15141, 15140);
  ASSERT_TRUE(fc.ok());
  LcmSide side;
  const fact::test::TempFile shift("fc-bridge-clock");
  std::ofstream(shift.path()) << "0\n";
  ::setenv("FACT_CLOCK_SHIFT_FILE", shift.path().c_str(), 1);
  ::setenv("LD_PRELOAD", FACT_CLOCK_SHIFT_LIBRARY, 1);
  Process bridge(bridge_args(15140, 15141, {"--setpoint-timeout", "0.3"}));
  ::unsetenv("LD_PRELOAD");
  ::unsetenv("FACT_CLOCK_SHIFT_FILE");
  ASSERT_TRUE(bridge_up(side)) << bridge.log();
  double next_hb = 0, next_sp = 0;
  bool send_sp = true;
  auto every = [&](double t) {
    if (t >= next_hb) fc.heartbeat(), next_hb = t + 0.1;
    if (send_sp && t >= next_sp) publish_sp(side, setpoint(1, 2, 3)), next_sp = t + 0.05;
  };
  run_for(0.6, fc, side, every);
  std::ofstream(shift.path()) << "-3600\n";
  g_stamp_shift_us = -3600000000LL;
  const double stepped = now_s();
  run_for(0.8, fc, side, every);
  EXPECT_GE(fc.count(84, stepped + 0.2, now_s()), 10) << "streaming stopped at the step";
  send_sp = false;  // the planner dies
  const double died = now_s();
  run_for(1.0, fc, side, every);
  EXPECT_EQ(fc.count(84, died + 0.3 + 0.12, now_s()), 0) << "a dead planner's setpoint streams on";
  EXPECT_EQ(bridge.stop(), 0);
  g_stamp_shift_us = 0;
}
#endif

// Setpoints stamped an hour ago (a log replayed onto the drone's bus) or an hour ahead never reach
// the wire; fresh ones stream (review, session 32: any stamp streamed).
TEST(FcBridge, SetpointsStampedFarFromTheClockAreRefused) {
  ASSERT_TRUE(only_loopback());
  FakeFc fc(15151, 15150);
  ASSERT_TRUE(fc.ok());
  LcmSide side;
  Process bridge(bridge_args(15150, 15151, {}));
  ASSERT_TRUE(bridge_up(side)) << bridge.log();
  double next_hb = 0, next_sp = 0;
  int64_t stamp_shift = -3600000000LL;
  run_for(1.0, fc, side, [&](double t) {
    if (t >= next_hb) fc.heartbeat(), next_hb = t + 0.1;
    if (t < next_sp) return;
    next_sp = t + 0.05;
    fact::setpoint_t s = setpoint(1, 2, 3);
    s.utime += stamp_shift;
    stamp_shift = -stamp_shift;  // an hour old, an hour ahead, …
    publish_sp(side, s);
  });
  EXPECT_EQ(fc.count(84), 0) << "a setpoint stamped an hour off was streamed";
  const double fresh = now_s();
  next_sp = 0;
  run_for(0.6, fc, side, [&](double t) {
    if (t >= next_hb) fc.heartbeat(), next_hb = t + 0.1;
    if (t >= next_sp) publish_sp(side, setpoint(1, 2, 3)), next_sp = t + 0.05;
  });
  EXPECT_GE(fc.count(84, fresh, now_s()), 5);
  EXPECT_EQ(bridge.stop(), 0);
  side.pump();
  EXPECT_GE(side.counter("rejected_stale"), 15);
  const std::string log = bridge.log();
  EXPECT_NE(log.find("is 3600 s old"), std::string::npos) << log;
  EXPECT_NE(log.find("is 3600 s ahead of this clock"), std::string::npos) << log;
}

// With --arm --offboard the bridge asks until the FC shows armed + OFFBOARD, and then never again:
// a pilot who switches to another mode or disarms is not overridden (review, session 32: the tries
// left were spent re-requesting OFFBOARD and re-arming after an RC takeover).
TEST(FcBridge, ArmAndOffboardRequestsEndOnceTheStateIsReached) {
  ASSERT_TRUE(only_loopback());
  FakeFc fc(15153, 15152);
  ASSERT_TRUE(fc.ok());
  LcmSide side;
  Process bridge(bridge_args(15152, 15153, {"--arm", "--offboard"}));
  ASSERT_TRUE(bridge_up(side)) << bridge.log();
  uint8_t base = mav::kModeFlagCustomModeEnabled;
  uint32_t custom = 0x00030000;  // POSCTL, disarmed
  double next_hb = 0, next_sp = 0;
  const auto every = [&](double t) {
    if (t >= next_hb) fc.heartbeat(base, custom), next_hb = t + 0.1;
    if (t >= next_sp) publish_sp(side, setpoint(1, 2, 3)), next_sp = t + 0.05;
  };
  run_for(2.4, fc, side, every);  // streaming 1 s, then requests once a second
  EXPECT_GE(fc.count(76), 2) << "no arm / offboard request";
  base = mav::kModeFlagCustomModeEnabled | mav::kModeFlagSafetyArmed;
  custom = static_cast<uint32_t>(mav::kPx4MainModeOffboard) << 16;
  // Longer than a request interval (1 s): a request already due when the state changed is sent
  // before the takeover below, whatever the machine's load.
  run_for(1.5, fc, side, every);
  base = mav::kModeFlagCustomModeEnabled;  // the pilot takes over: POSCTL, then disarms
  custom = 0x00030000;
  const double taken_over = now_s();
  run_for(2.5, fc, side, every);
  EXPECT_EQ(fc.count(76, taken_over, now_s()), 0) << "the bridge overrode the pilot";
  EXPECT_EQ(bridge.stop(), 0);
  const std::string log = bridge.log();
  EXPECT_NE(log.find("reports the requested state (armed / offboard): no more requests"), std::string::npos) << log;
  EXPECT_NE(log.find("left the requested state (disarmed, not offboard): not requested again"), std::string::npos) << log;
}

// MAVLink over UDP: a false start (a header claiming 255 bytes) in one datagram must not hold back
// the heartbeats of the next ones (review, session 32: the FC was "lost" for 13 s).
TEST(FcBridge, AFalseStartInADatagramDoesNotHoldBackTheNextOnes) {
  ASSERT_TRUE(only_loopback());
  FakeFc fc(15155, 15154);
  ASSERT_TRUE(fc.ok());
  LcmSide side;
  // Heartbeats every 0.1 s; the 255 bytes the false start claims would hold back 12 of them.
  const std::string timeout = std::to_string(fact::test::scaled_s(1.0));
  Process bridge(bridge_args(15154, 15155, {"--heartbeat-timeout", timeout}));
  ASSERT_TRUE(bridge_up(side)) << bridge.log();
  double next_hb = 0, next_sp = 0;
  bool sent_false_start = false;
  run_for(3.0, fc, side, [&](double t) {
    if (t >= next_sp) publish_sp(side, setpoint(1, 2, 3)), next_sp = t + 0.05;
    if (t < next_hb) return;
    next_hb = t + 0.1;
    if (!sent_false_start && fc.count(84) > 0) {
      fc.send_bytes({mav::kStx, 0xFF, 0, 0, 0, 1, 1, 0x99, 0x99, 0x0A});
      sent_false_start = true;
    }
    fc.heartbeat();
  });
  EXPECT_TRUE(sent_false_start);
  EXPECT_EQ(bridge.stop(), 0);
  side.pump();
  EXPECT_GE(side.counter("fc_heartbeats"), 20);
  EXPECT_GE(side.counter("mavlink_truncated"), 1);
  const std::string log = bridge.log();
  EXPECT_EQ(log.find("heartbeat lost"), std::string::npos) << log;
}

// One duplicated or reordered odometry datagram is dropped (rejected_out_of_order), not forwarded
// as a VIO reset; a stream that starts again (seq 0) is a reset (reset_counter 1).
TEST(FcBridge, ReorderedOdometryIsDroppedAndARestartIsAReset) {
  ASSERT_TRUE(only_loopback());
  FakeFc fc(15157, 15156);
  ASSERT_TRUE(fc.ok());
  LcmSide side;
  Process bridge(bridge_args(15156, 15157, {}));
  ASSERT_TRUE(bridge_up(side)) << bridge.log();
  const auto odometry = [](int64_t seq, int64_t utime) {
    fact::odometry_t o{};
    o.utime = utime;
    o.drone_id = 0;
    o.seq = seq;
    o.position[2] = 1;
    return o;
  };
  const int64_t t0 = 1000000000;
  std::vector<fact::odometry_t> sent;
  for (int64_t k = 10; k <= 14; ++k) sent.push_back(odometry(k, t0 + 10000 * k));
  sent.push_back(odometry(12, t0 + 120000));  // a reordered duplicate
  sent.push_back(odometry(15, t0 + 150000));
  sent.push_back(odometry(0, t0 - 5000000));  // the relay restarted
  size_t next = 0;
  run_for(1.0, fc, side, [&](double) {
    if (next < sent.size()) side.lcm.publish("FACT_ODOMETRY_0", &sent[next++]);
  });
  EXPECT_EQ(bridge.stop(), 0);
  side.pump();
  std::vector<mav::Odometry> got;
  for (const auto& r : fc.frames)
    if (mav::Odometry m; mav::decode(r.frame, &m)) got.push_back(m);
  ASSERT_EQ(got.size(), 7u);
  for (size_t i = 0; i + 1 < got.size(); ++i) EXPECT_EQ(got[i].reset_counter, 0) << i;
  EXPECT_EQ(got.back().reset_counter, 1);
  EXPECT_EQ(got[5].time_usec, static_cast<uint64_t>(t0 + 150000));
  EXPECT_EQ(side.counter("rejected_out_of_order"), 1);
}

TEST(FcBridge, BadSetpointsNeverReachTheWireAndAreCounted) {
  ASSERT_TRUE(only_loopback());
  FakeFc fc(15111, 15110);
  ASSERT_TRUE(fc.ok());
  LcmSide side;
  Process bridge(bridge_args(15110, 15111, {"--geofence", "-10,10,-10,10,0,5"}));
  ASSERT_TRUE(bridge_up(side)) << bridge.log();
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<fact::setpoint_t> bad = {setpoint(nan, 0, 1), setpoint(0, 0, 1, nan), setpoint(11, 0, 1),
                                       setpoint(0, 0, 6), setpoint(0, -20, 1), setpoint(0, 0, -0.5),
                                       setpoint(0, 0, 1)};
  bad[1].velocity[2] = inf;
  bad[6].velocity[1] = 1e39;  // finite as a double, ±inf as MAVLink's float (review, session 30)
  fact::setpoint_t foreign = setpoint(1, 1, 1);
  foreign.drone_id = 4;
  int step = 0;
  double next = 0, next_hb = 0;
  run_for(1.5, fc, side, [&](double t) {
    if (t >= next_hb) fc.heartbeat(), next_hb = t + 0.1;
    if (t < next) return;
    next = t + 0.02;
    const int i = step++;
    if (i % 4 == 0) {
      publish_sp(side, setpoint(1, -2, 4));
    } else if (i % 4 == 1) {
      side.lcm.publish("FACT_SETPOINT_0", &bad[static_cast<std::size_t>(i / 4) % bad.size()]);
    } else if (i % 4 == 2) {
      side.lcm.publish("FACT_SETPOINT_0", &foreign);
    } else {
      const uint8_t junk[5] = {1, 2, 3, 4, 5};
      side.lcm.publish("FACT_SETPOINT_0", junk, sizeof junk);
    }
  });
  EXPECT_EQ(bridge.stop(), 0);
  ::usleep(100000);
  side.pump();
  int spt = 0;
  for (const auto& r : fc.frames) {
    mav::SetPositionTargetLocalNed m;
    if (!mav::decode(r.frame, &m)) continue;
    ++spt;
    EXPECT_FLOAT_EQ(m.x, -2);  // f_i (1, -2, 4) -> NED (-2, 1, -4)
    EXPECT_FLOAT_EQ(m.y, 1);
    EXPECT_FLOAT_EQ(m.z, -4);
    EXPECT_FLOAT_EQ(m.vx, 0);
    EXPECT_FLOAT_EQ(m.vy, 0.1f);
    EXPECT_TRUE(std::isfinite(m.yaw) && std::isfinite(m.vz));
  }
  EXPECT_GE(spt, 40);
  ASSERT_TRUE(side.have_status);
  EXPECT_EQ(side.status.state, "stopped");
  EXPECT_GE(side.counter("rejected_nan"), 5);
  EXPECT_GE(side.counter("rejected_range"), 1);
  EXPECT_GE(side.counter("rejected_geofence"), 7);
  EXPECT_GE(side.counter("rejected_drone_id"), 15);
  EXPECT_GE(side.counter("undecodable"), 15);
  const std::string log = bridge.log();
  EXPECT_NE(log.find("rejected: setpoint position[0] = nan is not finite"), std::string::npos) << log;
  EXPECT_NE(log.find("rejected: setpoint velocity[2] = inf is not finite"), std::string::npos) << log;
  EXPECT_NE(log.find("rejected: setpoint velocity[1] = 1e+39 is beyond ±1e+06"), std::string::npos) << log;
  EXPECT_NE(log.find("rejected: setpoint position[2] = 6 m outside the geofence z [0, 5] m"), std::string::npos) << log;
  EXPECT_NE(log.find("rejected: setpoint drone_id = 4"), std::string::npos) << log;
}

TEST(FcBridge, MalformedMavlinkCountedAndFcStateConvertedBack) {
  ASSERT_TRUE(only_loopback());
  FakeFc fc(15121, 15120);
  ASSERT_TRUE(fc.ok());
  LcmSide side;
  Process bridge(bridge_args(15120, 15121, {"--arm", "--offboard"}));
  ASSERT_TRUE(bridge_up(side)) << bridge.log();
  mav::Encoder enc({1, 1});
  auto bad_crc = enc.encode(mav::LocalPositionNed{});
  bad_crc[12] ^= 0x40;
  std::array<uint8_t, 20> p{};
  p.fill(7);
  auto unknown = mav::frame_bytes(1, 124, p.data(), p.size(), 0, {1, 1});
  auto too_long = mav::frame_bytes(0, mav::Heartbeat::kCrcExtra, p.data(), p.size(), 0, {1, 1});
  auto signed_frame = enc.encode(mav::Heartbeat{});
  signed_frame[2] = mav::kIncompatSigned;
  signed_frame.insert(signed_frame.end(), 13, 0);
  mav::LocalPositionNed pos;
  pos.x = 2; pos.y = 1; pos.z = -3; pos.vx = 0.5; pos.vy = -0.5; pos.vz = 0.25;
  mav::Attitude att;
  att.roll = 0.1f; att.pitch = 0.2f; att.yaw = 0;
  mav::LocalPositionNed nan_pos = pos;  // sent after the valid one: it must not replace it
  nan_pos.y = std::numeric_limits<float>::quiet_NaN();
  FakeFc stranger(15129, 15120);  // the FC's address, another port: its heartbeats are ignored
  ASSERT_TRUE(stranger.ok());
  double next = 0, next_sp = 0;
  run_for(1.5, fc, side, [&](double t) {
    if (t >= next_sp) publish_sp(side, setpoint(0, 0, 1)), next_sp = t + 0.05;
    if (t < next) return;
    next = t + 0.1;
    fc.heartbeat(mav::kModeFlagCustomModeEnabled | mav::kModeFlagSafetyArmed, mav::kPx4MainModeOffboard << 16);
    fc.send(pos);
    fc.send(att);
    fc.send(nan_pos);
    stranger.heartbeat();
    for (const std::vector<uint8_t>* b : {&bad_crc, &unknown, &too_long, &signed_frame}) fc.send_bytes(*b);
  });
  EXPECT_EQ(bridge.stop(), 0);
  ::usleep(100000);
  side.pump();
  ASSERT_TRUE(side.have_status);
  EXPECT_GE(side.counter("mavlink_bad_crc"), 10);
  EXPECT_GE(side.counter("mavlink_unknown_id"), 10);
  EXPECT_GE(side.counter("mavlink_bad_length"), 10);
  EXPECT_GE(side.counter("mavlink_signed_frame"), 10);
  EXPECT_GE(side.counter("mavlink_non_finite"), 10);
  EXPECT_GE(side.counter("foreign_datagrams"), 10);
  EXPECT_GE(side.counter("fc_heartbeats"), 10);
  EXPECT_LE(side.counter("fc_heartbeats"), 20) << "the stranger's heartbeats were counted";
  EXPECT_GE(side.counter("setpoints_sent"), 40);
  EXPECT_EQ(side.counter("commands_sent"), 0) << "the FC already reports armed + offboard";
  EXPECT_EQ(fc.count(76), 0);
  ASSERT_FALSE(side.states.empty());
  const fact::fc_state_t& s = side.states.back();
  EXPECT_TRUE(s.connected);
  EXPECT_TRUE(s.armed);
  EXPECT_TRUE(s.offboard);
  EXPECT_TRUE(s.position_valid && s.attitude_valid);
  EXPECT_NEAR(s.position[0], 1, 1e-6);  // NED (2, 1, -3) -> f_i (1, 2, 3)
  EXPECT_NEAR(s.position[1], 2, 1e-6);
  EXPECT_NEAR(s.position[2], 3, 1e-6);
  EXPECT_NEAR(s.velocity[0], -0.5, 1e-6);
  EXPECT_NEAR(s.velocity[1], 0.5, 1e-6);
  EXPECT_NEAR(s.velocity[2], -0.25, 1e-6);
  EXPECT_NEAR(s.roll, 0.1, 1e-6);
  EXPECT_NEAR(s.pitch, -0.2, 1e-6);
  EXPECT_NEAR(s.yaw, kPi / 2, 1e-6);  // facing north
  EXPECT_GE(s.setpoints_sent, 40);
  const std::string log = bridge.log();
  EXPECT_NE(log.find("bad CRC on msgid 32 (LOCAL_POSITION_NED)"), std::string::npos) << log;
  EXPECT_NE(log.find("unknown msgid 1"), std::string::npos) << log;
  EXPECT_NE(log.find("payload 20 bytes, at most 9"), std::string::npos) << log;
  EXPECT_NE(log.find("signing is not supported"), std::string::npos) << log;
  EXPECT_NE(log.find("LOCAL_POSITION_NED y = nan is not finite"), std::string::npos) << log;
  EXPECT_NE(log.find("ignored a 21-byte datagram from 127.0.0.1:15129, not the flight controller 127.0.0.1:15121"),
            std::string::npos)
      << log;
}

TEST(FcBridge, SerialLinkOnAPseudoTerminal) {
  int master = -1, slave = -1;
  char name[128] = {};
  ASSERT_EQ(::openpty(&master, &slave, name, nullptr, nullptr), 0);
  Process bridge({"--drone-id", "0", "--lcm-url", "memq://", "--serial", name, "--baud", "57600"});
  mav::Parser parser;
  std::vector<mav::Frame> frames;
  const double start = now_s();
  ::fcntl(master, F_SETFL, O_NONBLOCK);
  while (now_s() - start < fact::test::scaled_s(1.5) && frames.empty()) {
    uint8_t buf[512];
    const ssize_t n = ::read(master, buf, sizeof buf);
    if (n > 0) parser.feed(buf, static_cast<std::size_t>(n), [&](const mav::Frame& f) { frames.push_back(f); }, nullptr);
    ::usleep(5000);
  }
  EXPECT_EQ(bridge.stop(), 0);
  ::close(slave);
  ::close(master);
  ASSERT_FALSE(frames.empty()) << bridge.log();
  mav::Heartbeat hb;
  ASSERT_TRUE(mav::decode(frames[0], &hb));
  EXPECT_EQ(hb.type, mav::kMavTypeOnboardController);
  EXPECT_NE(bridge.log().find("57600 8N1"), std::string::npos) << bridge.log();
}

TEST(FcBridge, FlagsAndLinkErrors) {
  // Each run: the flags, the exit code, and what the log must say ("" = only the code).
  struct Case {
    std::vector<std::string> args;
    int code;
    std::string says;
  };
  const std::vector<Case> cases = {
      {{"--help"}, 0, "--geofence"},
      {{"--lcm-url", "memq://"}, 2, "exactly one of --udp and --serial"},
      {{"--serial", "/dev/null", "--baud", "12345"}, 2, "--baud: 12345 is not a supported rate"},
      {{"--udp", "14540:127.0.0.1:99999"}, 2, "remote port '99999'"},
      {{"--udp", "1:127.0.0.1:2", "--geofence", "1,2,3"}, 2, "--geofence: expected 6 numbers"},
      {{"--udp", "1:127.0.0.1:2", "--geofence", "-1,1,-1,1,0,1,"}, 2, "--geofence: expected 6 numbers"},
      {{"--udp", "1:127.0.0.1:2", "--stream-rate", "2"}, 2, "more than 2 Hz"},
      {{"--udp", "1:127.0.0.1:2", "--sysid", "0"}, 2, ""},
      // Timeouts that round to 0 µs or never expire, a state rate that spins the loop, a fence beyond
      // a float's range (review, session 30: all were accepted).
      {{"--udp", "1:127.0.0.1:2", "--setpoint-timeout", "1e-9"}, 2,
       "--setpoint-timeout: expected a number in [0.01, 60] s, got 1e-09"},
      {{"--udp", "1:127.0.0.1:2", "--heartbeat-timeout", "1e13"}, 2,
       "--heartbeat-timeout: expected a number in [0.01, 60] s, got 1e+13"},
      {{"--udp", "1:127.0.0.1:2", "--state-rate", "1e7"}, 2,
       "--state-rate: expected a number in [0.01, 100] Hz, got 1e+07"},
      {{"--udp", "1:127.0.0.1:2", "--geofence", "-1e39,1,-1,1,0,1"}, 2,
       "--geofence: '-1e39' in '-1e39,1,-1,1,0,1' is beyond ±1e+06 m"},
      {{"--lcm-url", "memq://", "--serial", "/nonexistent/ttyFACT"}, 1,
       "cannot open serial device '/nonexistent/ttyFACT'"},
      {{"--lcm-url", "memq://", "--serial", "/dev/null"}, 1, "is not a serial device"},
  };
  for (const Case& c : cases) {
    std::string log;
    EXPECT_EQ(run_to_exit(c.args, &log), c.code) << c.args[0] << " " << (c.args.size() > 1 ? c.args[1] : "");
    EXPECT_NE(log.find(c.says), std::string::npos) << log;
  }
}

int main(int argc, char** argv) { return fact::test::main_in_private_netns(argc, argv, FACT_NETNS_RUN); }
