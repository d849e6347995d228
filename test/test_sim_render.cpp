// The simulator's renderer and ground-truth helper: a drone placed at a known pose appears at its
// projected pixel with the right depth, the depth noise RMS follows σ = z²·0.08/(fx·0.05) on a flat
// wall, depth is 0 beyond 10 m and below 0.2 m, 1 mm quantisation, attitude (pitch) moves the
// image, line of sight, determinism by seed, and complete frames for 4 turning drones.
#include "fact/sim_render.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace {

using fact::sim::DronePose;
using fact::sim::RenderedFrame;
using fact::sim::Renderer;
using fact::sim::World;

World empty_room(double sx, double sy, double sz) {
  World w;
  w.room_size = {sx, sy, sz};
  return w;
}

DronePose pose(double x, double y, double z, double yaw = 0, double pitch = 0, double roll = 0) {
  DronePose p;
  p.position = {x, y, z};
  p.yaw = yaw;
  p.pitch = pitch;
  p.roll = roll;
  return p;
}

fact::sim::RenderOptions no_noise() {
  fact::sim::RenderOptions o;
  o.depth_noise = false;
  return o;
}

size_t at(const fact::CameraIntrinsics& k, int u, int v) { return static_cast<size_t>(v) * k.width + u; }

double sigma(double z) { return z * z * 0.08 / (213.0 * 0.05); }

// A drone standing on the floor has its camera in the floor's plane: the floor below the horizon
// is seen (too near for depth), not black (review, session 33: half of every frame before
// takeoff was gray 0 and depth 0).
TEST(SimRender, CameraOnTheFloorSeesTheFloor) {
  const World w = empty_room(10, 10, 3);
  Renderer clean(w, fact::d430_424x240(), {}, no_noise(), 5);
  RenderedFrame f;
  clean.render({pose(0, 0, 0)}, 0, &f);
  const fact::CameraIntrinsics& k = clean.intrinsics();
  int black = 0, lower = 0;
  for (int v = k.height / 2 + 2; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u, ++lower) black += f.gray[at(k, u, v)] == 0;
  EXPECT_EQ(black, 0) << "of " << lower << " pixels below the horizon";
  EXPECT_EQ(f.depth_mm[at(k, k.width / 2, k.height - 1)], 0);  // too near for depth
  EXPECT_GT(f.depth_mm[at(k, k.width / 2, k.height / 2 - 10)], 0);  // the far wall above the horizon
  clean.render({pose(0, 0, -0.01)}, 0, &f);  // a camera outside the room still sees nothing
  EXPECT_EQ(f.gray[at(k, k.width / 2, k.height - 1)], 0);
}

