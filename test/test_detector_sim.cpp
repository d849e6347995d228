// fact_vision on fact_sim's rendered frames (640 × 480, default world, drones at random poses):
// detection recall and precision for unoccluded drones within 6 m, range and bearing errors
// against the renderer's ground truth, and track ids through a rendered spin.
#include "fact/detector.h"
#include "fact/sim_render.h"
#include "fact/sim_world.h"
#include "fact/tracker.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <vector>

namespace {

constexpr double kPi = 3.14159265358979323846;

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// Drones at random positions (≥ 0.4 m from obstacles, 1–2.5 m high), yaw uniform, small tilt.
std::vector<fact::sim::DronePose> random_poses(const fact::sim::World& w, int n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> U(0, 1);
  std::vector<fact::sim::DronePose> poses(static_cast<size_t>(n));
  for (auto& p : poses) {
    for (int tries = 0; tries < 100; ++tries) {
      p.position = Eigen::Vector3d(-4.5 + 9 * U(rng), -4.5 + 9 * U(rng), 1.0 + 1.5 * U(rng));
      bool ok = true;
      for (const auto& o : w.obstacles)
        if (fact::sim::distance(o, p.position) < 0.4) ok = false;
      if (ok) break;
    }
    p.yaw = -kPi + 2 * kPi * U(rng);
    p.pitch = 0.08 * (U(rng) - 0.5);
    p.roll = 0.08 * (U(rng) - 0.5);
  }
  return poses;
}

bool contains(const fact::BoxDetection& b, const Eigen::Vector2d& p, double margin) {
  return p.x() >= b.u - margin && p.x() <= b.u + b.w + margin && p.y() >= b.v - margin && p.y() <= b.v + b.h + margin;
}

TEST(DetectorSim, RecallPrecisionRangeBearingAt640x480) {
  const fact::CameraIntrinsics k = fact::d430_640x480();
  const fact::sim::World world = fact::sim::default_world(6, 3);
  fact::sim::Renderer renderer(world, k, fact::CameraExtrinsics(), fact::sim::RenderOptions(), 5);
  const fact::SegmentationOptions so;
  const fact::RangeOptions ro;
  const fact::TrackerOptions to;
  std::mt19937_64 rng(11);
  int truths = 0, found = 0, detections = 0, true_detections = 0;
  std::vector<double> range_error, bearing_error;
  fact::sim::RenderedFrame frame;
  for (int scene = 0; scene < 12; ++scene) {
    std::vector<fact::sim::DronePose> poses = random_poses(world, 6, rng);
    for (int view = 0; view < 12; ++view) {
      poses[0].yaw += 2 * kPi / 12;
      renderer.render(poses, 0, &frame);
      const fact::FrameView fv = frame.view(0);
      const auto boxes = fact::detect_depth(fv, so);
      const auto truth = fact::sim::ground_truth(world, renderer.body(), k, renderer.extrinsics(), poses, 0, &frame);
      for (const auto& t : truth) {
        if (!t.center_in_image || !t.line_of_sight || t.camera_range > 6.0 || t.visible_pixels == 0) continue;
        // Truncated by the image border (part of the drone out of view): scored low by design, so
        // it continues a track but never starts one; not part of the recall figure.
        if (t.u_min <= 0 || t.v_min <= 0 || t.u_max >= k.width - 1 || t.v_max >= k.height - 1) continue;
        ++truths;
        const fact::BoxDetection* hit = nullptr;
        for (const auto& b : boxes)
          if (b.score >= to.high_score && contains(b, t.center_px, 1.0)) hit = &b;
        if (!hit) continue;
        ++found;
        const fact::TargetVector v = fact::target_vector(fv, *hit, renderer.extrinsics(), poses[0].roll,
                                                         poses[0].pitch, ro);
        ASSERT_TRUE(v.valid);
        range_error.push_back(std::abs(v.range - t.range) / t.range);
        bearing_error.push_back(std::acos(std::min(1.0, v.vector_g.normalized().dot(t.vector_g.normalized()))) * 180 / kPi);
      }
      for (const auto& b : boxes) {  // a first-stage detection is true if it holds drone pixels
        if (b.score < to.high_score) continue;
        ++detections;
        bool drone = false;
        for (int v = std::max(0, int(std::ceil(b.v))); v < std::min(k.height, int(std::ceil(b.v + b.h))); ++v)
          for (int u = std::max(0, int(std::ceil(b.u))); u < std::min(k.width, int(std::ceil(b.u + b.w))); ++u)
            drone = drone || frame.object_id[static_cast<size_t>(v * k.width + u)] >= 0;
        true_detections += drone;
      }
    }
  }
  ASSERT_GT(truths, 50);
  const double recall = double(found) / truths, precision = double(true_detections) / detections;
  RecordProperty("recall", std::to_string(recall));
  RecordProperty("precision", std::to_string(precision));
  std::printf("recall %d/%d = %.3f, precision %d/%d = %.4f, median range error %.4f, median bearing error %.3f deg\n",
              found, truths, recall, true_detections, detections, precision, median(range_error),
              median(bearing_error));
  EXPECT_GE(recall, 0.95);
  EXPECT_GE(precision, 0.99);
  EXPECT_LE(median(range_error), 0.03);
  EXPECT_LE(median(bearing_error), 0.5);
}

// A drone `ahead` m in front of the viewer (level, at 1.6 m), `rise` m higher than it and `gap` m
// before the wall at x = 5, turned through 24 yaws with a small roll and pitch, each rendered with
// fresh noise: how many views
// give a first-stage detection holding the drone's centre, ranged within 3 %, and how many other
// first-stage boxes there are.
struct SweepResult {
  int views = 0, found = 0, extra = 0;  // views; views found; high-score boxes not on the drone
};
SweepResult yaw_sweep(double ahead, double gap, double rise, const fact::SegmentationOptions& so) {
  const fact::CameraIntrinsics k = fact::d430_640x480();
  fact::sim::World world = fact::sim::default_world(2, 3);
  world.obstacles.clear();
  fact::sim::Renderer renderer(world, k, fact::CameraExtrinsics(), fact::sim::RenderOptions(), 21);
  std::vector<fact::sim::DronePose> poses(2);
  poses[1].position = {5.0 - gap, 0.2, 1.6 + rise};
  poses[0].position = {poses[1].position.x() - ahead, 0.0, 1.6};
  const double high = fact::TrackerOptions{}.high_score;
  SweepResult r;
  fact::sim::RenderedFrame frame;
  for (int i = 0; i < 24; ++i) {
    poses[1].yaw = 2 * kPi * i / 24;
    poses[1].roll = 0.04 * std::sin(2.1 * i);  // a hovering drone's wobble (rad)
    poses[1].pitch = 0.04 * std::cos(1.7 * i);
    renderer.render(poses, 0, &frame);
    const fact::FrameView fv = frame.view(0);
    const auto truth = fact::sim::ground_truth(world, renderer.body(), k, renderer.extrinsics(), poses, 0, &frame);
    EXPECT_EQ(truth.size(), 1u);
    if (truth.empty()) continue;
    ++r.views;
    bool found = false;
    for (const auto& b : fact::detect_depth(fv, so)) {
      if (b.score < high) continue;
      const fact::TargetVector v = fact::target_vector(fv, b, renderer.extrinsics(), 0, 0, fact::RangeOptions());
      const bool on_drone = contains(b, truth[0].center_px, 1.0) && v.valid &&
                            std::abs(v.range - truth[0].range) < 0.03 * truth[0].range;
      if (on_drone && !found) {
        found = true;
      } else {
        ++r.extra;
      }
    }
    r.found += found;
  }
  return r;
}

// Beyond 5 m a drone is 3 working pixels tall at 640 × 480; 0.8 m before a wall it must still
// come out of the wall's surface (found in 22 of these 24 views; with the former edge threshold,
// 1.7 × as high there, it merged into the wall in 21 of them).
TEST(DetectorSim, DroneAt5p5mBeforeAWallIsFound) {
  const SweepResult r = yaw_sweep(5.5, 0.8, 0.0, fact::SegmentationOptions());
  std::printf("5.5 m, 0.8 m before the wall: found %d of %d views, %d other boxes\n", r.found, r.views, r.extra);
  EXPECT_EQ(r.views, 24);
  EXPECT_GE(r.found, 20);
  EXPECT_EQ(r.extra, 0);
}

// At 2.4 m, seen from 0.3 m above, a drone shows rotors and hub at depths up to 0.3 m apart, more
// than the edge threshold there: its parts must merge into one box, not split into several
// detections (without merge_depth a rotor comes out alone in one of the 24 views).
TEST(DetectorSim, NearDroneIsOneBoxFromEveryYaw) {
  const SweepResult r = yaw_sweep(2.4, 2.0, -0.3, fact::SegmentationOptions());
  std::printf("2.4 m: found %d of %d views, %d other boxes\n", r.found, r.views, r.extra);
  EXPECT_EQ(r.views, 24);
  EXPECT_EQ(r.found, 24);
  EXPECT_EQ(r.extra, 0);
}

TEST(DetectorSim, TrackIdsPersistThroughARenderedSpin) {
  const fact::CameraIntrinsics k = fact::d430_640x480();
  fact::sim::World world = fact::sim::default_world(4, 3);
  world.obstacles.clear();
  fact::sim::Renderer renderer(world, k, fact::CameraExtrinsics(), fact::sim::RenderOptions(), 9);
  std::vector<fact::sim::DronePose> poses(4);
  poses[0].position = {0, 0, 1.5};
  poses[1].position = {3.0, 0.8, 1.3};
  poses[2].position = {2.0, -0.9, 1.8};
  poses[3].position = {3.8, -0.6, 1.6};  // (1.2 m in front of the wall at x = 5)
  fact::Tracker tracker;
  std::map<int, int> id_of_drone;  // drone index → the track id it had
  std::map<int, int> drone_of_id;
  const double dt = 1.0 / 15, rate = 0.8;
  double prev_yaw = 0;
  fact::sim::RenderedFrame frame;
  int confirmed = 0;
  for (int f = 0; f < 40; ++f) {
    const double yaw = -1.1 + rate * dt * f;
    poses[0].yaw = yaw;
    renderer.render(poses, 0, &frame);
    const auto boxes = fact::detect_depth(frame.view(0), {});
    Eigen::Matrix3d H = Eigen::Matrix3d::Identity();
    if (f > 0) H = fact::rotation_homography(k, fact::camera_rotation(prev_yaw, 0, 0, yaw, 0, 0, renderer.extrinsics()));
    prev_yaw = yaw;
    tracker.update(boxes, H);
    for (const fact::Track* t : tracker.confirmed_matched()) {
      ++confirmed;
      // The drone whose pixels dominate the box.
      std::map<int, int> votes;
      for (int v = int(std::ceil(t->box.v)); v < int(std::ceil(t->box.v + t->box.h)); ++v)
        for (int u = int(std::ceil(t->box.u)); u < int(std::ceil(t->box.u + t->box.w)); ++u)
          if (u >= 0 && v >= 0 && u < k.width && v < k.height && frame.object_id[size_t(v * k.width + u)] >= 0)
            ++votes[frame.object_id[size_t(v * k.width + u)]];
      ASSERT_FALSE(votes.empty()) << "track " << t->id << " on no drone at frame " << f;
      const int drone = std::max_element(votes.begin(), votes.end(), [](auto a, auto b) { return a.second < b.second; })->first;
      if (id_of_drone.count(drone)) {
        EXPECT_EQ(id_of_drone[drone], t->id) << "drone " << drone << " frame " << f;
      }
      if (drone_of_id.count(t->id)) {
        EXPECT_EQ(drone_of_id[t->id], drone) << "track " << t->id;
      }
      id_of_drone[drone] = t->id;
      drone_of_id[t->id] = drone;
    }
  }
  EXPECT_EQ(id_of_drone.size(), 3u);  // every drone was tracked, each with one id
  EXPECT_GT(confirmed, 40);
}

}  // namespace
