// fact-sim as a real process over LCM udpm://, checked by a subscriber in this process: frames,
// raw VIO odometry, ground truth, the simulation clock and the status heartbeat arrive with the
// right sizes, ids and times; setpoints move a drone, bad setpoints are counted; a bad world file
// and bad flags exit 2 naming the problem.
//
// udpm must never leave the machine: main() re-executes this program through
// scripts/netns-run.sh (FACT_NETNS_RUN) unless it already sees no network interface but lo, and
// the URLs have ttl=0. Paths come from FACT_SIM_BINARY, FACT_NETNS_RUN.
#include "app_process.h"
#include "common/app.h"
#include "private_netns.h"
#include "test_time.h"
#include "fact/detections_t.hpp"
#include "fact/frame_t.hpp"
#include "fact/odometry_t.hpp"
#include "fact/setpoint_t.hpp"
#include "fact/sim_clock_t.hpp"
#include "fact/truth_t.hpp"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
constexpr int64_t kEpoch = 1700000000000000LL;

using fact::test::only_loopback;

std::string url(int port) { return "udpm://239.255.76.67:" + std::to_string(port) + "?ttl=0"; }
// The listener's URL: a 4 MB receive buffer (net.core.rmem_max permitting), since frames are
// 300 kB each and arrive in bursts at --rate 0.
std::string listen_url(int port) { return url(port) + "&recv_buf_size=4194304"; }

// fact-sim as a child process, stderr in a temporary file (removed with it), stdout discarded.
class SimProcess : private fact::test::TempFile, public fact::test::AppProcess {
 public:
  explicit SimProcess(const std::vector<std::string>& flags)
      : TempFile("fact-sim-test"),
        AppProcess(fact::test::command_line(FACT_SIM_BINARY, flags), "/dev/null", TempFile::path()) {}
  // The exit code once it exits (AppProcess::wait_for; −1 if it is still running after timeout_s).
  int wait(double timeout_s = 20) { return wait_s(timeout_s); }
};

// Everything fact-sim publishes, collected per channel.
class Listener {
 public:
  explicit Listener(const std::string& u) : lcm_(u) {
    sub("FACT_FRAMES_.*", [this](const lcm::ReceiveBuffer* b, const std::string& ch) {
      fact::frame_t m;
      if (fact::app::decode_error(b->data, static_cast<int>(b->data_size), &m).empty()) frames[ch].push_back(m);
    });
    sub("FACT_VIO_RAW_.*", [this](const lcm::ReceiveBuffer* b, const std::string& ch) {
      fact::odometry_t m;
      if (fact::app::decode_error(b->data, static_cast<int>(b->data_size), &m).empty()) odometry[ch].push_back(m);
    });
    sub("FACT_TRUTH", [this](const lcm::ReceiveBuffer* b, const std::string&) {
      fact::truth_t m;
      if (fact::app::decode_error(b->data, static_cast<int>(b->data_size), &m).empty()) truth.push_back(m);
    });
    sub("FACT_SIM_CLOCK", [this](const lcm::ReceiveBuffer* b, const std::string&) {
      fact::sim_clock_t m;
      if (fact::app::decode_error(b->data, static_cast<int>(b->data_size), &m).empty()) clock.push_back(m);
    });
    sub("FACT_STATUS", [this](const lcm::ReceiveBuffer* b, const std::string&) {
      fact::app_status_t m;
      if (fact::app::decode_error(b->data, static_cast<int>(b->data_size), &m).empty()) status.push_back(m);
    });
  }
  bool good() { return lcm_.good(); }
  lcm::LCM& lcm() { return lcm_; }
  // Handles messages until done() or timeout_s × FACT_TEST_TIME_SCALE.
  bool pump_until(const std::function<bool()>& done, double timeout_s = 15) {
    const auto end = std::chrono::steady_clock::now() + fact::test::scaled(std::chrono::duration<double>(timeout_s));
    while (std::chrono::steady_clock::now() < end) {
      if (done()) return true;
      lcm_.handleTimeout(20);
    }
    return done();
  }
  bool stopped() const { return !status.empty() && status.back().state == "stopped"; }
  int64_t counter(const std::string& name) const {
    if (status.empty()) return -1;
    return fact::app::counter_value(status.back(), name).value_or(0);
  }