TEST(SimRender, DroneAppearsAtProjectedPixelWithItsDepth) {
  const World w = empty_room(20, 20, 4);
  const std::vector<DronePose> drones = {pose(0, 0, 1.5), pose(3, 0.4, 1.7)};
  Renderer clean(w, fact::d430_424x240(), {}, no_noise(), 5);
  RenderedFrame f;
  clean.render(drones, 0, &f);
  const auto gt = fact::sim::ground_truth(w, clean.body(), clean.intrinsics(), clean.extrinsics(), drones, 0, &f);
  ASSERT_EQ(gt.size(), 1u);
  const auto& t = gt[0];
  EXPECT_EQ(t.index, 1);
  // Optical frame: x right = −y_world, y down = −z_world, z = forward from the optical centre (0.1, 0, 1.5).
  EXPECT_NEAR((t.p_cam - Eigen::Vector3d(-0.4, -0.2, 2.9)).norm(), 0, 1e-12);
  EXPECT_NEAR((t.vector_g - Eigen::Vector3d(3, 0.4, 0.2)).norm(), 0, 1e-12);
  EXPECT_NEAR(t.range, std::sqrt(9 + 0.16 + 0.04), 1e-12);
  const Eigen::Vector2d px(213 * -0.4 / 2.9 + 212, 213 * -0.2 / 2.9 + 120);
  EXPECT_NEAR((t.center_px - px).norm(), 0, 1e-9);
  EXPECT_TRUE(t.center_in_image);
  EXPECT_TRUE(t.line_of_sight);
  // The centre pixel shows the hub's front face, 0.06 m before the centre: z = 2.84 m.
  const int u = static_cast<int>(std::lround(px.x())), v = static_cast<int>(std::lround(px.y()));
  EXPECT_EQ(f.object_id[at(f.intrinsics, u, v)], 1);
  EXPECT_NEAR(f.depth_mm[at(f.intrinsics, u, v)], 2840, 1);
  EXPECT_LT(f.gray[at(f.intrinsics, u, v)], 90);  // drones are dark
  // Visible pixels: a box around the centre about 0.33 m wide (rotor tips) → ≈ 24 px at 2.9 m.
  EXPECT_GT(t.visible_pixels, 40);
  EXPECT_LE(t.u_min, u);
  EXPECT_GE(t.u_max, u);
  EXPECT_LE(t.v_min, v);
  EXPECT_GE(t.v_max, v);
  const int width = t.u_max - t.u_min + 1;
  EXPECT_GE(width, 21);
  EXPECT_LE(width, 28);
  EXPECT_FLOAT_EQ(t.visible_box.u, t.u_min - 0.5f);
  EXPECT_FLOAT_EQ(t.visible_box.w, static_cast<float>(width));
  // The noisy renderer: the hub's pixels average to 2.84 m within the noise.
  Renderer noisy(w, fact::d430_424x240(), {}, {}, 5);
  RenderedFrame g;
  noisy.render(drones, 0, &g);
  double sum = 0;
  int n = 0;
  for (int dv = -2; dv <= 2; ++dv)
    for (int du = -2; du <= 2; ++du) {
      const size_t i = at(g.intrinsics, u + du, v + dv);
      ASSERT_EQ(g.object_id[i], 1);
      sum += g.depth_mm[i] * 1e-3;
      ++n;
    }
  EXPECT_NEAR(sum / n, 2.84, 4 * sigma(2.84) / std::sqrt(n));
}

// Camera facing a wall at distance z (room 30 m long, viewer looking along +x at the x = 15 wall).
std::vector<DronePose> facing_wall(double z) { return {pose(15 - 0.1 - z, 0, 2)}; }

TEST(SimRender, DepthNoiseRmsFollowsTheFormulaOnAFlatWall) {
  const World w = empty_room(30, 10, 4);
  Renderer r(w, fact::d430_424x240(), {}, {}, 11);
  RenderedFrame f;
  for (double z : {2.0, 4.0}) {
    r.render(facing_wall(z), 0, &f);
    double sum = 0, sum2 = 0;
    int n = 0;
    for (int v = 80; v < 160; ++v)
      for (int u = 130; u < 294; ++u) {
        const size_t i = at(f.intrinsics, u, v);
        ASSERT_NEAR(f.depth_true[i], z, 1e-5);
        ASSERT_NE(f.depth_mm[i], 0);
        const double e = f.depth_mm[i] * 1e-3 - z;
        sum += e;
        sum2 += e * e;
        ++n;
      }
    const double rms = std::sqrt(sum2 / n), s = sigma(z);
    std::printf("wall at %.1f m: depth noise RMS %.2f mm, formula %.2f mm (%d px)\n", z, 1e3 * rms, 1e3 * s, n);
    EXPECT_NEAR(rms, s, 0.04 * s) << "z = " << z;
    EXPECT_NEAR(sum / n, 0.0, 4 * s / std::sqrt(n)) << "z = " << z;
  }
}

