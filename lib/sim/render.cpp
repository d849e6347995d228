// CPU renderer: per-pixel ray casting with a precomputed ray table. The room (the inside of an
// axis-aligned box) is analytic for every pixel; obstacles and drones are then ray-cast only
// inside their screen-space bounding rectangles, each keeping the nearer hit (a z-buffer on the
// ray parameter, which equals z_c because the rays have z_c = 1). A last pass adds depth noise.
#include "fact/sim_render.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fact::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Pixel rectangle [u0, u1) × [v0, v1); empty when u0 ≥ u1 or v0 ≥ v1.
struct Rect {
  int u0 = 0, v0 = 0, u1 = 0, v1 = 0;
};

// Screen rectangle holding the projection of the world-space box [lo, hi] for a camera with
// optical-from-world rotation R_cw (3×3) and optical centre c (world). A box that reaches behind
// the near plane covers the whole image; one wholly behind the camera covers nothing.
Rect screen_rect(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Matrix3d& R_cw,
                 const Eigen::Vector3d& c, const CameraIntrinsics& k) {
  const double near = 0.02;
  double umin = kInf, umax = -kInf, vmin = kInf, vmax = -kInf;
  int behind = 0;
  for (int i = 0; i < 8; ++i) {
    Eigen::Vector3d x((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(), (i & 4) ? hi.z() : lo.z());
    Eigen::Vector3d p = R_cw * (x - c);
    if (p.z() < near) {
      ++behind;
      continue;
    }
    Eigen::Vector2d uv = project(k, p);
    umin = std::min(umin, uv.x());
    umax = std::max(umax, uv.x());
    vmin = std::min(vmin, uv.y());
    vmax = std::max(vmax, uv.y());
  }
  if (behind == 8) return Rect{};
  if (behind > 0) return Rect{0, 0, k.width, k.height};
  Rect r;
  r.u0 = std::max(0, static_cast<int>(std::floor(umin)));
  r.v0 = std::max(0, static_cast<int>(std::floor(vmin)));
  r.u1 = std::min(k.width, static_cast<int>(std::ceil(umax)) + 2);
  r.v1 = std::min(k.height, static_cast<int>(std::ceil(vmax)) + 2);
  return r;
}

// Lambertian from a fixed overhead light plus a camera-mounted (head) light, and ambient.
uint8_t shade(double albedo, const Eigen::Vector3d& n, const Eigen::Vector3d& d_unit) {
  static const Eigen::Vector3d L = Eigen::Vector3d(0.25, 0.35, 1.0).normalized();
  double i = albedo * (0.30 + 0.45 * std::max(0.0, n.dot(L)) + 0.35 * std::abs(n.dot(d_unit)));
  return static_cast<uint8_t>(std::clamp(i * 255.0 + 0.5, 0.0, 255.0));
}

bool checker(double a, double b, double s) {
  return ((static_cast<long>(std::floor(a / s)) + static_cast<long>(std::floor(b / s))) & 1) != 0;
}

double obstacle_albedo(ObstacleKind k) {
  switch (k) {
    case ObstacleKind::box: return 0.62;
    case ObstacleKind::cylinder: return 0.50;
    case ObstacleKind::polytope: return 0.70;
  }
  return 0.6;
}

}  // namespace

FrameView RenderedFrame::view(int64_t utime) const {
  FrameView v;
  v.utime = utime;
  v.intrinsics = intrinsics;
  v.gray = gray.data();
  v.depth_mm = depth_mm.data();
  return v;
}

Eigen::Matrix3d camera_rotation(const DronePose& pose, const CameraExtrinsics& e) {
  return body_attitude(pose.yaw, pose.pitch, pose.roll) * e.R_body_cam;
}

Eigen::Vector3d camera_center(const DronePose& pose, const CameraExtrinsics& e) {
  return pose.position + body_attitude(pose.yaw, pose.pitch, pose.roll) * e.t_body_cam;
}

