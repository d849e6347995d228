// Tests of fact-vio-relay as a real process: TUM file replay, the UDP line stream and the
// simulator's raw LCM odometry, each checked by a subscriber in this process over LCM udpm://
// (messages received, their values, the counters in the final status message, the log), plus
// its flags (--help, bad flags → exit 2 with the reason).
//
// udpm must never leave the machine: main() re-executes this program through
// scripts/netns-run.sh (FACT_NETNS_RUN) unless it already sees no network interface but lo in
// /proc/net/dev (which, unlike /sys/class/net, shows the current network namespace), so the whole
// run and every process it spawns live in a private namespace. The URL also has ttl=0, and the
// LCM tests refuse to run if another interface is visible. Listing the tests needs no namespace.
//
// Paths come from compile definitions: FACT_VIO_RELAY_BINARY, FACT_TEST_DATA, FACT_NETNS_RUN.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Core>
#include <lcm/lcm-cpp.hpp>

#include "common/app.h"
#include "fact/sim_clock_t.hpp"
#include "fact/app_status_t.hpp"
#include "fact/odometry_t.hpp"
#include "app_process.h"
#include "private_netns.h"
#include "temp_dir.h"
#include "test_time.h"

namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;
const std::string kApp = "fact-vio-relay";

using fact::test::only_loopback;

int count_of(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size())) ++n;
  return n;
}

// fact-vio-relay as a child process, stdout and stderr in <dir>/<name>.out and .err.
class Relay : public fact::test::AppProcess {
 public:
  Relay(const std::vector<std::string>& args, const fs::path& dir, const std::string& name)
      : AppProcess(fact::test::command_line(FACT_VIO_RELAY_BINARY, args), dir / (name + ".out"),
                   dir / (name + ".err")) {}
  // The exit code once it exits (AppProcess::wait_for; −1 if it is still running after 20 s).
  int wait() { return wait_s(20); }
};

// What this process hears on LCM: the relay's odometry and status messages.
class Listener {
 public:
  Listener(const std::string& url, const std::string& odometry_channel) : lcm_(url) {
    // LCM drops messages beyond a subscription's queue (30 by default) that arrive between two
    // handle calls; a --rate 0 replay publishes faster than that.
    lcm_.subscribe(odometry_channel, &Listener::on_odometry, this)->setQueueCapacity(10000);
    lcm_.subscribe("FACT_STATUS", &Listener::on_status, this)->setQueueCapacity(10000);
  }
  bool good() { return lcm_.good(); }
  lcm::LCM& lcm() { return lcm_; }

  // Handles messages until done() holds or 10 s × FACT_TEST_TIME_SCALE pass (a guard against a
  // hang, not a speed requirement). Returns done().
  bool pump_until(const std::function<bool()>& done) {
    const auto deadline = std::chrono::steady_clock::now() + fact::test::scaled(std::chrono::seconds(10));
    while (!done()) {
      if (std::chrono::steady_clock::now() > deadline) return false;
      lcm_.handleTimeout(50);
    }
    return true;
  }
  // The relay's status messages (app fact-vio-relay, this drone).
  std::vector<fact::app_status_t> statuses(int drone_id) const {
    std::vector<fact::app_status_t> out;
    for (const auto& s : statuses_)
      if (s.app == kApp && s.drone_id == drone_id) out.push_back(s);
    return out;
  }
  bool has_state(int drone_id, const std::string& prefix) const {
    for (const auto& s : statuses(drone_id))
      if (s.state.rfind(prefix, 0) == 0) return true;
    return false;
  }
  const std::vector<fact::odometry_t>& odometry() const { return odometry_; }

 private:
  void on_odometry(const lcm::ReceiveBuffer*, const std::string&, const fact::odometry_t* m) { odometry_.push_back(*m); }
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const fact::app_status_t* m) { statuses_.push_back(*m); }

  lcm::LCM lcm_;
  std::vector<fact::odometry_t> odometry_;
  std::vector<fact::app_status_t> statuses_;
};