TEST(SimRender, InvalidBeyondTenMetresAndBelowTwentyCentimetres) {
  const World w = empty_room(30, 10, 4);
  Renderer r(w, fact::d430_424x240(), {}, {}, 3);
  RenderedFrame f;
  for (double z : {14.0, 0.15}) {
    r.render(facing_wall(z), 0, &f);
    for (int v = 100; v < 140; ++v)
      for (int u = 190; u < 234; ++u) ASSERT_EQ(f.depth_mm[at(f.intrinsics, u, v)], 0) << "z = " << z;
  }
  // Everywhere in the frame: 0 exactly where the true z is outside [0.2, 10] m.
  r.render(facing_wall(11.0), 0, &f);
  int invalid = 0;
  for (size_t i = 0; i < f.depth_mm.size(); ++i) {
    const bool valid = f.depth_true[i] >= 0.2f && f.depth_true[i] <= 10.0f;
    ASSERT_EQ(f.depth_mm[i] != 0, valid) << i << " z " << f.depth_true[i];
    invalid += valid ? 0 : 1;
  }
  EXPECT_GT(invalid, 10000);                                      // the wall at 11 m
  EXPECT_GT(static_cast<int>(f.depth_mm.size()) - invalid, 10000);  // the floor and side walls nearer
}

TEST(SimRender, QuantisedToOneMillimetre) {
  const World w = empty_room(30, 10, 4);
  Renderer r(w, fact::d430_424x240(), {}, no_noise(), 3);
  RenderedFrame f;
  const size_t centre = at(fact::d430_424x240(), 212, 120);
  r.render(facing_wall(2.0004), 0, &f);
  EXPECT_EQ(f.depth_mm[centre], 2000);
  r.render(facing_wall(2.0006), 0, &f);
  EXPECT_EQ(f.depth_mm[centre], 2001);
  for (size_t i = 0; i < f.depth_mm.size(); ++i)
    if (f.depth_mm[i] != 0) {
      ASSERT_EQ(f.depth_mm[i], std::lround(static_cast<double>(f.depth_true[i]) * 1000.0));
    }
}

TEST(SimRender, PitchedCameraSeesTargetHigherInTheImage) {
  const World w = empty_room(20, 20, 4);
  const double pitch = 0.1;  // nose down
  const std::vector<DronePose> drones = {pose(0, 0, 1.5, 0, pitch), pose(3, 0, 1.5)};
  Renderer r(w, fact::d430_424x240(), {}, no_noise(), 1);
  RenderedFrame f;
  r.render(drones, 0, &f);
  const auto gt = fact::sim::ground_truth(w, r.body(), r.intrinsics(), r.extrinsics(), drones, 0, &f);
  ASSERT_EQ(gt.size(), 1u);
  EXPECT_LT(gt[0].center_px.y(), 120 - 0.8 * 213 * std::tan(pitch));
  ASSERT_GT(gt[0].visible_pixels, 0);
  EXPECT_NEAR(0.5 * (gt[0].v_min + gt[0].v_max), gt[0].center_px.y(), 2.0);
  EXPECT_NEAR(0.5 * (gt[0].u_min + gt[0].u_max), gt[0].center_px.x(), 2.0);
  // The gravity-aligned vector ignores the pitch.
  EXPECT_NEAR((gt[0].vector_g - Eigen::Vector3d(3, 0, 0)).norm(), 0, 1e-12);
}

TEST(SimRender, LineOfSightBlockedByObstacleOrDrone) {
  World w = empty_room(20, 20, 4);
  w.obstacles.push_back(fact::sim::make_box({2, 0, 1}, {0.3, 1, 2}, 0));
  std::vector<DronePose> drones = {pose(0, 0, 1.5), pose(4, 0, 1.5), pose(0, 3, 1.5), pose(-3, 0, 1.5),
                                   pose(0, 6, 1.5)};
  Renderer r(w, fact::d430_424x240(), {}, no_noise(), 1);
  RenderedFrame f;
  r.render(drones, 0, &f);
  const auto gt = fact::sim::ground_truth(w, r.body(), r.intrinsics(), r.extrinsics(), drones, 0, &f);
  ASSERT_EQ(gt.size(), 4u);
  EXPECT_FALSE(gt[0].line_of_sight);  // behind the box
  EXPECT_TRUE(gt[0].center_in_image);
  EXPECT_EQ(gt[0].visible_pixels, 0);
  EXPECT_TRUE(gt[1].line_of_sight);   // to the left, outside the field of view
  EXPECT_FALSE(gt[1].center_in_image);
  EXPECT_FALSE(gt[2].in_front);       // behind the viewer
  EXPECT_FALSE(gt[2].center_in_image);
  EXPECT_TRUE(gt[2].line_of_sight);
  EXPECT_FALSE(gt[3].line_of_sight);  // drone 2 sits on the segment to drone 4
  // The obstacle's pixels carry its id.
  EXPECT_EQ(f.object_id[at(f.intrinsics, 212, 120)], fact::sim::kIdObstacle);
}