Renderer::Renderer(const World& world, const CameraIntrinsics& k, const CameraExtrinsics& extrinsics,
                   const RenderOptions& options, uint64_t seed, const DroneBody& body)
    : world_(world), k_(k), extrinsics_(extrinsics), options_(options), body_(body), rng_(seed) {
  parts_ = body_parts(body_);
  body_radius_ = bounding_radius(body_);
  rays_.resize(static_cast<size_t>(k_.width) * k_.height);
  for (int v = 0; v < k_.height; ++v)
    for (int u = 0; u < k_.width; ++u)
      rays_[static_cast<size_t>(v) * k_.width + u] =
          Eigen::Vector3f(static_cast<float>((u - k_.cx) / k_.fx), static_cast<float>((v - k_.cy) / k_.fy), 1.0f);
  std::mt19937_64 table_rng(seed ^ 0x9E3779B97F4A7C15ull);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  unit_normals_.resize(65536);
  for (auto& x : unit_normals_) x = normal(table_rng);
}

void Renderer::render(const std::vector<DronePose>& drones, int viewer, RenderedFrame* out) {
  const int W = k_.width, H = k_.height;
  const size_t N = static_cast<size_t>(W) * H;
  out->intrinsics = k_;
  out->gray.resize(N);
  out->depth_mm.resize(N);
  out->object_id.resize(N);
  out->depth_true.resize(N);

  const DronePose& me = drones.at(static_cast<size_t>(viewer));
  const Eigen::Matrix3d R_wc = camera_rotation(me, extrinsics_);  // world-from-optical (3×3)
  const Eigen::Matrix3d R_cw = R_wc.transpose();
  const Eigen::Vector3d c = camera_center(me, extrinsics_);       // optical centre (world)
  const Eigen::Vector3d lo = room_min(world_), hi = room_max(world_);
  const double cs = options_.checker_size;

  // 1. The room, for every pixel: exit point of the ray from the inside of the box.
  for (size_t i = 0; i < N; ++i) {
    const Eigen::Vector3d d = R_wc * rays_[i].cast<double>();
    double t = kInf;
    int axis = 2;
    for (int a = 0; a < 3; ++a) {
      if (d[a] == 0.0) continue;
      double ta = ((d[a] > 0 ? hi[a] : lo[a]) - c[a]) / d[a];
      if (ta < t) {
        t = ta;
        axis = a;
      }
    }
    // A camera on a face (a drone standing on the floor: its centre, and the camera, at z = 0)
    // meets that face at t = ±0: it sees it there, too near for depth (0); only a camera outside
    // the room sees nothing (those pixels were black, half of every frame before takeoff).
    const bool inside = t >= 0 && std::isfinite(t);  // (−0 ≥ 0)
    if (!inside) t = 0;
    const Eigen::Vector3d x = c + t * d;
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    n[axis] = d[axis] > 0 ? -1 : 1;
    double albedo;
    if (axis == 2) {
      albedo = d[2] < 0 ? (checker(x.x(), x.y(), cs) ? 0.45 : 0.75) : 0.80;  // floor / ceiling
    } else {
      const int other = axis == 0 ? 1 : 0;
      albedo = checker(x[other], x.z(), cs) ? 0.55 : 0.70;  // walls
    }
    out->depth_true[i] = static_cast<float>(t);
    out->object_id[i] = kIdRoom;
    out->gray[i] = inside ? shade(albedo, n, d.normalized()) : 0;
  }

  // 2. Obstacles inside their screen rectangles.
  for (const Obstacle& o : world_.obstacles) {
    Eigen::Vector3d blo, bhi;
    obstacle_bounds(o, &blo, &bhi);
    const Rect r = screen_rect(blo, bhi, R_cw, c, k_);
    const double albedo = obstacle_albedo(o.kind);
    for (int v = r.v0; v < r.v1; ++v)
      for (int u = r.u0; u < r.u1; ++u) {
        const size_t i = static_cast<size_t>(v) * W + u;
        const Eigen::Vector3d d = R_wc * rays_[i].cast<double>();
        Hit h;
        if (!intersect(o, Ray{c, d}, 1e-6, out->depth_true[i], &h)) continue;
        out->depth_true[i] = static_cast<float>(h.t);
        out->object_id[i] = kIdObstacle;
        out->gray[i] = shade(albedo, h.normal, d.normalized());
      }
  }

  // 3. Every other drone inside its screen rectangle: bounding sphere, then the body parts.
  for (size_t j = 0; j < drones.size(); ++j) {
    if (static_cast<int>(j) == viewer) continue;
    const DronePose& other = drones[j];
    const Eigen::Matrix3d R_wb = body_attitude(other.yaw, other.pitch, other.roll);  // world-from-body
    const Eigen::Matrix3d R_bc = R_wb.transpose() * R_wc;  // body(other)-from-optical(viewer)
    const Eigen::Vector3d o_b = R_wb.transpose() * (c - other.position);  // optical centre in its body frame
    const double rad = body_radius_;
    const Eigen::Vector3d ext = Eigen::Vector3d::Constant(rad);
    const Rect r = screen_rect(other.position - ext, other.position + ext, R_cw, c, k_);
    const double oo = o_b.squaredNorm() - rad * rad;
    for (int v = r.v0; v < r.v1; ++v)
      for (int u = r.u0; u < r.u1; ++u) {
        const size_t i = static_cast<size_t>(v) * W + u;
        const Eigen::Vector3d d_b = R_bc * rays_[i].cast<double>();
        // Ray–sphere rejection: |o_b + t d_b|² = rad² has a root ahead?
        const double a = d_b.squaredNorm(), b = o_b.dot(d_b);
        if (b * b - a * oo < 0) continue;
        Hit h;
        if (!intersect_body(parts_, Ray{o_b, d_b}, 1e-6, out->depth_true[i], &h)) continue;
        const Eigen::Vector3d n_w = R_wb * h.normal;
        const Eigen::Vector3d d_w = R_wb * d_b;
        out->depth_true[i] = static_cast<float>(h.t);
        out->object_id[i] = static_cast<int16_t>(j);
        const double albedo = h.normal.z() > 0.5 ? 0.22 : 0.15;
        out->gray[i] = shade(albedo, n_w, d_w.normalized());
      }
  }

  // 4. Depth: z + N(0, σ(z)²), 1 mm steps; 0 where the true z is outside [min_depth, max_depth].
  const DepthNoise& dn = options_.noise;
  const double k_sigma = dn.disparity_rms / (k_.fx * dn.baseline);  // σ = k_sigma · z²
  uint64_t bits = 0;
  int left = 0;
  for (size_t i = 0; i < N; ++i) {
    const double z = out->depth_true[i];
    if (!(z >= dn.min_depth && z <= dn.max_depth)) {
      out->depth_mm[i] = 0;
      continue;
    }
    double zn = z;
    if (options_.depth_noise) {
      if (left == 0) {
        bits = rng_();
        left = 4;
      }
      const float g = unit_normals_[bits & 0xFFFF];
      bits >>= 16;
      --left;
      zn = z + k_sigma * z * z * g;
    }
    const double mm = std::round(zn * 1000.0);
    out->depth_mm[i] = static_cast<uint16_t>(std::clamp(mm, 1.0, 65535.0));
  }
}