  std::map<std::string, std::vector<fact::frame_t>> frames;
  std::map<std::string, std::vector<fact::odometry_t>> odometry;
  std::vector<fact::truth_t> truth;
  std::vector<fact::sim_clock_t> clock;
  std::vector<fact::app_status_t> status;

 private:
  using Handler = std::function<void(const lcm::ReceiveBuffer*, const std::string&)>;
  struct Thunk {
    Handler h;
    void on(const lcm::ReceiveBuffer* b, const std::string& ch) { h(b, ch); }
  };
  void sub(const std::string& ch, Handler h) {
    thunks_.push_back(std::make_unique<Thunk>(Thunk{std::move(h)}));
    lcm_.subscribe(ch, &Thunk::on, thunks_.back().get())->setQueueCapacity(100000);
  }
  lcm::LCM lcm_;
  std::vector<std::unique_ptr<Thunk>> thunks_;
};

class SimApp : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!only_loopback()) GTEST_SKIP() << "not in a private network namespace: run through scripts/netns-run.sh (ctest does)";
  }
};

TEST_F(SimApp, TwoSimulatedSecondsOfFramesOdometryTruthAndClock) {
  Listener l(listen_url(7801));
  ASSERT_TRUE(l.good());
  SimProcess sim({"--duration", "2", "--rate", "0", "--drones", "3", "--seed", "4", "--script", "hover", "--lcm-url",
                  url(7801)});
  ASSERT_TRUE(sim.started());
  ASSERT_TRUE(l.pump_until([&] { return l.stopped(); })) << sim.err();
  l.pump_until([] { return false; }, 0.3);  // stragglers
  ASSERT_EQ(sim.wait(), 0) << sim.err();

  // Clock: every 10 ms of sim time from the epoch to epoch + 2 s (201 ticks), strictly increasing.
  EXPECT_GE(l.clock.size(), 190u);
  ASSERT_FALSE(l.clock.empty());
  EXPECT_EQ(l.clock.back().utime, kEpoch + 2000000);
  for (size_t i = 1; i < l.clock.size(); ++i) ASSERT_GT(l.clock[i].utime, l.clock[i - 1].utime);
  EXPECT_EQ(l.clock.back().rate, 0.0);

  for (int id = 0; id < 3; ++id) {
    SCOPED_TRACE("drone " + std::to_string(id));
    // Frames at 15 Hz: t = 0, 66.7 ms, … 2 s → 31, each 424 × 240 with intrinsics.
    const auto& fr = l.frames["FACT_FRAMES_" + std::to_string(id)];
    EXPECT_GE(fr.size(), 28u);
    EXPECT_LE(fr.size(), 31u);
    for (const auto& f : fr) {
      ASSERT_EQ(f.drone_id, id);
      ASSERT_EQ(f.width, 424);
      ASSERT_EQ(f.height, 240);
      ASSERT_EQ(f.gray_size, 424 * 240);
      ASSERT_EQ(f.depth_size, 424 * 240);
      ASSERT_EQ(f.gray.size(), 424u * 240u);
      ASSERT_EQ(f.depth_mm.size(), 424u * 240u);
      ASSERT_DOUBLE_EQ(f.fx, 213.0);
      ASSERT_GE(f.utime, kEpoch);
      ASSERT_LE(f.utime, kEpoch + 2000000);
      int valid = 0;
      for (int16_t d : f.depth_mm) valid += (d > 0 && d <= 13000) ? 1 : 0;
      ASSERT_GT(valid, 424 * 240 / 2);  // a 10 m room: most pixels have depth
    }
    if (fr.size() >= 2) {
      EXPECT_EQ(fr[1].seq, fr[0].seq + 1);
    }
    // Odometry at 100 Hz: 201 samples; seq counts up; hover takes off (z grows, in f_i).
    const auto& od = l.odometry["FACT_VIO_RAW_" + std::to_string(id)];
    EXPECT_GE(od.size(), 190u);
    ASSERT_FALSE(od.empty());
    for (size_t i = 1; i < od.size(); ++i) ASSERT_GT(od[i].seq, od[i - 1].seq);
    EXPECT_NEAR(od.front().position[2], 0.0, 0.01);
    EXPECT_GT(od.back().position[2], 0.5);
    EXPECT_EQ(od.back().drone_id, id);
  }
  // Truth at 10 Hz: 21 messages with all three drones; positions in the room.
  EXPECT_GE(l.truth.size(), 19u);
  ASSERT_FALSE(l.truth.empty());
  const auto& t = l.truth.back();
  ASSERT_EQ(t.num_drones, 3);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(t.drone_ids[static_cast<size_t>(i)], i);
    EXPECT_LE(std::abs(t.position[static_cast<size_t>(i)][0]), 5.0);
    EXPECT_GT(t.position[static_cast<size_t>(i)][2], 0.5);
    EXPECT_EQ(t.frame_origin[static_cast<size_t>(i)][2], 0.0);
  }
  EXPECT_EQ(l.counter("frames"), 93);
  EXPECT_EQ(l.counter("odometry"), 603);
  EXPECT_NE(sim.err().find("takeoff done"), std::string::npos) << sim.err();
}

