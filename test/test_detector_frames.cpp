// fact_vision on frames painted here (a wall with near blobs of known size and depth) and on
// synthetic box streams: frame checks, segmentation, range and vectors, the rotation homography
// and the tracker (tentative → confirmed → lost → removed, ids kept through a compensated spin).
#include "fact/detector.h"
#include "fact/tracker.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace {

using fact::BoxDetection;

// A 640 × 480 frame: a flat wall at wall_z (m) with depth noise, and rectangles nearer.
struct Painted {
  fact::CameraIntrinsics k = fact::d430_640x480();
  std::vector<uint8_t> gray;
  std::vector<uint16_t> depth;
  explicit Painted(double wall_z, uint64_t seed = 1) : gray(640 * 480, 128), depth(640 * 480) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> n(0, 1);
    const double s = fact::depth_sigma(fact::DepthNoise{}, k.fx, wall_z);
    for (auto& d : depth) d = static_cast<uint16_t>(std::lround((wall_z + s * n(rng)) * 1000));
  }
  // Pixel columns u0 … u1, rows v0 … v1 at depth z (m) exactly.
  void rect(int u0, int v0, int u1, int v1, double z) {
    for (int v = v0; v <= v1; ++v)
      for (int u = u0; u <= u1; ++u) depth[v * k.width + u] = static_cast<uint16_t>(std::lround(z * 1000));
  }
  // A drone-sized flat blob (0.40 × 0.08 m) centred on the optical-frame point (x, y, z).
  void drone(double x, double y, double z) {
    const Eigen::Vector2d c = fact::project(k, Eigen::Vector3d(x, y, z));
    const double hw = 0.20 * k.fx / z, hh = 0.04 * k.fy / z;
    rect(static_cast<int>(std::lround(c.x() - hw)), static_cast<int>(std::lround(c.y() - hh)),
         static_cast<int>(std::lround(c.x() + hw)), static_cast<int>(std::lround(c.y() + hh)), z);
  }
  fact::FrameView view() const {
    fact::FrameView f;
    f.intrinsics = k;
    f.gray = gray.data();
    f.depth_mm = depth.data();
    return f;
  }
};

TEST(DetectorFrame, ErrorsNameTheField) {
  Painted p(5.0);
  fact::FrameView f = p.view();
  EXPECT_EQ(fact::frame_error(f), "");
  f.intrinsics.fx = std::nan("");
  EXPECT_NE(fact::frame_error(f).find("fx"), std::string::npos) << fact::frame_error(f);
  f = p.view();
  f.intrinsics.width = 0;
  EXPECT_NE(fact::frame_error(f).find("width = 0"), std::string::npos) << fact::frame_error(f);
  f = p.view();
  f.gray = nullptr;
  EXPECT_EQ(fact::frame_error(f), "gray: null buffer");
  f = p.view();
  f.depth_mm = nullptr;
  EXPECT_EQ(fact::frame_error(f), "depth_mm: null buffer");
  // The principal point within one image size of the image; focal lengths 1 … 1e6 px.
  f = p.view();
  f.intrinsics.cx = 1e6;
  EXPECT_NE(fact::frame_error(f).find("cx = 1000000"), std::string::npos) << fact::frame_error(f);
  f = p.view();
  f.intrinsics.cy = -481;
  EXPECT_NE(fact::frame_error(f).find("cy = -481"), std::string::npos) << fact::frame_error(f);
  f = p.view();
  f.intrinsics.fy = 0.5;
  EXPECT_NE(fact::frame_error(f).find("fy = 0.5"), std::string::npos) << fact::frame_error(f);
  std::fill(p.depth.begin(), p.depth.end(), 0);
  EXPECT_EQ(fact::frame_error(p.view()), "depth_mm: all 307200 pixels are 0 (no valid depth)");
  EXPECT_TRUE(fact::detect_depth(p.view(), {}).empty());
}