int64_t counter(const fact::app_status_t& s, const std::string& name) {
  const std::optional<int64_t> value = fact::app::counter_value(s, name);
  if (!value) ADD_FAILURE() << "no counter " << name << " in the status message";
  return value.value_or(-1);
}

int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string data(const std::string& name) { return std::string(FACT_TEST_DATA) + "/vio/" + name; }

// A fresh temporary directory per test.
class VioRelayTest : public fact::test::TempDirTest {
 protected:
  VioRelayTest() : TempDirTest("fact-vio-relay") {}
};

// The LCM tests: only inside a private network namespace.
class VioRelayLcm : public VioRelayTest {
 protected:
  void SetUp() override {
    if (!only_loopback())
      GTEST_SKIP() << "not in a private network namespace: run through scripts/netns-run.sh (ctest does)";
    VioRelayTest::SetUp();
  }
  // A different multicast port per test: no test hears another's leftovers.
  static std::string url(int port) { return "udpm://239.255.76.67:" + std::to_string(port) + "?ttl=0"; }
};

// ---------------------------------------------------------------------------------------------
// test/data/vio/spin.tum: 48 good samples, k = 0 … 47, t = 1305031102.175304 + 0.1 k s, position
// (cos 0.2k, sin 0.2k, 1 + 0.01k) m, yaw 0.4 k rad, pitch −0.03, roll 0.05; between them 2 NaN/inf
// lines, 2 out-of-order lines, 2 jumps, 1 malformed line and 1 quaternion of norm 2.
Eigen::Vector3d spin_position(int k) { return {std::cos(0.2 * k), std::sin(0.2 * k), 1 + 0.01 * k}; }

TEST_F(VioRelayLcm, TumReplayPublishesEveryGoodSampleUnwrapped) {
  Listener l(url(7701), "FACT_ODOMETRY_3");
  ASSERT_TRUE(l.good());
  Relay relay({"--source", "tum", "--file", data("spin.tum"), "--rate", "0", "--drone-id", "3", "--lcm-url", url(7701)},
              dir_, "relay");
  ASSERT_TRUE(relay.started());
  // The final status ("finished") goes out after the last sample.
  ASSERT_TRUE(l.pump_until([&] { return l.has_state(3, "finished"); })) << relay.err();
  EXPECT_EQ(relay.wait(), 0) << relay.err();

  const auto& odo = l.odometry();
  ASSERT_EQ(odo.size(), 48u) << relay.err();
  for (int k = 0; k < 48; ++k) {
    const fact::odometry_t& m = odo[k];
    SCOPED_TRACE("sample " + std::to_string(k));
    EXPECT_EQ(m.drone_id, 3);
    EXPECT_EQ(m.seq, k);
    EXPECT_EQ(m.utime, 1305031102175304LL + 100000LL * k);
    EXPECT_NEAR(m.yaw, 0.4 * k, 1e-9);  // unwrapped: 18.8 rad at the end, past +π three times
    EXPECT_NEAR(m.pitch, -0.03, 1e-9);
    EXPECT_NEAR(m.roll, 0.05, 1e-9);
    const Eigen::Vector3d p = spin_position(k);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(m.position[i], p[i], 1e-8);
    const Eigen::Vector3d v = k == 0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d((p - spin_position(k - 1)) / 0.1);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(m.velocity[i], v[i], 1e-6);
  }
  EXPECT_GT(odo.back().yaw, 5 * kPi);

  const fact::app_status_t last = l.statuses(3).back();
  EXPECT_EQ(counter(last, "published"), 48);
  EXPECT_EQ(counter(last, "rejected_nan"), 2);
  EXPECT_EQ(counter(last, "rejected_out_of_order"), 2);
  EXPECT_EQ(counter(last, "rejected_jump"), 2);
  EXPECT_EQ(counter(last, "rejected_malformed"), 1);
  EXPECT_EQ(counter(last, "rejected_attitude"), 1);
  EXPECT_EQ(counter(last, "rejected_time"), 0);

  // One log line per reason per second: the replay takes far less, so the second NaN and the
  // second jump are counted but not logged.
  const std::string log = relay.err();
  EXPECT_EQ(count_of(log, ": rejected_nan: "), 1) << log;
  EXPECT_EQ(count_of(log, ": rejected_jump: "), 1) << log;
  EXPECT_EQ(count_of(log, ": rejected_out_of_order: "), 1) << log;
  EXPECT_NE(log.find("spin.tum line 13: rejected_nan: tx is nan"), std::string::npos) << log;
  EXPECT_NE(log.find("rejected_attitude: quaternion norm 2"), std::string::npos) << log;
  EXPECT_NE(log.find("rejected_malformed: expected 8 numbers"), std::string::npos) << log;
  EXPECT_NE(log.find("end of file after 69 lines: published 48, rejected_nan 2"), std::string::npos) << log;
}