TEST_F(SimApp, SetpointsMoveADroneAndBadOnesAreCounted) {
  Listener l(listen_url(7802));
  ASSERT_TRUE(l.good());
  SimProcess sim({"--duration", "3", "--rate", "1", "--drones", "2", "--camera-rate", "2", "--lcm-url", url(7802)});
  ASSERT_TRUE(sim.started());
  ASSERT_TRUE(l.pump_until([&] { return !l.clock.empty(); })) << sim.err();
  fact::setpoint_t sp{};
  sp.utime = l.clock.back().utime;
  sp.drone_id = 1;
  sp.position[2] = 1.0;
  l.lcm().publish("FACT_SETPOINT_1", &sp);
  fact::setpoint_t wrong = sp;
  wrong.drone_id = 0;
  l.lcm().publish("FACT_SETPOINT_1", &wrong);
  fact::setpoint_t nan = sp;
  nan.yaw = std::nan("");
  l.lcm().publish("FACT_SETPOINT_1", &nan);
  fact::setpoint_t huge = sp;  // finite, but the controller's clamp made it command nothing
  huge.position[0] = 1e200;
  l.lcm().publish("FACT_SETPOINT_1", &huge);
  l.lcm().publish("FACT_SETPOINT_0", "garbage!", 8);
  ASSERT_TRUE(l.pump_until([&] { return l.stopped(); })) << sim.err();
  ASSERT_EQ(sim.wait(), 0) << sim.err();
  EXPECT_EQ(l.counter("setpoints"), 1);
  EXPECT_EQ(l.counter("wrong_drone_id"), 1);
  EXPECT_EQ(l.counter("rejected_nan"), 1);
  EXPECT_EQ(l.counter("rejected_range"), 1);
  EXPECT_EQ(l.counter("undecodable"), 1);
  const std::string err = sim.err();
  EXPECT_NE(err.find("first setpoint for drone 1"), std::string::npos) << err;
  EXPECT_NE(err.find("yaw = nan"), std::string::npos) << err;
  EXPECT_NE(err.find("position[0] = 1e+200 (|position| <= 1000 m), ignored"), std::string::npos) << err;
  // Drone 1 climbs towards 1 m; drone 0, without setpoints, stays on the floor.
  const auto& o1 = l.odometry["FACT_VIO_RAW_1"];
  const auto& o0 = l.odometry["FACT_VIO_RAW_0"];
  ASSERT_FALSE(o1.empty());
  ASSERT_FALSE(o0.empty());
  EXPECT_GT(o1.back().position[2], 0.7);
  EXPECT_LT(std::abs(o0.back().position[2]), 0.1);  // VIO drift only (σ ≈ 0.017 m after 3 s)
  ASSERT_FALSE(l.truth.empty());
  EXPECT_EQ(l.truth.back().position[0][2], 0.0);     // truly still on the floor
  EXPECT_GT(l.truth.back().position[1][2], 0.7);
}

