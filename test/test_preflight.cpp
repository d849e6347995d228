// fact-preflight as a process, fed crafted fc_state_t, frame_t and odometry_t over LCM udpm:// by
// this test: each item passes on what the apps take and fails, naming the field and value, on what
// they would refuse (review, helper-21: frames with no valid depth or bad intrinsics, odometry of
// another drone, NaN, frozen, or on another clock than the camera, and a flight controller in
// emergency all passed). The whole binary re-runs itself in a private network namespace
// (scripts/netns-run.sh), as every udpm test does.
#include "fact/fc_state_t.hpp"
#include "fact/frame_t.hpp"
#include "fact/odometry_t.hpp"
#include "app_process.h"
#include "private_netns.h"
#include "temp_dir.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

namespace {

const std::string kUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
constexpr int kDrone = 3;

// What the healthy drone publishes; each test breaks one thing.
struct Hardware {
  int fc_status = 3;                 // MAV_STATE_STANDBY
  int fc_drone = kDrone;
  int frame_drone = kDrone;
  double fy = 213;                   // px
  bool depth = true;                 // some valid depth
  int depth_from = 0;                // frames before this one have none (a camera warming up)
  int restart_at = -1;               // the relay restarts its stream (seq 0 again) here
  int odometry_drone = kDrone;
  double roll = 0;                   // rad
  bool frozen = false;               // the same seq and utime again and again
  int64_t odometry_offset_us = 0;    // odometry clock − camera clock
  bool extreme_clocks = false;       // frames from INT64_MAX − 0.2 s, odometry from INT64_MIN + 0.2 s,
                                     // both advancing 1 ms a message
};

class Preflight : public fact::test::TempDirTest {
 protected:
  Preflight() : TempDirTest("fact-preflight") {}