TEST(SimRender, SameSeedSameBytes) {
  const World w = fact::sim::default_world(4, 21);
  std::vector<DronePose> drones;
  for (const auto& s : w.starts) drones.push_back(pose(s.position.x(), s.position.y(), 1.5, s.yaw));
  Renderer a(w, fact::d430_424x240(), {}, {}, 77), b(w, fact::d430_424x240(), {}, {}, 77),
      c(w, fact::d430_424x240(), {}, {}, 78);
  RenderedFrame fa, fb, fc;
  for (int round = 0; round < 2; ++round)
    for (int i = 0; i < 4; ++i) {
      a.render(drones, i, &fa);
      b.render(drones, i, &fb);
      c.render(drones, i, &fc);
      EXPECT_EQ(fa.gray, fb.gray);
      EXPECT_EQ(fa.depth_mm, fb.depth_mm);
      EXPECT_EQ(fa.object_id, fb.object_id);
      EXPECT_EQ(fa.gray, fc.gray);          // noise is only in depth
      EXPECT_NE(fa.depth_mm, fc.depth_mm);  // another seed, other noise
    }
}

// Four drones of the default world turning one step per frame, each camera in turn (the load of
// fact-sim with 4 drones): every frame is complete — full-size buffers, every pixel on the room, an
// obstacle or another drone (never the viewer itself), with depth — and a camera's successive
// frames differ as it turns. How fast this runs is fact-bench-detector's renderer figure
// (BENCHMARKS.md), not a test.
TEST(SimRender, FourDronesTurningEveryFrameComplete) {
  const World w = fact::sim::default_world(4, 7);
  std::vector<DronePose> drones;
  for (const auto& s : w.starts) drones.push_back(pose(s.position.x(), s.position.y(), 1.5, s.yaw));
  Renderer r(w, fact::d430_424x240(), {}, {}, 1);
  const size_t pixels = 424u * 240u;
  std::vector<std::vector<uint8_t>> last_gray(4);
  RenderedFrame f;
  for (int k = 0; k < 120; ++k) {
    const int viewer = k % 4;
    drones[static_cast<size_t>(viewer)].yaw += 0.05;
    r.render(drones, viewer, &f);
    ASSERT_EQ(f.gray.size(), pixels);
    ASSERT_EQ(f.depth_mm.size(), pixels);
    ASSERT_EQ(f.object_id.size(), pixels);
    ASSERT_EQ(f.depth_true.size(), pixels);
    size_t hit = 0, with_depth = 0;
    for (size_t i = 0; i < pixels; ++i) {
      const int id = f.object_id[i];
      ASSERT_TRUE(id == fact::sim::kIdRoom || id == fact::sim::kIdObstacle || (id >= 0 && id < 4 && id != viewer))
          << "frame " << k << " pixel " << i << " id " << id;
      hit += f.depth_true[i] > 0;
      with_depth += f.depth_mm[i] > 0;
    }
    EXPECT_EQ(hit, pixels) << "frame " << k << ": a closed room, every ray hits something";
    EXPECT_GT(with_depth, pixels / 2) << "frame " << k;
    EXPECT_NE(f.gray, last_gray[static_cast<size_t>(viewer)]) << "frame " << k << ": the camera turned";
    last_gray[static_cast<size_t>(viewer)] = f.gray;
  }
}

}  // namespace