// test/data/vio/walk.tum: 5 samples 0.05 s apart from t = 0, yaw π − 0.1 + 0.1 k (wrapped past π
// in the file), x = 0.05 k m.
TEST_F(VioRelayLcm, TumReplayInRealTimeAndRestamped) {
  Listener l(url(7702), "FACT_ODOMETRY_0");
  ASSERT_TRUE(l.good());
  const int64_t before = wall_us();
  Relay relay({"--source", "tum", "--file", data("walk.tum"), "--rate", "1", "--restamp", "--lcm-url", url(7702)}, dir_,
              "relay");
  ASSERT_TRUE(l.pump_until([&] { return l.has_state(0, "finished"); })) << relay.err();
  EXPECT_EQ(relay.wait(), 0) << relay.err();
  const int64_t after = wall_us();
  const auto& odo = l.odometry();
  ASSERT_EQ(odo.size(), 5u) << relay.err();
  EXPECT_GE(odo[0].utime, before);  // restamped onto the wall clock at the first sample
  EXPECT_LE(odo[0].utime, after);
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(odo[k].utime - odo[0].utime, 50000 * k);  // intervals kept
    EXPECT_NEAR(odo[k].yaw, kPi - 0.1 + 0.1 * k, 1e-9);
    EXPECT_NEAR(odo[k].position[0], 0.05 * k, 1e-12);
    EXPECT_NEAR(odo[k].velocity[0], k == 0 ? 0.0 : 1.0, 1e-9);
  }
  EXPECT_GT(odo[4].yaw, kPi);
}

// --sim-clock with a tum replay: the relay handles the clock's ticks while it replays, so its
// heartbeat keeps time with the simulation (review, session 33: the tum and udp sources never
// handled LCM, the clock stood at its first tick, and a 23 s replay sent two heartbeats).
TEST_F(VioRelayLcm, TumReplayFollowsTheSimulationClock) {
  const fs::path tum = dir_ / "slow.tum";  // 3 s of a level drone at 0.1 m/s, 10 samples a second
  {
    std::ofstream f(tum);
    for (int k = 0; k <= 30; ++k) f << 0.1 * k << " " << 0.01 * k << " 0 1 0 0 0 1\n";
  }
  Listener l(url(7707), "FACT_ODOMETRY_0");
  ASSERT_TRUE(l.good());
  const int64_t epoch = 1700000000000000;  // µs: the simulation clock runs at wall speed from here
  const auto start = std::chrono::steady_clock::now();
  const auto tick = [&] {
    fact::sim_clock_t c{};
    c.utime = epoch + std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - start).count();
    c.rate = 1;
    l.lcm().publish("FACT_SIM_CLOCK", &c);
  };
  Relay relay({"--source", "tum", "--file", tum.string(), "--rate", "1", "--restamp", "--sim-clock", "--lcm-url", url(7707)},
              dir_, "relay");
  ASSERT_TRUE(l.pump_until([&] {
    tick();
    return l.has_state(0, "finished");
  })) << relay.err();
  EXPECT_EQ(relay.wait(), 0) << relay.err();
  ASSERT_EQ(l.odometry().size(), 31u) << relay.err();
  EXPECT_GE(l.odometry()[0].utime, epoch);  // restamped onto the simulation clock
  EXPECT_LT(l.odometry()[0].utime, epoch + 10000000);
  const auto statuses = l.statuses(0);
  ASSERT_FALSE(statuses.empty());
  // One heartbeat a second of simulation time, and their times span the replay.
  EXPECT_GE(statuses.size(), 4u) << relay.err();
  EXPECT_GE(statuses.back().utime - statuses.front().utime, 2500000) << relay.err();
}

