// fact-detector as a process: --png-dir frames painted here (PNG pairs, intrinsics.json,
// odometry.tum), detections received over LCM udpm:// by this process and checked against the
// painted drone (one track, its id kept, its range and vector), the bad pair counted in the final
// status; flags (--help, bad flags and an unloadable model → exit 2 with the reason).
//
// udpm never leaves the machine: main() re-executes this program through scripts/netns-run.sh
// (FACT_NETNS_RUN) unless only lo is visible, as test_vio_relay.cpp does.
#include "common/app.h"
#include "fact/app_status_t.hpp"
#include "fact/camera.h"
#include "fact/detections_t.hpp"
#include "fact/frame_t.hpp"
#include "fact/odometry_t.hpp"
#include "private_netns.h"
#include "temp_dir.h"
#include "test_time.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

extern char** environ;

namespace {

namespace fs = std::filesystem;
const std::string kUrl = "udpm://239.255.76.67:7667?ttl=0";
const std::string kLiveUrl = kUrl + "&recv_buf_size=4194304";  // whole 424 × 240 frames over udpm

using fact::test::only_loopback;

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs fact-detector with args; stderr to a file; returns the child's pid.
pid_t spawn(const std::vector<std::string>& args, const fs::path& err) {
  posix_spawn_file_actions_t a;
  posix_spawn_file_actions_init(&a);
  posix_spawn_file_actions_addopen(&a, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&a, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<std::string> words = {FACT_DETECTOR_BINARY};
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  pid_t pid = -1;
  if (posix_spawn(&pid, FACT_DETECTOR_BINARY, &a, nullptr, argv.data(), environ) != 0) pid = -1;
  posix_spawn_file_actions_destroy(&a);
  return pid;
}

int exit_code(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// This test's LCM endpoint: the detections on one channel and every status message, in arrival order.
class Bus {
 public:
  Bus(const std::string& url, const std::string& detections_channel) : lcm_(url) {
    lcm_.subscribe(detections_channel, &Bus::on_detections, this)->setQueueCapacity(100);
    lcm_.subscribe("FACT_STATUS", &Bus::on_status, this)->setQueueCapacity(100);
  }
  bool good() { return lcm_.good(); }
  lcm::LCM& lcm() { return lcm_; }
  // Handles messages until done() or `ms` × FACT_TEST_TIME_SCALE have passed.
  void pump_until(const std::function<bool()>& done, int ms) {
    const auto end = std::chrono::steady_clock::now() + fact::test::scaled(std::chrono::milliseconds(ms));
    while (!done() && std::chrono::steady_clock::now() < end) lcm_.handleTimeout(20);
  }
  void pump(int ms) { pump_until([] { return false; }, ms); }
  // A counter of the newest status message (−1 when it has none, or there is none).
  int64_t counter(const std::string& name) const {
    return status.empty() ? -1 : fact::app::counter_value(status.back(), name).value_or(-1);
  }

  std::vector<fact::detections_t> got;
  std::vector<fact::app_status_t> status;

 private:
  void on_detections(const lcm::ReceiveBuffer*, const std::string&, const fact::detections_t* m) { got.push_back(*m); }
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const fact::app_status_t* m) { status.push_back(*m); }
  lcm::LCM lcm_;
};

// Drone 2's 424 × 240 frame `seq` at `utime` (µs) of a wall `wall_mm` away, as a camera driver
// publishes it on FACT_FRAMES_2.
fact::frame_t wall_frame(int64_t seq, int64_t utime, int16_t wall_mm) {
  const fact::CameraIntrinsics k = fact::d430_424x240();
  fact::frame_t m;
  m.utime = utime;
  m.drone_id = 2;
  m.seq = seq;
  m.width = k.width;
  m.height = k.height;
  m.fx = k.fx, m.fy = k.fy, m.cx = k.cx, m.cy = k.cy;
  m.gray_size = m.depth_size = k.width * k.height;
  m.gray.assign(static_cast<size_t>(m.gray_size), 100);
  m.depth_mm.assign(static_cast<size_t>(m.depth_size), wall_mm);
  return m;
}

class DetectorApp : public fact::test::TempDirTest {
 protected:
  DetectorApp() : TempDirTest("fact-detector-app") {}

  // fact-detector as drone 2 on kLiveUrl (stderr to dir_/err, a status every 0.2 s), once its
  // first status has arrived on `bus` (it has subscribed then): its pid, or −1.
  pid_t start_live(Bus& bus) {
    const pid_t pid = spawn({"--drone-id", "2", "--lcm-url", kLiveUrl, "--status-period", "0.2"}, dir_ / "err");
    if (pid <= 0) return -1;
    bus.pump_until([&] { return !bus.status.empty(); }, 5000);
    EXPECT_FALSE(bus.status.empty()) << read_text(dir_ / "err");
    return pid;
  }
  void SetUp() override {
    TempDirTest::SetUp();
    if (HasFatalFailure()) return;  // no directory: nothing to create under it
    fs::create_directories(dir_ / "png");
  }
};

TEST_F(DetectorApp, PngDirPublishesTrackedDetections) {
  const fact::CameraIntrinsics k = fact::d430_640x480();
  {
    std::ofstream j(dir_ / "png" / "intrinsics.json");
    j << "{\"width\": 640, \"height\": 480, \"fx\": 387, \"fy\": 387, \"cx\": 321, \"cy\": 243}\n";
    std::ofstream tum(dir_ / "png" / "odometry.tum");  // level, heading +x, for 2 s
    for (int i = 0; i <= 200; ++i) tum << 1000.0 + i * 0.01 << " 0 0 1 0 0 0 1\n";
    // After a 18 s pause in the recording, pitched 0.3 rad about y: a pause in a file is not a new
    // clock, the frames before it keep their level attitude (all 231 samples are taken).
    for (int i = 0; i < 30; ++i)
      tum << 1020.0 + i * 0.01 << " 0 0 1 0 " << std::sin(0.15) << " 0 " << std::cos(0.15) << "\n";
  }
  // A drone-sized blob (0.40 × 0.08 m) at z = 3 m, 0.5 m left of the axis, in front of a wall at 7 m.
  const double z = 3.0, x = -0.5;
  const Eigen::Vector2d c = fact::project(k, Eigen::Vector3d(x, 0, z));
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0, 1);
  const int frames = 8;
  for (int f = 0; f < frames; ++f) {
    cv::Mat gray(480, 640, CV_8U, cv::Scalar(120)), depth(480, 640, CV_16U);
    for (int v = 0; v < 480; ++v)
      for (int u = 0; u < 640; ++u) depth.at<uint16_t>(v, u) = static_cast<uint16_t>(std::lround(7000 + 60 * noise(rng)));
    const int hw = static_cast<int>(0.20 * k.fx / z), hh = static_cast<int>(0.04 * k.fy / z);
    const int cu = static_cast<int>(std::lround(c.x())), cv_ = static_cast<int>(std::lround(c.y()));
    depth(cv::Rect(cu - hw, cv_ - hh, 2 * hw + 1, 2 * hh + 1)).setTo(3000);
    const std::string t = std::to_string(int64_t(1000000000) + f * 66666);  // µs, ~15 Hz (odometry covers it)
    cv::imwrite((dir_ / "png" / (t + "_gray.png")).string(), gray);
    cv::imwrite((dir_ / "png" / (t + "_depth.png")).string(), depth);
  }
  // A bad pair: depth of another size.
  cv::imwrite((dir_ / "png" / "1000999999_gray.png").string(), cv::Mat(480, 640, CV_8U, cv::Scalar(1)));
  cv::imwrite((dir_ / "png" / "1000999999_depth.png").string(), cv::Mat(240, 320, CV_16U, cv::Scalar(1000)));

  Bus bus(kUrl, "FACT_DETECTIONS_4");
  ASSERT_TRUE(bus.good());
  const std::vector<fact::detections_t>& got = bus.got;
  const pid_t pid = spawn({"--png-dir", (dir_ / "png").string(), "--drone-id", "4", "--lcm-url", kUrl}, dir_ / "err");
  ASSERT_GT(pid, 0);
  int code = -2;
  bus.pump_until([&] {
    int st = 0;
    if (waitpid(pid, &st, WNOHANG) != pid) return false;
    code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    return true;
  }, 15000);
  bus.pump(200);  // what it published last
  const std::string err = read_text(dir_ / "err");
  ASSERT_EQ(code, 0) << err;
  ASSERT_EQ(got.size(), static_cast<size_t>(frames)) << err;
  int track = -1;
  for (int f = 0; f < frames; ++f) {
    EXPECT_EQ(got[f].drone_id, 4);
    EXPECT_EQ(got[f].utime, int64_t(1000000000) + f * 66666);
    if (f < 1) {  // tentative in the first frame (confirm_hits 2)
      EXPECT_EQ(got[f].count, 0);
      continue;
    }
    ASSERT_EQ(got[f].count, 1) << "frame " << f;
    const fact::detection_t& d = got[f].detections[0];
    if (track < 0) track = d.track_id;
    EXPECT_EQ(d.track_id, track);
    // Expected: near surface at z = 3 m on the ray through the blob centre, + 0.17 m, then body frame.
    const Eigen::Vector3d ray = fact::pixel_ray(k, d.box[0] + d.box[2] / 2, d.box[1] + d.box[3] / 2);
    const Eigen::Vector3d p_b = fact::CameraExtrinsics().R_body_cam * (ray * (z / ray.z() + 0.17)) +
                                fact::CameraExtrinsics().t_body_cam;
    EXPECT_NEAR(d.range, p_b.norm(), 1e-6);
    EXPECT_NEAR(d.vector[0], 3.0 + 0.1 + 0.17, 0.02);  // ahead
    EXPECT_NEAR(d.vector[1], 0.5, 0.03);               // left (optical x = −0.5)
    EXPECT_NEAR(d.vector[2], 0.0, 0.02);
    EXPECT_GE(d.confidence, 0.9f);
  }
  ASSERT_FALSE(bus.status.empty());
  EXPECT_EQ(bus.counter("size_mismatch"), 1) << err;
  EXPECT_EQ(bus.counter("published"), frames);
  EXPECT_NE(err.find("size_mismatch"), std::string::npos) << err;
  EXPECT_NE(err.find("gray 640 x 480, depth 320 x 240"), std::string::npos) << err;
  EXPECT_NE(err.find("231 odometry samples"), std::string::npos) << err;
}

TEST_F(DetectorApp, FlagsAndModelErrors) {
  const pid_t help = spawn({"--help"}, dir_ / "help");
  EXPECT_EQ(exit_code(help), 0);
  const std::string missing = (dir_ / "no-such.onnx").string();
  fs::path garbage = dir_ / "garbage.onnx";
  std::ofstream(garbage) << "not a model";
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--backend", "sift"}, "--backend: expected depth or yolo, got \"sift\""},
      {{"--backend", "yolo"}, "--backend yolo needs --model FILE"},
      {{"--backend", "yolo", "--model", missing}, missing},
      {{"--backend", "yolo", "--model", garbage.string()}, garbage.string()},
      {{"--smallest-percent", "0"}, "--smallest-percent"},
      {{"--png-dir", missing}, "not a directory"},
      {{"--drone-id", "-2"}, "--drone-id"},
  };
  int i = 0;
  for (const auto& [args, reason] : cases) {
    const fs::path err = dir_ / ("bad" + std::to_string(i++));
    EXPECT_EQ(exit_code(spawn(args, err)), 2) << args[0];
    const std::string text = read_text(err);
    EXPECT_NE(text.find(reason), std::string::npos) << text;
    EXPECT_EQ(text.rfind("fact-detector: error: ", 0), 0u) << text;
  }
}