// One-row and one-column frames too narrow to decimate are segmented at full resolution (481 × 1
// decimated to 0 rows threw inside OpenCV and aborted fact-detector).
TEST(DetectorSegmentation, ThinFramesAreSegmentedWithoutDecimation) {
  for (const auto& [w, h] : {std::pair{481, 1}, std::pair{640, 1}, std::pair{1, 481}, std::pair{481, 2}}) {
    std::vector<uint8_t> gray(static_cast<size_t>(w * h), 100);
    std::vector<uint16_t> depth(static_cast<size_t>(w * h), 3000);
    fact::FrameView f;
    f.intrinsics = fact::CameraIntrinsics{w, h, 387, 387, w / 2.0, h / 2.0};
    f.gray = gray.data();
    f.depth_mm = depth.data();
    EXPECT_NO_THROW(fact::detect_depth(f, {})) << w << " x " << h;
  }
}

TEST(DetectorSegmentation, FindsDroneSizedNearBlobsOnly) {
  Painted p(6.0);
  p.drone(-1.0, 0.0, 2.0);   // drones at 2 m and 4 m
  p.drone(0.8, -0.3, 4.0);
  p.rect(400, 300, 600, 470, 1.5);  // a 0.8 × 0.7 m slab at 1.5 m: too big (and touching nothing)
  p.rect(100, 400, 101, 401, 1.0);  // 2 × 2 px speck at 1 m: 2 mm, too small
  const auto boxes = fact::detect_depth(p.view(), {});
  ASSERT_EQ(boxes.size(), 2u);
  for (const Eigen::Vector3d& t : {Eigen::Vector3d(-1.0, 0.0, 2.0), Eigen::Vector3d(0.8, -0.3, 4.0)}) {
    const Eigen::Vector2d c = fact::project(p.k, t);
    bool found = false;
    for (const BoxDetection& b : boxes)
      if (std::abs(b.u + b.w / 2 - c.x()) < 1.5 && std::abs(b.v + b.h / 2 - c.y()) < 1.5) {
        found = true;
        EXPECT_NEAR(b.w * t.z() / p.k.fx, 0.40, 4.5 * t.z() / p.k.fx);  // ±2 px per side at half resolution
        EXPECT_GE(b.score, 0.95f);  // the whole ring is the wall, 2–4 m behind
      }
    EXPECT_TRUE(found) << t.transpose();
  }
}

TEST(DetectorSegmentation, BlobCloseToTheWallOrTouchingTheBorderIsWeak) {
  Painted p(3.0);
  p.drone(0.0, 0.0, 2.9);  // 0.1 m in front of the wall: not separable from it
  EXPECT_TRUE(fact::detect_depth(p.view(), {}).empty());
  Painted q(6.0);
  q.rect(0, 200, 60, 215, 2.0);  // cut by the left border
  const auto boxes = fact::detect_depth(q.view(), {});
  ASSERT_EQ(boxes.size(), 1u);
  EXPECT_LE(boxes[0].score, fact::SegmentationOptions{}.border_factor + 1e-6);
  EXPECT_LT(boxes[0].score, fact::TrackerOptions{}.new_track_score);  // cannot start a track
}