// Same seed → the same bytes: two runs publish identical frames and odometry (compared by seq,
// in case UDP dropped one), and another seed differs.
TEST_F(SimApp, SameSeedSameBytes) {
  auto run = [](int port, const std::string& seed) {
    auto l = std::make_unique<Listener>(listen_url(port));
    SimProcess sim({"--duration", "0.5", "--rate", "0", "--drones", "2", "--script", "spin", "--seed", seed,
                    "--lcm-url", url(port)});
    EXPECT_TRUE(l->pump_until([&] { return l->stopped(); })) << sim.err();
    l->pump_until([] { return false; }, 0.2);
    EXPECT_EQ(sim.wait(), 0) << sim.err();
    return l;
  };
  auto a = run(7803, "9"), b = run(7804, "9"), c = run(7805, "10");
  int compared = 0;
  for (const auto& fa : a->frames["FACT_FRAMES_1"])
    for (const auto& fb : b->frames["FACT_FRAMES_1"])
      if (fa.seq == fb.seq) {
        EXPECT_EQ(fa.utime, fb.utime);
        EXPECT_EQ(fa.gray, fb.gray);
        EXPECT_EQ(fa.depth_mm, fb.depth_mm);
        ++compared;
      }
  EXPECT_GE(compared, 3);
  const auto& oa = a->odometry["FACT_VIO_RAW_0"];
  const auto& ob = b->odometry["FACT_VIO_RAW_0"];
  const auto& oc = c->odometry["FACT_VIO_RAW_0"];
  ASSERT_FALSE(oa.empty());
  ASSERT_FALSE(oc.empty());
  for (const auto& x : oa)
    for (const auto& y : ob)
      if (x.seq == y.seq) {
        ASSERT_EQ(x.utime, y.utime);
        for (int k = 0; k < 3; ++k) ASSERT_EQ(x.position[k], y.position[k]);
        ASSERT_EQ(x.yaw, y.yaw);
      }
  EXPECT_NE(oa.back().position[2], oc.back().position[2]);  // another seed: another height, drift
}

// --frames-url: each drone's frames go to its own URL ("{id}" replaced), none to --lcm-url; the
// frames do not depend on --render-threads.
TEST_F(SimApp, FramesOnPerDroneUrlsAndRenderThreadsDoNotChangeThem) {
  auto run = [](int port, const std::string& threads) {
    auto main_bus = std::make_unique<Listener>(listen_url(port));
    std::vector<std::unique_ptr<Listener>> cams;
    for (int id = 0; id < 2; ++id)
      cams.push_back(std::make_unique<Listener>("udpm://239.255.77." + std::to_string(id) + ":" +
                                                std::to_string(port + 1 + id) + "?ttl=0&recv_buf_size=4194304"));
    SimProcess sim({"--duration", "0.5", "--rate", "0", "--drones", "2", "--script", "spin", "--seed", "4",
                    "--render-threads", threads, "--lcm-url", url(port), "--frames-url",
                    "udpm://239.255.77.{id}:{" + std::to_string(port + 1) + "+id}?ttl=0"});
    EXPECT_TRUE(main_bus->pump_until([&] { return main_bus->stopped(); })) << sim.err();
    for (auto& c : cams) c->pump_until([] { return false; }, 0.2);
    EXPECT_EQ(sim.wait(), 0) << sim.err();
    EXPECT_TRUE(main_bus->frames.empty()) << "frames leaked onto --lcm-url";
    EXPECT_FALSE(main_bus->odometry.empty());
    for (int id = 0; id < 2; ++id) {
      const std::string own = "FACT_FRAMES_" + std::to_string(id), other = "FACT_FRAMES_" + std::to_string(1 - id);
      EXPECT_GE(cams[static_cast<size_t>(id)]->frames[own].size(), 4u) << own;
      EXPECT_TRUE(cams[static_cast<size_t>(id)]->frames[other].empty()) << other << " reached drone " << id << "'s URL";
    }
    return cams;
  };
  auto one = run(7810, "1"), two = run(7820, "2");
  int compared = 0;
  for (const auto& fa : one[1]->frames["FACT_FRAMES_1"])
    for (const auto& fb : two[1]->frames["FACT_FRAMES_1"])
      if (fa.seq == fb.seq) {
        EXPECT_EQ(fa.depth_mm, fb.depth_mm);
        EXPECT_EQ(fa.gray, fb.gray);
        ++compared;
      }
  EXPECT_GE(compared, 3);
}