// Publishes that fail (the network gone: lo down in this test's private namespace) are counted,
// reported in the summary, and make the exit code 1, as the help promises (review, session 33:
// 19 of 30 failed, "published 11", exit 0).
TEST_F(VioRelayLcm, FailedPublishesExitOne) {
  const fs::path tum = dir_ / "slow.tum";  // 2 s, 10 samples a second
  {
    std::ofstream f(tum);
    for (int k = 0; k <= 20; ++k) f << 0.1 * k << " " << 0.01 * k << " 0 1 0 0 0 1\n";
  }
  Relay relay({"--source", "tum", "--file", tum.string(), "--rate", "1", "--lcm-url", url(7708)}, dir_, "relay");
  std::this_thread::sleep_for(std::chrono::milliseconds(700));
  ASSERT_EQ(std::system("ip link set lo down"), 0);
  const int code = relay.wait();
  ASSERT_EQ(std::system("ip link set lo up"), 0);
  const std::string err = relay.err();
  EXPECT_EQ(code, 1) << err;
  EXPECT_NE(err.find("publish_failed"), std::string::npos) << err;
  EXPECT_NE(err.find("publish(es) failed"), std::string::npos) << err;
}

// Sends one datagram to 127.0.0.1:port.
void send_line(int sock, int port, const std::string& text) {
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<uint16_t>(port));
  inet_pton(AF_INET, "127.0.0.1", &to.sin_addr);
  ASSERT_EQ(sendto(sock, text.data(), text.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof to),
            static_cast<ssize_t>(text.size()));
}

// "t x y z qx qy qz qw" for a level drone with this yaw.
std::string udp_line(double t, double x, double yaw) {
  char buf[200];
  std::snprintf(buf, sizeof buf, "%.6f %.6f 0 1 0 0 %.15f %.15f\n", t, x, std::sin(yaw / 2), std::cos(yaw / 2));
  return buf;
}