TEST(DetectorRange, MeanOfSmallestPercentAlongTheCentreRayPlusRadius) {
  Painted p(6.0);
  // A box of 100 pixels: 20 at 3.000 m, 80 at 3.5 m.
  p.rect(300, 200, 309, 209, 3.5);
  p.rect(300, 200, 309, 201, 3.0);
  BoxDetection b{299.5f, 199.5f, 10.f, 10.f, 1.f};
  fact::RangeOptions ro;
  ro.smallest_percent = 20;
  ro.target_radius = 0.2;
  EXPECT_NEAR(fact::near_surface_depth(p.view(), b, ro), 3.0, 1e-9);
  ro.smallest_percent = 40;
  EXPECT_NEAR(fact::near_surface_depth(p.view(), b, ro), 3.25, 1e-9);
  ro.smallest_percent = 20;
  fact::CameraExtrinsics e;
  const double roll = 0.05, pitch = -0.1;
  const fact::TargetVector t = fact::target_vector(p.view(), b, e, roll, pitch, ro);
  ASSERT_TRUE(t.valid);
  const Eigen::Vector3d ray = fact::pixel_ray(p.k, 304.5, 204.5);
  const Eigen::Vector3d point_c = ray * (3.0 / ray.z() + 0.2);
  EXPECT_NEAR((t.point_c - point_c).norm(), 0, 1e-9);
  const Eigen::Vector3d expected = fact::gravity_from_body(roll, pitch) * (e.R_body_cam * point_c + e.t_body_cam);
  EXPECT_NEAR((t.vector_g - expected).norm(), 0, 1e-9);
  EXPECT_NEAR(t.range, expected.norm(), 1e-12);
  // The gravity-aligned x points ahead: a target straight ahead of a level camera is at +x.
  EXPECT_GT(t.vector_g.x(), 3.0);
  BoxDetection outside{700.f, 10.f, 5.f, 5.f, 1.f};
  EXPECT_FALSE(fact::target_vector(p.view(), outside, e, 0, 0, ro).valid);
}

TEST(TrackerGeometry, HomographyMovesWorldDirectionsWithTheCamera) {
  const fact::CameraIntrinsics k = fact::d430_640x480();
  const fact::CameraExtrinsics e;
  // A world direction seen at yaw 0 and after the body yawed left by 3°: it moves right by
  // ~fx·tan(3°) ≈ 20 px, and H maps one pixel to the other exactly.
  const Eigen::Vector3d d_w = Eigen::Vector3d(1.0, 0.2, 0.1).normalized();
  auto pixel_at = [&](double yaw, double pitch, double roll) {
    const Eigen::Matrix3d R_wc = fact::body_attitude(yaw, pitch, roll) * e.R_body_cam;
    return fact::project(k, R_wc.transpose() * d_w);
  };
  const Eigen::Vector2d a = pixel_at(0.0, 0.02, -0.01), b = pixel_at(0.0524, 0.03, 0.0);
  const Eigen::Matrix3d H =
      fact::rotation_homography(k, fact::camera_rotation(0.0, 0.02, -0.01, 0.0524, 0.03, 0.0, e));
  EXPECT_NEAR((fact::apply_homography(H, a) - b).norm(), 0, 1e-9);
  EXPECT_GT(b.x() - a.x(), 15);
}

BoxDetection box_at(double cx, double cy, float w, float h, float score) {
  return BoxDetection{static_cast<float>(cx - w / 2), static_cast<float>(cy - h / 2), w, h, score};
}