// Frames over LCM: good ones are processed and published; each kind of bad frame (wrong size,
// missing intrinsics, all-invalid depth, gray and depth of different sizes, another drone's frame,
// a truncated message) is counted under its own name and logged, and the app keeps running.
TEST_F(DetectorApp, LcmFramesBadOnesCountedAppKeepsRunning) {
  Bus bus(kLiveUrl, "FACT_DETECTIONS_2");
  ASSERT_TRUE(bus.good());
  const pid_t pid = start_live(bus);
  ASSERT_GT(pid, 0);
  lcm::LCM& lcm = bus.lcm();
  const std::vector<fact::detections_t>& got = bus.got;
  auto pump = [&](int ms) { bus.pump(ms); };
  // A wall at 6 m: nothing to detect.
  auto frame = [](int64_t seq) { return wall_frame(seq, 2000000000 + seq * 66666, 6000); };
  int64_t seq = 0;
  auto good = [&]() {
    fact::frame_t m = frame(seq++);
    lcm.publish("FACT_FRAMES_2", &m);
    pump(100);
  };
  good();
  fact::frame_t m = frame(seq++);
  m.width = 100;  // wrong size for the buffers
  lcm.publish("FACT_FRAMES_2", &m);
  good();
  m = frame(seq++);
  m.fx = std::nan("");  // missing intrinsics
  lcm.publish("FACT_FRAMES_2", &m);
  good();
  m = frame(seq++);
  std::fill(m.depth_mm.begin(), m.depth_mm.end(), 0);  // all-invalid depth
  lcm.publish("FACT_FRAMES_2", &m);
  good();
  m = frame(seq++);
  m.depth_size = m.gray_size / 4;  // depth of another size than gray
  m.depth_mm.resize(static_cast<size_t>(m.depth_size));
  lcm.publish("FACT_FRAMES_2", &m);
  good();
  m = frame(seq++);
  m.drone_id = 3;  // another drone's frame
  lcm.publish("FACT_FRAMES_2", &m);
  good();
  m = frame(seq++);
  m.cx = 1e6;  // principal point far outside the image (ranges of kilometres, or NaN at 1e300)
  lcm.publish("FACT_FRAMES_2", &m);
  good();
  m = frame(seq++);  // 481 × 1: valid, but decimated to 0 rows it aborted the app in OpenCV
  m.width = 481;
  m.height = 1;
  m.cx = 240;
  m.cy = 0;
  m.gray_size = m.depth_size = 481;
  m.gray.assign(481, 100);
  m.depth_mm.assign(481, 3000);
  lcm.publish("FACT_FRAMES_2", &m);
  pump(100);
  {
    m = frame(seq++);
    std::vector<uint8_t> bytes(static_cast<size_t>(m.getEncodedSize()));
    m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    lcm.publish("FACT_FRAMES_2", bytes.data(), static_cast<unsigned>(bytes.size() / 2));  // truncated
  }
  good();
  bus.pump_until([&] { return got.size() >= 9; }, 1200);
  kill(pid, SIGTERM);
  const int code = exit_code(pid);
  pump(300);
  const std::string err = read_text(dir_ / "err");
  EXPECT_EQ(code, 0) << err;
  ASSERT_FALSE(bus.status.empty()) << err;
  auto counter = [&](const std::string& name) { return bus.counter(name); };
  EXPECT_EQ(counter("published"), 9) << err;  // every good frame (the 481 × 1 one too), also after bad ones
  EXPECT_EQ(counter("bad_frame"), 1) << err;
  EXPECT_EQ(counter("bad_intrinsics"), 2) << err;
  EXPECT_EQ(counter("no_depth"), 1) << err;
  EXPECT_EQ(counter("size_mismatch"), 1) << err;
  EXPECT_EQ(counter("wrong_drone_id"), 1) << err;
  EXPECT_EQ(counter("undecodable"), 1) << err;
  EXPECT_EQ(got.size(), 9u) << err;
  for (const auto& d : got) EXPECT_EQ(d.count, 0);  // a bare wall holds no drone
  EXPECT_NE(err.find("fx"), std::string::npos) << err;
  EXPECT_NE(err.find("cx = 1000000"), std::string::npos) << err;
  EXPECT_NE(err.find("drone_id = 3"), std::string::npos) << err;
}