TEST_F(VioRelayLcm, UdpStreamCountsBadDatagramsAndPublishesTheRest) {
  const int port = 47311;
  Listener l(url(7703), "FACT_ODOMETRY_5");
  ASSERT_TRUE(l.good());
  Relay relay({"--source", "udp", "--port", std::to_string(port), "--drone-id", "5", "--lcm-url", url(7703)}, dir_,
              "relay");
  // Listening once its first status message says so.
  ASSERT_TRUE(l.pump_until([&] { return l.has_state(5, "listening on udp 127.0.0.1:" + std::to_string(port)); }))
      << relay.err();

  // A second relay cannot take the same port: exit 1 with the reason.
  Relay twin({"--source", "udp", "--port", std::to_string(port), "--drone-id", "5", "--lcm-url", url(7703)}, dir_, "twin");
  EXPECT_EQ(twin.wait(), 1);
  EXPECT_NE(twin.err().find("cannot listen on udp 127.0.0.1:" + std::to_string(port)), std::string::npos) << twin.err();

  const int sock = socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(sock, 0);
  // Yaw 2.8 + 0.3 k (3 rad/s), wrapped into (−π, π] by the quaternion; x = 0.1 k.
  send_line(sock, port, udp_line(50.0, 0.0, 2.8));
  send_line(sock, port, udp_line(50.1, 0.1, 3.1));
  send_line(sock, port, "50.15 nan 0 1 0 0 0 1");          // rejected_nan
  send_line(sock, port, udp_line(50.05, 0.1, 3.1));        // rejected_out_of_order
  send_line(sock, port, udp_line(50.1, 0.1, 3.1));         // rejected_out_of_order (duplicate)
  send_line(sock, port, "# a comment: no sample, not counted");
  send_line(sock, port, "hello relay");                    // rejected_malformed
  send_line(sock, port, std::string("50.2 0 0 1 0 0 0 1\0junk", 23));  // rejected_malformed (binary)
  send_line(sock, port, udp_line(50.2, 0.2, 3.4));
  send_line(sock, port, udp_line(50.25, 30.0, 3.4));       // rejected_jump (596 m/s)
  send_line(sock, port, udp_line(50.3, 0.3, 3.7));
  send_line(sock, port, udp_line(50.4, 0.4, 4.0));
  close(sock);

  ASSERT_TRUE(l.pump_until([&] { return l.odometry().size() >= 5; })) << relay.err();
  EXPECT_EQ(relay.stop(), 0) << relay.err();
  ASSERT_TRUE(l.pump_until([&] { return l.has_state(5, "stopped"); })) << relay.err();

  const auto& odo = l.odometry();
  ASSERT_EQ(odo.size(), 5u);
  for (int k = 0; k < 5; ++k) {
    SCOPED_TRACE("sample " + std::to_string(k));
    EXPECT_EQ(odo[k].seq, k);
    EXPECT_EQ(odo[k].drone_id, 5);
    EXPECT_EQ(odo[k].utime, 50000000 + 100000 * k);
    EXPECT_NEAR(odo[k].yaw, 2.8 + 0.3 * k, 1e-9);  // 3.4, 3.7, 4.0: past π, continuous
    EXPECT_NEAR(odo[k].position[0], 0.1 * k, 1e-9);
    EXPECT_NEAR(odo[k].velocity[0], k == 0 ? 0.0 : 1.0, 1e-6);
    EXPECT_NEAR(odo[k].roll, 0, 1e-12);
    EXPECT_NEAR(odo[k].pitch, 0, 1e-12);
  }
  const fact::app_status_t last = l.statuses(5).back();
  EXPECT_EQ(last.state, "stopped");
  EXPECT_EQ(counter(last, "published"), 5);
  EXPECT_EQ(counter(last, "rejected_nan"), 1);
  EXPECT_EQ(counter(last, "rejected_out_of_order"), 2);
  EXPECT_EQ(counter(last, "rejected_malformed"), 2);
  EXPECT_EQ(counter(last, "rejected_jump"), 1);
  const std::string log = relay.err();
  EXPECT_NE(log.find("first datagram from 127.0.0.1:"), std::string::npos) << log;
  EXPECT_NE(log.find("rejected_nan: tx is nan"), std::string::npos) << log;
  EXPECT_NE(log.find("rejected_malformed: expected 8 numbers (t tx ty tz qx qy qz qw), got 2"), std::string::npos)
      << log;
  EXPECT_NE(log.find("stopped after 12 datagrams"), std::string::npos) << log;
}