// Drone 0's stand-in detector for --lockstep: answers every FACT_FRAMES_0 it hears with an empty
// fact::detections_t of that frame on `bus`, and counts the answers.
struct DetectorAnswer {
  lcm::LCM* bus;
  int64_t* answered;
  void on(const lcm::ReceiveBuffer* b, const std::string&) {
    fact::frame_t f;
    if (!fact::app::decode_error(b->data, static_cast<int>(b->data_size), &f).empty()) return;
    fact::detections_t d;
    d.utime = f.utime;
    d.drone_id = f.drone_id;
    d.frame_seq = f.seq;
    d.count = 0;
    bus->publish("FACT_DETECTIONS_0", &d);
    ++*answered;
  }
};

// How often fact-sim's log says that drone `id`'s detector timed out.
size_t lockstep_timeouts_of(const std::string& err, int id) {
  const std::string needle = "drone " + std::to_string(id) + "'s detector has not answered";
  size_t n = 0;
  for (size_t at = err.find(needle); at != std::string::npos; at = err.find(needle, at + 1)) ++n;
  return n;
}

// --drone-url: each drone's raw VIO and the clock go to its own bus, none of its VIO to --lcm-url
// (truth and the clock stay there), and --lockstep hears a detector's answer on its drone's bus.
TEST_F(SimApp, DroneBusesCarryEachDronesVioClockAndLockstep) {
  const int port = 7830;
  Listener main_bus(listen_url(port));
  std::vector<std::unique_ptr<Listener>> buses;
  for (int id = 0; id < 2; ++id)
    buses.push_back(std::make_unique<Listener>("udpm://239.255.78." + std::to_string(id) + ":" +
                                               std::to_string(port + 1 + id) + "?ttl=0&recv_buf_size=4194304"));
  int64_t answered = 0;
  DetectorAnswer answer{&buses[0]->lcm(), &answered};  // frames from the main bus, answers on drone 0's bus
  main_bus.lcm().subscribe("FACT_FRAMES_0", &DetectorAnswer::on, &answer);
  SimProcess sim({"--duration", "1.0", "--rate", "0", "--drones", "2", "--camera-rate", "10", "--lockstep",
                  "--lockstep-timeout", "2", "--lcm-url", url(port), "--drone-url",
                  "udpm://239.255.78.{id}:{" + std::to_string(port + 1) + "+id}?ttl=0"});
  EXPECT_TRUE(main_bus.pump_until([&] { return main_bus.stopped(); }, 30)) << sim.err();
  for (auto& b : buses) b->pump_until([] { return false; }, 0.2);
  EXPECT_EQ(sim.wait(), 0) << sim.err();
  EXPECT_TRUE(main_bus.odometry.empty()) << "raw VIO leaked onto --lcm-url";
  EXPECT_FALSE(main_bus.truth.empty());
  EXPECT_FALSE(main_bus.clock.empty());
  for (int id = 0; id < 2; ++id) {
    const Listener& b = *buses[static_cast<size_t>(id)];
    const std::string own = "FACT_VIO_RAW_" + std::to_string(id), other = "FACT_VIO_RAW_" + std::to_string(1 - id);
    ASSERT_TRUE(b.odometry.count(own)) << own << " is not on drone " << id << "'s bus";
    EXPECT_GE(b.odometry.at(own).size(), 50u) << own;
    EXPECT_FALSE(b.odometry.count(other)) << other << " reached drone " << id << "'s bus";
    EXPECT_GE(b.clock.size(), 50u) << "drone " << id << "'s bus has no clock";
    EXPECT_TRUE(b.truth.empty()) << "truth on drone " << id << "'s bus";
  }
  // Drone 1 has no detector: timed out once. Drone 0's answers, on its own bus, were heard (a
  // frame lost to UDP on a loaded machine can time it out, at most twice).
  const std::string err = sim.err();
  EXPECT_EQ(lockstep_timeouts_of(err, 1), 1u) << err;
  EXPECT_LE(lockstep_timeouts_of(err, 0), 2u) << err;
  EXPECT_GE(answered, 8);
}