// Odometry over LCM with a drone in view: one sample 10⁶ s in the future is refused (it used to
// be kept, every later sample refused as older, and the attitude frozen at the old pitch); the
// pitch that follows reaches the detections' vectors. A seq going back (fact-vio-relay's restart
// after a VIO clock reset) restarts the buffer instead of losing every later sample.
TEST_F(DetectorApp, OdometryGlitchAndRestartDoNotFreezeTheAttitude) {
  Bus bus(kLiveUrl, "FACT_DETECTIONS_2");
  ASSERT_TRUE(bus.good());
  const pid_t pid = start_live(bus);
  ASSERT_GT(pid, 0);
  lcm::LCM& lcm = bus.lcm();
  const std::vector<fact::detections_t>& got = bus.got;

  const fact::CameraIntrinsics k = fact::d430_424x240();
  int64_t odometry_seq = 0;
  auto odometry = [&](int64_t utime, double pitch, int64_t seq) {
    fact::odometry_t o{};
    o.utime = utime;
    o.drone_id = 2;
    o.seq = seq;
    o.pitch = pitch;
    lcm.publish("FACT_ODOMETRY_2", &o);
  };
  // Frame f at 2000 s + f·66.7 ms: a drone-sized blob 3 m ahead in front of a wall at 6 m, after
  // the odometry up to its time (10 ms apart) at `pitch`.
  auto frame = [&](int64_t f, double pitch) {
    const int64_t t = 2000000000 + f * 66666;
    for (int64_t u = t - 66666 + 10000; u <= t; u += 10000) odometry(u, pitch, odometry_seq++);
    fact::frame_t m = wall_frame(f, t, 6000);
    const int hw = static_cast<int>(0.20 * k.fx / 3.0), hh = static_cast<int>(0.04 * k.fy / 3.0);
    for (int v = 120 - hh; v <= 120 + hh; ++v)
      for (int u = 212 - hw; u <= 212 + hw; ++u) m.depth_mm[static_cast<size_t>(v * k.width + u)] = 3000;
    lcm.publish("FACT_FRAMES_2", &m);
    const size_t before = got.size();
    bus.pump_until([&] { return got.size() > before; }, 2000);
  };
  for (int f = 0; f < 4; ++f) frame(f, 0.0);
  odometry(2000000000 + 4 * 66666 + 1000000000000, 0.0, odometry_seq++);  // 10⁶ s ahead
  for (int f = 4; f < 10; ++f) frame(f, 0.3);
  // One datagram reordered by UDP (seq and time just below the newest): refused, not a restart.
  odometry(2000000000 + 9 * 66666 - 20000, 0.3, odometry_seq - 2);  // (the newest: - 6666 µs)
  // The relay restarts after a VIO clock reset: seq 0 and earlier times, then frames at those times.
  odometry_seq = 0;
  for (int f = 10; f < 14; ++f) frame(f - 3000, 0.0);
  bus.pump(500);
  kill(pid, SIGTERM);
  const int code = exit_code(pid);
  const std::string err = read_text(dir_ / "err");
  EXPECT_EQ(code, 0) << err;
  ASSERT_EQ(got.size(), 14u) << err;
  // The vector's z (gravity-aligned, m) follows the pitch: about 0 level, about ±0.9 at 0.3 rad.
  for (size_t i = 0; i < got.size(); ++i) {
    if (got[i].count != 1) continue;  // the tracker confirms a drone on its second frame
    const double z = got[i].detections[0].vector[2];
    if (i >= 5 && i < 10) {
      EXPECT_GT(std::abs(z), 0.5) << "frame " << i << ": the attitude froze\n" << err;
    } else if (i < 4 || i >= 11) {
      EXPECT_LT(std::abs(z), 0.2) << "frame " << i << "\n" << err;
    }
  }
  int confirmed = 0;
  for (size_t i = 5; i < 10; ++i) confirmed += got[i].count;
  EXPECT_GE(confirmed, 4) << err;
  ASSERT_FALSE(bus.status.empty());
  auto counter = [&](const std::string& name) { return bus.counter(name); };
  EXPECT_EQ(counter("odometry_out_of_order"), 2) << err;  // the sample far ahead, the reordered one
  EXPECT_EQ(counter("odometry_restarts"), 1) << err;
  EXPECT_NE(err.find("is more than 10 s after the newest sample"), std::string::npos) << err;
  EXPECT_NE(err.find("the odometry restarted"), std::string::npos) << err;
}

}  // namespace

int main(int argc, char** argv) { return fact::test::main_in_private_netns(argc, argv, FACT_NETNS_RUN); }