// --restamp with a live source whose VIO clock jumps back 100 s, then 5 s: the offset is taken
// again at each jump, so the published times go on along the wall clock, without a gap, a rejection or a restart
// (before, 20 samples were refused as jumps, then the stream restarted on the stale offset, 100 s
// before the camera's frame times).
TEST_F(VioRelayLcm, RestampedStreamFollowsAVioClockReset) {
  const int port = 47313;
  Listener l(url(7705), "FACT_ODOMETRY_6");
  ASSERT_TRUE(l.good());
  Relay relay({"--source", "udp", "--port", std::to_string(port), "--drone-id", "6", "--restamp", "--lcm-url",
               url(7705)},
              dir_, "relay");
  ASSERT_TRUE(l.pump_until([&] { return l.has_state(6, "listening on udp 127.0.0.1:" + std::to_string(port)); }))
      << relay.err();
  const int sock = socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(sock, 0);
  const int64_t before = fact::app::now_us();
  for (int k = 0; k < 45; ++k) {  // 20 Hz; the VIO's clock goes back 100 s after sample 14, 5 s after 29
    const double t = (k < 15 ? 500.0 : k < 30 ? 400.0 : 395.0) + 0.05 * k;
    send_line(sock, port, udp_line(t, 0.01 * k, 0.0));
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  close(sock);
  ASSERT_TRUE(l.pump_until([&] { return l.odometry().size() >= 45; })) << relay.err();
  const int64_t after = fact::app::now_us();
  EXPECT_EQ(relay.stop(), 0) << relay.err();
  ASSERT_TRUE(l.pump_until([&] { return l.has_state(6, "stopped"); })) << relay.err();
  const auto& odo = l.odometry();
  ASSERT_EQ(odo.size(), 45u);
  for (size_t k = 0; k < odo.size(); ++k) {
    EXPECT_EQ(odo[k].seq, static_cast<int64_t>(k));  // no restart
    EXPECT_GE(odo[k].utime, before) << k;
    EXPECT_LE(odo[k].utime, after) << k;
    if (k > 0) {
      EXPECT_GT(odo[k].utime, odo[k - 1].utime) << k;
      EXPECT_LT(odo[k].utime - odo[k - 1].utime, 1000000) << k;  // along the wall clock: no 100 s hole
    }
  }
  const fact::app_status_t last = l.statuses(6).back();
  EXPECT_EQ(counter(last, "restamp_rebased"), 2);  // 100 s back (beyond max_gap), 5 s back (time going back)
  EXPECT_EQ(counter(last, "rejected_jump"), 0);
  EXPECT_EQ(counter(last, "rejected_out_of_order"), 0);
  EXPECT_EQ(counter(last, "restarts"), 0);
  EXPECT_NE(relay.err().find("the VIO clock jumped by -"), std::string::npos) << relay.err();
}

fact::odometry_t raw(int drone, int64_t utime, double x, double yaw, double vx) {
  fact::odometry_t m;
  m.utime = utime;
  m.drone_id = drone;
  m.seq = 0;
  m.position[0] = x;
  m.position[1] = 0;
  m.position[2] = 1;
  m.velocity[0] = vx;
  m.velocity[1] = 0;
  m.velocity[2] = 0;
  m.yaw = yaw;
  m.roll = 0.01;
  m.pitch = -0.02;
  return m;
}

TEST_F(VioRelayLcm, SimulatorOdometryOverLcm) {
  Listener l(url(7704), "FACT_ODOMETRY_2");
  ASSERT_TRUE(l.good());
  Relay relay({"--drone-id", "2", "--lcm-url", url(7704)}, dir_, "relay");  // --source lcm is the default
  ASSERT_TRUE(l.pump_until([&] { return l.has_state(2, "listening on FACT_VIO_RAW_2"); })) << relay.err();

  lcm::LCM& lcm = l.lcm();
  fact::odometry_t m = raw(2, 1000000, 0.0, 3.0, 1.0);
  lcm.publish("FACT_VIO_RAW_2", &m);
  m = raw(2, 1100000, 0.1, -3.1, 1.0);  // wrapped by the source: 3.0 → 2π − 3.1
  lcm.publish("FACT_VIO_RAW_2", &m);
  m = raw(7, 1150000, 0.15, -3.1, 1.0);  // another drone's: wrong_drone_id
  lcm.publish("FACT_VIO_RAW_2", &m);
  m = raw(2, 1150000, 0.15, -3.1, 1.0);
  m.pitch = std::nan("");  // rejected_nan
  lcm.publish("FACT_VIO_RAW_2", &m);
  m = raw(2, 1050000, 0.05, -3.1, 1.0);  // rejected_out_of_order
  lcm.publish("FACT_VIO_RAW_2", &m);
  // A flood of garbage and of NaN samples: every one counted, the log at one line per reason per second.
  const auto flood_start = std::chrono::steady_clock::now();
  const char garbage[] = "not an odometry_t message";
  for (int i = 0; i < 50; ++i) {
    lcm.publish("FACT_VIO_RAW_2", garbage, sizeof garbage);  // undecodable
    m = raw(2, 1160000 + i, 0.15, -3.1, 1.0);
    m.position[1] = std::nan("");  // rejected_nan
    lcm.publish("FACT_VIO_RAW_2", &m);
  }
  m = raw(2, 1200000, 5.0, -3.1, 1.0);  // rejected_jump (49 m/s)
  lcm.publish("FACT_VIO_RAW_2", &m);
  m = raw(2, 1300000, 0.3, -2.9, 1.5);
  lcm.publish("FACT_VIO_RAW_2", &m);

  ASSERT_TRUE(l.pump_until([&] { return l.odometry().size() >= 3; })) << relay.err();
  EXPECT_EQ(relay.stop(), 0) << relay.err();
  const double flood_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - flood_start).count();
  ASSERT_TRUE(l.pump_until([&] { return l.has_state(2, "stopped"); })) << relay.err();

  const auto& odo = l.odometry();
  ASSERT_EQ(odo.size(), 3u);
  EXPECT_EQ(odo[0].utime, 1000000);
  EXPECT_EQ(odo[1].utime, 1100000);
  EXPECT_EQ(odo[2].utime, 1300000);
  EXPECT_NEAR(odo[0].yaw, 3.0, 1e-12);
  EXPECT_NEAR(odo[1].yaw, 2 * kPi - 3.1, 1e-12);
  EXPECT_NEAR(odo[2].yaw, 2 * kPi - 2.9, 1e-12);
  EXPECT_DOUBLE_EQ(odo[2].velocity[0], 1.5);  // the simulator's velocity, kept
  EXPECT_DOUBLE_EQ(odo[2].position[0], 0.3);
  EXPECT_DOUBLE_EQ(odo[2].roll, 0.01);
  EXPECT_DOUBLE_EQ(odo[2].pitch, -0.02);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(odo[k].seq, k);
    EXPECT_EQ(odo[k].drone_id, 2);
  }
  const fact::app_status_t last = l.statuses(2).back();
  EXPECT_EQ(counter(last, "published"), 3);
  EXPECT_EQ(counter(last, "wrong_drone_id"), 1);
  EXPECT_EQ(counter(last, "rejected_nan"), 51);
  EXPECT_EQ(counter(last, "rejected_out_of_order"), 1);
  EXPECT_EQ(counter(last, "undecodable"), 50);
  EXPECT_EQ(counter(last, "rejected_jump"), 1);
  const std::string log = relay.err();
  EXPECT_NE(log.find("from drone 7"), std::string::npos) << log;
  EXPECT_NE(log.find("rejected_nan: pitch is nan"), std::string::npos) << log;
  EXPECT_NE(log.find("undecodable message on FACT_VIO_RAW_2 (26 bytes, expected odometry_t)"), std::string::npos)
      << log;
  // At most one line per reason per second of flood (a bound from elapsed time, not a speed test).
  const int allowed = 1 + static_cast<int>(flood_s);
  EXPECT_GE(count_of(log, "undecodable message on"), 1);
  EXPECT_LE(count_of(log, "undecodable message on"), allowed) << log;
  EXPECT_LE(count_of(log, ": rejected_nan: "), allowed) << log;
}