// --lockstep: a frame waits for every drone's detections of the previous frame. Drone 0's
// "detector" (this test) answers every frame it receives; drone 1 has none, so it times out once
// and is then not waited for, which the log names. A frame this process did not receive (UDP on a
// loaded machine) can time drone 0 out too, so drone 0 is only required to be waited for: it
// answered most frames and timed out at most twice.
TEST_F(SimApp, LockstepWaitsForTheDetectorsAndGoesOnWithoutASilentOne) {
  Listener l(listen_url(7814));
  int64_t answered = 0;
  DetectorAnswer answer{&l.lcm(), &answered};
  l.lcm().subscribe("FACT_FRAMES_0", &DetectorAnswer::on, &answer);
  SimProcess sim({"--duration", "1.0", "--rate", "0", "--drones", "2", "--camera-rate", "10", "--lockstep",
                  "--lockstep-timeout", "2", "--lcm-url", url(7814)});
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_TRUE(l.pump_until([&] { return l.stopped(); }, 30)) << sim.err();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(sim.wait(), 0) << sim.err();
  const std::string err = sim.err();
  EXPECT_NE(err.find("drone 1's detector has not answered"), std::string::npos) << err;
  const size_t drone0_timeouts = lockstep_timeouts_of(err, 0);
  EXPECT_LE(drone0_timeouts, 2u) << err;
  EXPECT_EQ(l.counter("lockstep_timeouts"), static_cast<int64_t>(1 + drone0_timeouts)) << err;
  EXPECT_GE(wall, 2.0);            // drone 1's timeout was waited out
  EXPECT_GE(answered, 8);          // 1 s at 10 Hz: frames 0..10
}

TEST(SimAppFlags, PrintIdsAndBadRunFlags) {
  {
    const std::string cmd = std::string(FACT_SIM_BINARY) + " --print-ids --world " FACT_WORLDS_DIR "/small.json --drones 5";
    FILE* p = popen(cmd.c_str(), "r");
    ASSERT_NE(p, nullptr);
    char buf[128] = {0};
    const size_t n = fread(buf, 1, sizeof buf - 1, p);
    EXPECT_EQ(pclose(p), 0);
    EXPECT_EQ(std::string(buf, n), "0 1 2 3 4\n");  // small.json: ids 0..count-1
  }
  // Rates above the 100 Hz the 10 ms batches can serve (1e11 spun deaf to SIGTERM), durations and
  // epochs near int64 µs overflow, a signed seed (read as 2^64 − 1) exit 2 naming flag and value;
  // so do rates so small that a sample time leaves int64 µs (1e-14 Hz spun deaf to SIGTERM, review,
  // session 33).
  for (const auto& [flag, value] : std::vector<std::pair<std::string, std::string>>{
           {"--render-threads", "0"}, {"--lockstep-timeout", "-1"}, {"--odometry-rate", "1e11"},
           {"--camera-rate", "101"}, {"--truth-rate", "nan"}, {"--duration", "1e300"},
           {"--epoch-utime", "9223372036854775000"}, {"--seed", "-1"}, {"--spin-rate", "2"},
           {"--truth-rate", "1e-14"}, {"--camera-rate", "1e-14"}, {"--rate", "1e-20"}}) {
    SimProcess sim({flag, value, "--lcm-url", "memq://"});
    EXPECT_EQ(sim.wait(), 2) << flag << " " << value;
    EXPECT_NE(sim.err().find(flag), std::string::npos) << sim.err();
  }
  // A world's ids are kept: fewer drones take the first ids, more than it lists is refused (they
  // were replaced by 0 … N−1, so the FACT_*_<id> channels of the world's ids went unused).
  char tmpl[] = "/tmp/fact-sim-ids-XXXXXX";
  const int fd = mkstemp(tmpl);
  const std::string text =
      R"({"format": "fact-world-v1", "room": {"size": [6, 6, 3]}, "drones": {"count": 2, "ids": [5, 7], "start": "random"}})";
  ASSERT_EQ(write(fd, text.data(), text.size()), static_cast<ssize_t>(text.size()));
  close(fd);
  const auto print_ids = [&](const std::string& drones, int* code) {
    const std::string cmd = std::string(FACT_SIM_BINARY) + " --print-ids --world " + tmpl + " --drones " + drones + " 2>&1";
    FILE* p = popen(cmd.c_str(), "r");
    char buf[512] = {0};
    const size_t n = p ? fread(buf, 1, sizeof buf - 1, p) : 0;
    *code = p ? WEXITSTATUS(pclose(p)) : -1;
    return std::string(buf, n);
  };
  int code = 0;
  EXPECT_EQ(print_ids("1", &code), "5\n");
  EXPECT_EQ(code, 0);
  const std::string more = print_ids("3", &code);
  EXPECT_EQ(code, 2);
  EXPECT_NE(more.find("--drones: 3 but the world file lists only 2 ids"), std::string::npos) << more;
  fs::remove(tmpl);
}