  // Runs fact-preflight (--insecure, 1.5 s) while publishing `hw` at 20 Hz: its exit code and output.
  std::pair<int, std::string> run(const Hardware& hw) {
    lcm::LCM lcm(kUrl);
    EXPECT_TRUE(lcm.good());
    fact::test::AppProcess p({FACT_PREFLIGHT_BINARY, "--drone-id", std::to_string(kDrone), "--lcm-url", kUrl, "--insecure",
                              "--timeout", "1.5"},
                             dir_ / "out", dir_ / "out");
    EXPECT_TRUE(p.started());
    const int64_t t0 = 1700000000000000;
    for (int k = 0; p.running() && k < 150; ++k) {
      const int64_t t = hw.extreme_clocks ? std::numeric_limits<int64_t>::max() - 200000 + k * 1000
                                          : t0 + k * 50000;  // µs
      fact::fc_state_t fc{};
      fc.utime = t;
      fc.drone_id = hw.fc_drone;
      fc.connected = true;
      fc.system_status = hw.fc_status;
      fc.heartbeat_age_ms = 40;
      lcm.publish("FACT_FC_STATE_3", &fc);
      fact::odometry_t o{};
      const bool restarted = hw.restart_at >= 0 && k >= hw.restart_at;
      o.utime = hw.extreme_clocks ? std::numeric_limits<int64_t>::min() + 200000 + k * 1000
                                  : (hw.frozen ? t0 : t) + hw.odometry_offset_us;
      o.seq = hw.frozen ? 0 : restarted ? k - hw.restart_at : k;
      o.drone_id = hw.odometry_drone;
      o.position[2] = 1.0;
      o.roll = hw.roll;
      lcm.publish("FACT_ODOMETRY_3", &o);
      fact::frame_t f{};
      f.utime = t;
      f.drone_id = hw.frame_drone;
      f.seq = k;
      f.width = 64;
      f.height = 48;
      f.fx = 213, f.fy = hw.fy, f.cx = 32, f.cy = 24;
      f.gray_size = f.depth_size = 64 * 48;
      f.gray.assign(64 * 48, 100);
      f.depth_mm.assign(64 * 48, static_cast<int16_t>(hw.depth && k >= hw.depth_from ? 3000 : 0));
      lcm.publish("FACT_FRAMES_3", &f);
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return {p.wait_for(std::chrono::seconds(5)), p.out()};
  }
};

TEST_F(Preflight, HealthyHardwarePassesEveryItem) {
  const auto [code, out] = run({});
  EXPECT_EQ(code, 0) << out;
  EXPECT_NE(out.find("[PASS] flight controller HEARTBEAT 40 ms old, MAV_STATE 3 (standby)"), std::string::npos) << out;
  EXPECT_NE(out.find("[PASS] camera"), std::string::npos) << out;
  EXPECT_NE(out.find("[PASS] VIO"), std::string::npos) << out;
}

// What the apps take passes too: a camera's first frames without depth, and the relay restarting
// its stream (seq 0 again) — review, helper-23.
TEST_F(Preflight, WarmUpFramesAndAnOdometryRestartPass) {
  Hardware hw;
  hw.depth_from = 3;
  hw.restart_at = 1;
  const auto [code, out] = run(hw);
  EXPECT_EQ(code, 0) << out;
}

// Each case: what is broken, and the words the failed item must say.
TEST_F(Preflight, WhatTheAppsWouldRefuseFailsItsItemNamingIt) {
  struct Case {
    const char* what;
    std::function<void(Hardware&)> breaks;
    std::string line;
  };
  const std::vector<Case> cases = {
      {"FC in emergency", [](Hardware& h) { h.fc_status = 6; }, "[FAIL] flight controller HEARTBEAT fresh but the flight "
                                                                 "controller is not ready: MAV_STATE 6 (emergency)"},
      {"another drone's FC", [](Hardware& h) { h.fc_drone = 7; }, "[FAIL] flight controller fc_state of drone 7"},
      {"no valid depth", [](Hardware& h) { h.depth = false; }, "depth_mm is 0 at every pixel"},
      {"fy NaN", [](Hardware& h) { h.fy = std::nan(""); }, "intrinsics: fy = nan"},
      {"another drone's frames", [](Hardware& h) { h.frame_drone = 4; }, "drone_id = 4, expected 3"},
      {"another drone's odometry", [](Hardware& h) { h.odometry_drone = 7; }, "[FAIL] VIO               odometry of drone 7"},
      {"NaN roll", [](Hardware& h) { h.roll = std::nan(""); }, "roll = nan (must be finite)"},
      {"frozen VIO", [](Hardware& h) { h.frozen = true; }, "not increasing (a frozen or repeating VIO)"},
      {"VIO on the boot clock", [](Hardware& h) { h.odometry_offset_us = -1699990000000000; },
       "the VIO and the camera are on different clocks"},
      // 2^64 − 0.4 s apart: the stamps' int64 difference wraps to 0.4 s, which once passed.
      {"clocks at the ends of int64", [](Hardware& h) { h.extreme_clocks = true; },
       "the VIO and the camera are on different clocks"},
  };
  for (const Case& c : cases) {
    Hardware hw;
    c.breaks(hw);
    const auto [code, out] = run(hw);
    EXPECT_EQ(code, 1) << c.what << "\n" << out;
    EXPECT_NE(out.find(c.line), std::string::npos) << c.what << "\n" << out;
    EXPECT_NE(out.find("must not fly"), std::string::npos) << c.what;
  }
}

// The offline items, as the apps would read their inputs (review, session 33): a key file that is
// a FIFO hung the check and /dev/zero grew it without end; a --png-dir whose intrinsics.json the
// detector refuses, or whose pairs it ignores (not <utime>_gray.png), passed; a symbolic link loop
// threw out of the check. Each now fails its item, naming why, within the timeout.
TEST_F(Preflight, KeyFileAndPngDirAreCheckedAsTheAppsReadThem) {
  namespace fs = std::filesystem;
  const auto preflight = [&](const std::vector<std::string>& extra) {
    std::vector<std::string> args{FACT_PREFLIGHT_BINARY, "--drone-id", std::to_string(kDrone), "--lcm-url", "memq://",
                                  "--timeout", "0.5"};
    args.insert(args.end(), extra.begin(), extra.end());
    fact::test::AppProcess p(args, dir_ / "out", dir_ / "out");
    EXPECT_TRUE(p.started());
    const int code = p.wait_for(std::chrono::seconds(10));  // (-1: still running, the old hang)
    return std::pair<int, std::string>{code, p.out()};
  };
  ASSERT_EQ(::mkfifo((dir_ / "key.fifo").c_str(), 0600), 0);
  for (const std::string& key : {(dir_ / "key.fifo").string(), std::string("/dev/zero")}) {
    const auto [code, out] = preflight(std::vector<std::string>{"--key-file", key});
    EXPECT_EQ(code, 1) << key << "\n" << out;
    EXPECT_NE(out.find("[FAIL] swarm key         " + key + " is not a regular file"), std::string::npos) << out;
  }
  const fs::path png = dir_ / "png";
  fs::create_directories(png);
  const auto write = [](const fs::path& p, const std::string& text) { std::ofstream(p) << text; };
  write(png / "intrinsics.json", "not json");
  write(png / "cam_gray.png", ""), write(png / "cam_depth.png", "");
  auto [code, out] = preflight(std::vector<std::string>{"--insecure", "--png-dir", png.string()});
  EXPECT_EQ(code, 1) << out;
  EXPECT_NE(out.find("[FAIL] camera"), std::string::npos) << out;
  EXPECT_NE(out.find((png / "intrinsics.json").string() + ": "), std::string::npos) << out;
  write(png / "intrinsics.json", R"({"width": 64, "height": 48, "fx": 213, "fy": 213, "cx": 32, "cy": 24})");
  std::tie(code, out) = preflight(std::vector<std::string>{"--insecure", "--png-dir", png.string()});
  EXPECT_NE(out.find("[FAIL] camera            0 gray/depth PNG pairs"), std::string::npos) << out;  // "cam" is no utime
  write(png / "1700000000000000_gray.png", ""), write(png / "1700000000000000_depth.png", "");
  std::tie(code, out) = preflight(std::vector<std::string>{"--insecure", "--png-dir", png.string()});
  EXPECT_NE(out.find("[PASS] camera            1 gray/depth PNG pairs"), std::string::npos) << out;
  write(png / "99999999999999999999_gray.png", ""), write(png / "99999999999999999999_depth.png", "");
  std::tie(code, out) = preflight(std::vector<std::string>{"--insecure", "--png-dir", png.string()});
  EXPECT_NE(out.find("the time 99999999999999999999 us does not fit in 64 bits"), std::string::npos) << out;
  fs::remove(png / "99999999999999999999_gray.png"), fs::remove(png / "99999999999999999999_depth.png");
  fs::remove(png / "intrinsics.json");
  fs::create_symlink(png / "intrinsics.json", png / "intrinsics.json");  // a loop
  std::tie(code, out) = preflight(std::vector<std::string>{"--insecure", "--png-dir", png.string()});
  EXPECT_EQ(code, 1) << out;
  EXPECT_NE(out.find("[FAIL] camera"), std::string::npos) << out;
}

}  // namespace

int main(int argc, char** argv) { return fact::test::main_in_private_netns(argc, argv, FACT_NETNS_RUN); }