// ---------------------------------------------------------------------------------------------
// Flags: no LCM is opened for any of these.

TEST_F(VioRelayTest, HelpExitsZeroAndDocumentsTheLineFormat) {
  Relay relay({"--help"}, dir_, "help");
  EXPECT_EQ(relay.wait(), 0);
  const std::string out = relay.out();
  for (const char* what : {"--source", "--file", "--rate", "--port", "--bind", "--max-speed", "--max-yaw-rate",
                           "--input-channel", "--output-channel", "--lcm-url", "--drone-id", "t tx ty tz qx qy qz qw",
                           "Hamilton", "rejected_nan"})
    EXPECT_NE(out.find(what), std::string::npos) << what << "\n" << out;
}

// A typo'd far-future time in a file replayed in real time put the relay to sleep for decades
// (review, session 30): now that line is rejected as a jump and not waited for.
TEST_F(VioRelayTest, FarFutureLineOfAReplayIsRejectedNotWaitedFor) {
  const fs::path file = dir_ / "typo.tum";
  {
    std::ofstream out(file);
    for (const char* t : {"0", "0.01", "1e9", "0.02", "0.03"}) out << t << " 0 0 1 0 0 0 1\n";
  }
  Relay relay({"--source", "tum", "--file", file.string(), "--rate", "1", "--lcm-url", "memq://"}, dir_, "typo");
  ASSERT_EQ(relay.wait(), 0) << relay.err();
  const std::string log = relay.err();
  EXPECT_NE(log.find("time gap of"), std::string::npos) << log;
  EXPECT_NE(log.find("published 4, rejected_jump 1"), std::string::npos) << log;
}