TEST(SimAppFlags, BadWorldFileAndFlagsExitTwoWithTheReason) {
  char tmpl[] = "/tmp/fact-sim-world-XXXXXX";
  int fd = mkstemp(tmpl);
  const std::string text = R"({"format": "fact-world-v1", "room": {"size": [4, 4, -3]}})";
  ASSERT_EQ(write(fd, text.data(), text.size()), static_cast<ssize_t>(text.size()));
  close(fd);
  {
    SimProcess sim({"--world", tmpl, "--lcm-url", "memq://"});
    ASSERT_TRUE(sim.started());
    EXPECT_EQ(sim.wait(), 2);
    EXPECT_NE(sim.err().find("room.size[2]: expected a number > 0, got -3"), std::string::npos) << sim.err();
  }
  fs::remove(tmpl);
  {
    // A FIFO nobody writes to is read as empty, not waited on (review, session 33: it hung), and
    // a device is refused (/dev/zero grew without end); a pipe with a world in it (a shell's
    // <(...)) is read as before.
    const std::string fifo = std::string(tmpl) + ".fifo";
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    SimProcess sim({"--world", fifo, "--lcm-url", "memq://"});
    EXPECT_EQ(sim.wait(), 2);
    EXPECT_NE(sim.err().find(fifo + ": "), std::string::npos) << sim.err();
    fs::remove(fifo);
    SimProcess zero({"--world", "/dev/zero", "--lcm-url", "memq://"});
    EXPECT_EQ(zero.wait(), 2);
    EXPECT_NE(zero.err().find("/dev/zero: a device, not a file"), std::string::npos) << zero.err();
    const std::string cmd = std::string("bash -c '") + FACT_SIM_BINARY + " --print-ids --world <(cat " FACT_WORLDS_DIR
                            "/small.json)'";
    FILE* p = popen(cmd.c_str(), "r");
    ASSERT_NE(p, nullptr);
    char buf[64] = {0};
    const size_t n = fread(buf, 1, sizeof buf - 1, p);
    EXPECT_EQ(pclose(p), 0);
    EXPECT_EQ(std::string(buf, n), "0 1 2\n");
  }
  {
    SimProcess sim({"--resolution", "320x200", "--lcm-url", "memq://"});
    EXPECT_EQ(sim.wait(), 2);
    EXPECT_NE(sim.err().find("--resolution"), std::string::npos) << sim.err();
  }
  {
    SimProcess sim({"--help"});
    EXPECT_EQ(sim.wait(), 0);
  }
}

}  // namespace

int main(int argc, char** argv) { return fact::test::main_in_private_netns(argc, argv, FACT_NETNS_RUN); }