TEST(Tracker, TentativeConfirmedLostRemoved) {
  fact::TrackerOptions o;
  o.confirm_hits = 3;
  o.max_lost = 2;
  fact::Tracker t(o);
  const BoxDetection d = box_at(100, 100, 40, 10, 0.9f);
  t.update({d});
  ASSERT_EQ(t.tracks().size(), 1u);
  EXPECT_EQ(t.tracks()[0].state, fact::TrackState::tentative);
  EXPECT_TRUE(t.confirmed_matched().empty());
  t.update({d});
  EXPECT_EQ(t.tracks()[0].state, fact::TrackState::tentative);
  t.update({d});
  EXPECT_EQ(t.tracks()[0].state, fact::TrackState::confirmed);
  ASSERT_EQ(t.confirmed_matched().size(), 1u);
  const int id = t.tracks()[0].id;
  t.update({});
  EXPECT_EQ(t.tracks()[0].state, fact::TrackState::lost);
  EXPECT_TRUE(t.confirmed_matched().empty());
  t.update({box_at(101, 100, 40, 10, 0.3f)});  // a low-score detection does not revive a lost track
  EXPECT_EQ(t.tracks()[0].state, fact::TrackState::lost);
  t.update({box_at(101, 100, 40, 10, 0.9f)});  // a high one does, with its id
  ASSERT_EQ(t.tracks().size(), 1u);
  EXPECT_EQ(t.tracks()[0].state, fact::TrackState::confirmed);
  EXPECT_EQ(t.tracks()[0].id, id);
  for (int i = 0; i < 3; ++i) t.update({});
  EXPECT_TRUE(t.tracks().empty());  // lost for more than max_lost frames
  // A tentative track dies at its first miss; a weak detection never starts a track.
  t.update({d});
  t.update({});
  EXPECT_TRUE(t.tracks().empty());
  t.update({box_at(100, 100, 40, 10, 0.65f)});
  EXPECT_TRUE(t.tracks().empty());
  // A confirmed track is kept through a low-score detection (ByteTrack's second stage).
  for (int i = 0; i < 3; ++i) t.update({d});
  const int id2 = t.tracks()[0].id;
  EXPECT_GT(id2, id);  // never reused
  t.update({box_at(100, 101, 40, 10, 0.35f)});
  ASSERT_EQ(t.confirmed_matched().size(), 1u);
  EXPECT_EQ(t.confirmed_matched()[0]->id, id2);
}

// Three targets fixed in the world, the observer spinning in place at 0.8 rad/s, 15 frames/s
// (≈ 20 px/frame at 640 × 480): with H every target keeps one id while in view; without it the
// boxes of the small far targets jump too far and ids break.
int id_switches(bool compensate) {
  const fact::CameraIntrinsics k = fact::d430_640x480();
  const fact::CameraExtrinsics e;
  const std::vector<Eigen::Vector3d> targets = {{4, 0.3, 0.1}, {3, -1.0, -0.2}, {5.5, 1.5, 0.3}};
  fact::Tracker tracker;
  std::vector<int> last_id(targets.size(), 0);
  int switches = 0;
  const double dt = 1.0 / 15, rate = 0.8;
  double prev_yaw = -1.2;
  for (int f = 0; f < 45; ++f) {
    const double yaw = -1.2 + rate * dt * f;
    std::vector<BoxDetection> dets;
    std::vector<int> det_target;
    for (size_t i = 0; i < targets.size(); ++i) {
      const Eigen::Matrix3d R_wc = fact::body_attitude(yaw, 0, 0) * e.R_body_cam;
      const Eigen::Vector3d p_c = R_wc.transpose() * (targets[i] - e.t_body_cam);
      if (p_c.z() < 0.5) continue;
      const Eigen::Vector2d c = fact::project(k, p_c);
      const float w = static_cast<float>(0.41 * k.fx / p_c.z()), h = static_cast<float>(0.08 * k.fy / p_c.z());
      if (c.x() < w || c.x() > k.width - w) continue;
      dets.push_back(box_at(c.x(), c.y(), w, h, 0.95f));
      det_target.push_back(static_cast<int>(i));
    }
    Eigen::Matrix3d H = Eigen::Matrix3d::Identity();
    if (compensate) H = fact::rotation_homography(k, fact::camera_rotation(prev_yaw, 0, 0, yaw, 0, 0, e));
    prev_yaw = yaw;
    tracker.update(dets, H);
    for (const fact::Track* t : tracker.confirmed_matched()) {
      const int target = det_target[static_cast<size_t>(t->detection)];
      if (last_id[target] != 0 && last_id[target] != t->id) ++switches;
      last_id[target] = t->id;
    }
  }
  for (int id : last_id) EXPECT_NE(id, 0);  // each target was tracked
  return switches;
}

TEST(Tracker, KeepsIdsThroughACompensatedSpin) {
  EXPECT_EQ(id_switches(true), 0);
  fact::TrackerOptions o;
  EXPECT_GT(0.8 / 15 * 387, o.iou_min_side);  // the test is meaningful: motion > grown box size
}

}  // namespace