// A 10.7 s pause in a file replayed in real time: the lines after it are paced again from there
// (review, session 30: the first fix replayed everything after a pause at once), and the filter
// restarts the stream once over the gap.
TEST_F(VioRelayTest, ReplayAfterAPauseIsPacedAgain) {
  const fs::path file = dir_ / "pause.tum";
  {
    std::ofstream out(file);
    for (int k = 0; k <= 30; ++k) out << 0.0 + k / 30.0 << " 0 0 1 0 0 0 1\n";
    for (int k = 0; k <= 60; ++k) out << 12.0 + k / 30.0 << " 0 0 1 0 0 0 1\n";
  }
  const auto start = std::chrono::steady_clock::now();
  Relay relay({"--source", "tum", "--file", file.string(), "--rate", "1", "--lcm-url", "memq://"}, dir_, "pause");
  ASSERT_EQ(relay.wait(), 0) << relay.err();
  const double took_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GT(took_s, 2.8) << "the 2 s after the pause were not paced";
  EXPECT_LT(took_s, fact::test::scaled_s(8.0)) << "the pause itself was waited for";
  EXPECT_NE(relay.err().find("restarts 1"), std::string::npos) << relay.err();
}

TEST_F(VioRelayTest, BadFlagsExitTwoWithTheReason) {
  const std::string missing = (dir_ / "no-such.tum").string();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--source", "ros"}, "--source: expected lcm, tum or udp, got \"ros\""},
      {{"--source", "tum"}, "--source tum needs --file FILE"},
      {{"--source", "tum", "--file", missing}, "--file " + missing + ": cannot open"},
      {{"--source", "tum", "--file", dir_.string()}, "is a directory"},
      {{"--source", "tum", "--file", data("walk.tum"), "--rate", "-1"}, "--rate: expected 0 (as fast as possible) or"},
      {{"--source", "tum", "--file", data("walk.tum"), "--rate", "1e-12"}, "in [0.01, 1000], got 1e-12"},
      {{"--source", "tum", "--file", data("walk.tum"), "--rate", "2", "--restamp"}, "--restamp with --source tum needs --rate 1"},
      {{"--source", "udp"}, "--source udp needs --port in 1-65535, got 0"},
      {{"--source", "udp", "--port", "70000"}, "--source udp needs --port in 1-65535, got 70000"},
      {{"--source", "udp", "--port", "4000", "--bind", "localhost"}, "--bind: expected an IPv4 address"},
      {{"--file", data("walk.tum")}, "--file is only for --source tum (the source is lcm)"},
      {{"--source", "tum", "--file", data("walk.tum"), "--port", "4000"}, "--port is only for --source udp"},
      {{"--restamp"}, "--restamp is only for --source tum or udp"},
      {{"--max-speed", "0"}, "--max-speed: expected a finite number > 0, got 0"},
      {{"--max-yaw-rate", "-3"}, "--max-yaw-rate: expected a finite number > 0, got -3"},
      {{"--drone-id", "-1"}, "--drone-id: expected an id >= 0, got -1"},
      {{"--input-channel", "X", "--output-channel", "X"}, "the relay would feed itself"},
      {{"--status-channel", "FACT_VIO_RAW_0"}, "the relay would read its own heartbeats"},
      {{"--rate", "abc"}, "--rate"},
      {{"--bogus"}, "--bogus"},
  };
  int i = 0;
  for (const auto& [args, reason] : cases) {
    Relay relay(args, dir_, "bad" + std::to_string(i++));
    std::string joined;
    for (const auto& a : args) joined += a + " ";
    EXPECT_EQ(relay.wait(), 2) << joined;
    const std::string err = relay.err();
    EXPECT_NE(err.find(reason), std::string::npos) << joined << "\n" << err;
    EXPECT_EQ(err.rfind("fact-vio-relay: error: ", 0), 0u) << err;
  }
}

}  // namespace

// Runs the tests inside a private network namespace (see the top of this file).
int main(int argc, char** argv) { return fact::test::main_in_private_netns(argc, argv, FACT_NETNS_RUN); }