// ----------------------------------------------------------------------------------------------
// Ground truth

namespace {

// Whether the segment a → b (t ∈ (0, 1) along b − a) crosses an obstacle or the body of a drone
// other than `skip1` and `skip2`.
bool segment_blocked(const World& world, const std::vector<BodyPart>& parts, double body_radius,
                     const std::vector<DronePose>& drones, int skip1, int skip2, const Eigen::Vector3d& a,
                     const Eigen::Vector3d& b) {
  const Ray ray{a, b - a};
  Hit h;
  for (const Obstacle& o : world.obstacles)
    if (intersect(o, ray, 1e-9, 1.0, &h)) return true;
  for (size_t j = 0; j < drones.size(); ++j) {
    if (static_cast<int>(j) == skip1 || static_cast<int>(j) == skip2) continue;
    const DronePose& d = drones[j];
    // Quick reject: distance of the drone's centre from the segment > bounding radius.
    const Eigen::Vector3d ab = b - a;
    const double s = std::clamp((d.position - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    if ((a + s * ab - d.position).norm() > body_radius) continue;
    const Eigen::Matrix3d R_bw = body_attitude(d.yaw, d.pitch, d.roll).transpose();
    const Ray rb{R_bw * (a - d.position), R_bw * ab};
    if (intersect_body(parts, rb, 1e-9, 1.0, &h)) return true;
  }
  return false;
}

}  // namespace

std::vector<TargetTruth> ground_truth(const World& world, const DroneBody& body, const CameraIntrinsics& k,
                                      const CameraExtrinsics& e, const std::vector<DronePose>& drones, int viewer,
                                      const RenderedFrame* frame) {
  std::vector<TargetTruth> out;
  const DronePose& me = drones.at(static_cast<size_t>(viewer));
  const Eigen::Matrix3d R_wc = camera_rotation(me, e);
  const Eigen::Vector3d c = camera_center(me, e);
  // Viewer's gravity-aligned body frame: world-from-g is R_z(yaw).
  const Eigen::Matrix3d R_gw = Eigen::AngleAxisd(-me.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const std::vector<BodyPart> parts = body_parts(body);
  const double radius = bounding_radius(body);
  for (size_t j = 0; j < drones.size(); ++j) {
    if (static_cast<int>(j) == viewer) continue;
    TargetTruth t;
    t.index = static_cast<int>(j);
    const Eigen::Vector3d target = drones[j].position;
    t.p_cam = R_wc.transpose() * (target - c);
    t.vector_g = R_gw * (target - me.position);
    t.range = t.vector_g.norm();
    t.camera_range = t.p_cam.norm();
    t.in_front = t.p_cam.z() > 0;
    if (t.in_front) {
      t.center_px = project(k, t.p_cam);
      t.center_in_image = t.center_px.x() >= -0.5 && t.center_px.x() < k.width - 0.5 && t.center_px.y() >= -0.5 &&
                          t.center_px.y() < k.height - 0.5;
    }
    t.line_of_sight = !segment_blocked(world, parts, radius, drones, viewer, t.index, me.position, target);
    out.push_back(t);
  }
  if (frame == nullptr || frame->object_id.size() != static_cast<size_t>(k.width) * k.height) return out;
  std::vector<int> slot(drones.size(), -1);
  for (size_t s = 0; s < out.size(); ++s) slot[static_cast<size_t>(out[s].index)] = static_cast<int>(s);
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) {
      const int id = frame->object_id[static_cast<size_t>(v) * k.width + u];
      if (id < 0 || id >= static_cast<int>(drones.size()) || slot[static_cast<size_t>(id)] < 0) continue;
      TargetTruth& t = out[static_cast<size_t>(slot[static_cast<size_t>(id)])];
      if (t.visible_pixels == 0) {
        t.u_min = t.u_max = u;
        t.v_min = t.v_max = v;
      }
      ++t.visible_pixels;
      t.u_min = std::min(t.u_min, u);
      t.u_max = std::max(t.u_max, u);
      t.v_min = std::min(t.v_min, v);
      t.v_max = std::max(t.v_max, v);
    }
  for (auto& t : out) {
    if (t.visible_pixels == 0) continue;
    t.visible_box.u = static_cast<float>(t.u_min - 0.5);
    t.visible_box.v = static_cast<float>(t.v_min - 0.5);
    t.visible_box.w = static_cast<float>(t.u_max - t.u_min + 1);
    t.visible_box.h = static_cast<float>(t.v_max - t.v_min + 1);
    t.visible_box.score = 1.0f;
  }
  return out;
}

}  // namespace fact::sim
