// The planner's local obstacle map from the drone's own depth frames (fact/local_map.h).
#include "fact/local_map.h"

#include <algorithm>
#include <cmath>

namespace fact {

double box_distance(const ObstacleBox& b, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = (b.lo - p).cwiseMax(p - b.hi).cwiseMax(0.0);
  return d.norm();
}

std::string local_map_params_error(const LocalMapParams& p) {
  auto bad = [](const char* name, double v) { return std::string(name) + " = " + std::to_string(v) + " is invalid"; };
  if (!(p.resolution > 0.01 && p.resolution <= 1)) return bad("resolution (0.01 … 1 m)", p.resolution);
  if (!(p.z_max > p.z_min) || !std::isfinite(p.z_min) || !std::isfinite(p.z_max)) return bad("z_max", p.z_max);
  if (!(p.min_range >= 0) || !(p.max_range > p.min_range) || !std::isfinite(p.max_range)) return bad("max_range", p.max_range);
  if (!(p.half_extent_xy > p.resolution) || !std::isfinite(p.half_extent_xy)) return bad("half_extent_xy", p.half_extent_xy);
  if (!std::isfinite(p.floor_height)) return bad("floor_height", p.floor_height);
  if (p.hit_threshold < 1 || p.hit_threshold > 60000) return bad("hit_threshold", p.hit_threshold);
  if (p.pixel_step < 1) return bad("pixel_step", p.pixel_step);
  if (p.box_dilation_px < 0) return bad("box_dilation_px", p.box_dilation_px);
  if (!(p.box_dilation_fraction >= 0)) return bad("box_dilation_fraction", p.box_dilation_fraction);
  const double cells = local_map_voxels(p);
  if (cells > kMaxMapVoxels) return "grid of " + std::to_string(cells) + " voxels is too large";
  return "";
}

double local_map_voxels(const LocalMapParams& p) {
  const double side = 2 * p.half_extent_xy / p.resolution;
  return side * side * ((p.z_max - p.z_min) / p.resolution);
}

LocalMap::LocalMap(const LocalMapParams& params) : params_(params) {
  if (!local_map_params_error(params_).empty()) params_ = LocalMapParams{};
  nx_ = ny_ = static_cast<int>(std::ceil(2 * params_.half_extent_xy / params_.resolution));
  nz_ = static_cast<int>(std::ceil((params_.z_max - params_.z_min) / params_.resolution));
  origin_ = Eigen::Vector3d(-params_.half_extent_xy, -params_.half_extent_xy, params_.z_min);
  hits_.assign(static_cast<size_t>(nx_) * ny_ * nz_, 0);
  rays_for_.width = 0;
  touched_lo_ = Eigen::Vector3i(nx_, ny_, nz_);
  touched_hi_ = Eigen::Vector3i(-1, -1, -1);
}

void LocalMap::clear() {
  std::fill(hits_.begin(), hits_.end(), 0);
  touched_lo_ = Eigen::Vector3i(nx_, ny_, nz_);
  touched_hi_ = Eigen::Vector3i(-1, -1, -1);
}

std::string LocalMap::add_frame(const FrameView& frame, const CameraExtrinsics& extrinsics, const MapPose& pose,
                                const std::vector<BoxDetection>& drone_boxes, FrameIntegration* stats) {
  const CameraIntrinsics& k = frame.intrinsics;
  const std::string kerr = intrinsics_error(k);
  if (!kerr.empty()) return "frame.intrinsics: " + kerr;
  if (frame.depth_mm == nullptr) return "frame.depth_mm is null";
  if (!pose.position.allFinite()) return "pose.position is not finite";
  if (pose.position.cwiseAbs().maxCoeff() > 1e6) return "pose.position is beyond 1e6 m";
  if (!std::isfinite(pose.yaw)) return "pose.yaw is not finite";
  if (!std::isfinite(pose.pitch)) return "pose.pitch is not finite";
  if (!std::isfinite(pose.roll)) return "pose.roll is not finite";
  if (!extrinsics.R_body_cam.allFinite() || !extrinsics.t_body_cam.allFinite()) return "extrinsics are not finite";
  for (size_t i = 0; i < drone_boxes.size(); ++i) {
    const BoxDetection& b = drone_boxes[i];
    if (!std::isfinite(b.u) || !std::isfinite(b.v) || !std::isfinite(b.w) || !std::isfinite(b.h))
      return "drone_boxes[" + std::to_string(i) + "] is not finite";
    if (b.w < 0 || b.h < 0)
      return "drone_boxes[" + std::to_string(i) + "] has a negative size (" + std::to_string(b.w) + " × " +
             std::to_string(b.h) + " px)";
  }
  const int W = k.width, H = k.height;
  // Ray tables for these intrinsics.
  if (rays_for_.width != W || rays_for_.height != H || rays_for_.fx != k.fx || rays_for_.fy != k.fy ||
      rays_for_.cx != k.cx || rays_for_.cy != k.cy) {
    ray_x_.resize(W);
    ray_y_.resize(H);
    for (int u = 0; u < W; ++u) ray_x_[u] = static_cast<float>((u - k.cx) / k.fx);
    for (int v = 0; v < H; ++v) ray_y_[v] = static_cast<float>((v - k.cy) / k.fy);
    rays_for_ = k;
  }
  // Mask of the dilated drone boxes.
  mask_.assign(static_cast<size_t>(W) * H, 0);
  for (const BoxDetection& b : drone_boxes) {
    const double gu = params_.box_dilation_px + params_.box_dilation_fraction * b.w;
    const double gv = params_.box_dilation_px + params_.box_dilation_fraction * b.h;
    // The box encloses pixel centres u ∈ [b.u, b.u + b.w] (fact/frame.h), clipped to the image in
    // double before any int conversion: a box beyond the image's edge gave a reversed fill range
    // (and 1e30 an undefined conversion), which crashed fact-planner (review, session 30).
    const double u0 = std::max(0.0, std::floor(b.u - gu + 0.5)), u1 = std::min(W - 1.0, std::ceil(b.u + b.w + gu - 0.5));
    const double v0 = std::max(0.0, std::floor(b.v - gv + 0.5)), v1 = std::min(H - 1.0, std::ceil(b.v + b.h + gv - 0.5));
    if (!(u0 <= u1 && v0 <= v1)) continue;  // nothing of it in the image
    for (int v = static_cast<int>(v0); v <= static_cast<int>(v1); ++v)
      std::fill(mask_.begin() + v * W + static_cast<int>(u0), mask_.begin() + v * W + static_cast<int>(u1) + 1, 1);
  }
  // p_f = R_fc · p_c + t_fc; R_fc (3×3) = attitude · R_body_cam, t_fc (3) = attitude · t_body_cam + position.
  // The farthest a mapped point can be from the drone: max_range along the widest ray (a corner's
  // (u, v, 1) is longer than the optical axis: 1.48× for a D430) plus the camera's offset.
  const double rx = std::max(std::abs(ray_x_.front()), std::abs(ray_x_.back()));
  const double ry = std::max(std::abs(ray_y_.front()), std::abs(ray_y_.back()));
  const double reach = params_.max_range * std::sqrt(rx * rx + ry * ry + 1) + extrinsics.t_body_cam.norm();
  const int forgotten = follow(pose.position, reach);
  const Eigen::Matrix3d att = body_attitude(pose.yaw, pose.pitch, pose.roll);
  const Eigen::Matrix3f R = (att * extrinsics.R_body_cam).cast<float>();
  const Eigen::Vector3f t = (att * extrinsics.t_body_cam + pose.position).cast<float>();
  const Eigen::Vector3f o = origin_.cast<float>();
  const float inv_res = static_cast<float>(1.0 / params_.resolution);
  const float zmin_mm = static_cast<float>(params_.min_range * 1000), zmax_mm = static_cast<float>(params_.max_range * 1000);
  const float floor_z = static_cast<float>(params_.floor_height);
  FrameIntegration st;
  st.recentred = forgotten >= 0;
  st.forgotten = std::max(forgotten, 0);
  Eigen::Vector3i tlo = touched_lo_, thi = touched_hi_;
  const int step = params_.pixel_step;
  for (int v = 0; v < H; v += step) {
    const uint16_t* row = frame.depth_mm + static_cast<size_t>(v) * W;
    const uint8_t* mrow = mask_.data() + static_cast<size_t>(v) * W;
    const float yn = ray_y_[v];
    for (int u = 0; u < W; u += step) {
      const float zmm = row[u];
      if (zmm == 0 || zmm < zmin_mm || zmm > zmax_mm) {
        ++st.out_of_range;
        continue;
      }
      if (mrow[u]) {
        ++st.removed_drone;
        continue;
      }
      const float z = zmm * 0.001f;
      const Eigen::Vector3f pc(ray_x_[u] * z, yn * z, z);
      const Eigen::Vector3f p = R * pc + t;
      if (p.z() < floor_z) {
        ++st.floor;
        continue;
      }
      const Eigen::Vector3f g = (p - o) * inv_res;
      const int ix = static_cast<int>(std::floor(g.x())), iy = static_cast<int>(std::floor(g.y())),
                iz = static_cast<int>(std::floor(g.z()));
      if (ix < 0 || iy < 0 || iz < 0 || ix >= nx_ || iy >= ny_ || iz >= nz_) {
        ++st.out_of_range;
        continue;
      }
      uint16_t& h = hits_[(static_cast<size_t>(iz) * ny_ + iy) * nx_ + ix];
      if (h < 65535) ++h;
      const Eigen::Vector3i ii(ix, iy, iz);
      tlo = tlo.cwiseMin(ii);
      thi = thi.cwiseMax(ii);
      ++st.points;
    }
  }
  touched_lo_ = tlo;
  touched_hi_ = thi;
  if (stats) *stats = st;
  return "";
}

int LocalMap::follow(const Eigen::Vector3d& p, double reach) {
  const double half = 0.5 * nx_ * params_.resolution;  // (nx_ = ny_)
  const Eigen::Vector2d centre = origin_.head<2>() + Eigen::Vector2d::Constant(half);
  // (keep ≤ 0: a grid smaller than a frame's reach re-centres whenever the drone moves a voxel)
  const double keep = half - reach - params_.resolution;
  if ((p.head<2>() - centre).cwiseAbs().maxCoeff() <= keep) return -1;
  // Shift by whole voxels: new voxel (ix, iy) is old voxel (ix + sx, iy + sy).
  const int sx = static_cast<int>(std::lround((p.x() - centre.x()) / params_.resolution));
  const int sy = static_cast<int>(std::lround((p.y() - centre.y()) / params_.resolution));
  if (sx == 0 && sy == 0) return -1;
  const uint16_t thr = static_cast<uint16_t>(params_.hit_threshold);
  std::vector<uint16_t> moved(hits_.size(), 0);
  int kept = 0;
  for (int iz = 0; iz < nz_; ++iz)
    for (int iy = 0; iy < ny_; ++iy) {
      const int oy = iy + sy;
      if (oy < 0 || oy >= ny_) continue;
      for (int ix = 0; ix < nx_; ++ix) {
        const int ox = ix + sx;
        if (ox < 0 || ox >= nx_) continue;
        const uint16_t h = hits_[(static_cast<size_t>(iz) * ny_ + oy) * nx_ + ox];
        moved[(static_cast<size_t>(iz) * ny_ + iy) * nx_ + ix] = h;
        kept += h >= thr;
      }
    }
  const int forgotten = occupied_voxels() - kept;
  hits_.swap(moved);
  origin_ += params_.resolution * Eigen::Vector3d(sx, sy, 0);
  if ((touched_hi_.array() >= touched_lo_.array()).all()) {
    const Eigen::Vector3i shift(sx, sy, 0), top(nx_ - 1, ny_ - 1, nz_ - 1);
    touched_lo_ = (touched_lo_ - shift).cwiseMax(0);
    touched_hi_ = (touched_hi_ - shift).cwiseMin(top);
  }
  return forgotten;
}

ObstacleBox LocalMap::bounds() const {
  ObstacleBox b;
  b.lo = origin_;
  b.hi = origin_ + params_.resolution * Eigen::Vector3d(nx_, ny_, nz_);
  return b;
}

int LocalMap::occupied_voxels() const {
  const uint16_t thr = static_cast<uint16_t>(params_.hit_threshold);
  return static_cast<int>(std::count_if(hits_.begin(), hits_.end(), [thr](uint16_t h) { return h >= thr; }));
}

bool LocalMap::occupied(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d g = (p - origin_) / params_.resolution;
  const int ix = static_cast<int>(std::floor(g.x())), iy = static_cast<int>(std::floor(g.y())),
            iz = static_cast<int>(std::floor(g.z()));
  if (ix < 0 || iy < 0 || iz < 0 || ix >= nx_ || iy >= ny_ || iz >= nz_) return false;
  return hits_[(static_cast<size_t>(iz) * ny_ + iy) * nx_ + ix] >= params_.hit_threshold;
}

std::vector<ObstacleBox> LocalMap::pieces() const {
  // Greedy merge: for each occupied voxel not yet covered (z, y, x order), grow a run along x,
  // then extend the run along y while the whole row is occupied and uncovered, then along z while
  // the whole rectangle is; mark the box covered. Only the region ever hit is scanned.
  std::vector<ObstacleBox> out;
  if ((touched_hi_.array() < touched_lo_.array()).any()) return out;
  const uint16_t thr = static_cast<uint16_t>(params_.hit_threshold);
  const Eigen::Vector3i lo = touched_lo_, hi = touched_hi_;
  const Eigen::Vector3i n = hi - lo + Eigen::Vector3i::Ones();
  std::vector<uint8_t> covered(static_cast<size_t>(n.x()) * n.y() * n.z(), 0);
  auto cov = [&](int x, int y, int z) -> uint8_t& {
    return covered[(static_cast<size_t>(z - lo.z()) * n.y() + (y - lo.y())) * n.x() + (x - lo.x())];
  };
  auto free_cell = [&](int x, int y, int z) {
    return hits_[(static_cast<size_t>(z) * ny_ + y) * nx_ + x] >= thr && !cov(x, y, z);
  };
  for (int z = lo.z(); z <= hi.z(); ++z) {
    for (int y = lo.y(); y <= hi.y(); ++y) {
      for (int x = lo.x(); x <= hi.x(); ++x) {
        if (!free_cell(x, y, z)) continue;
        int x1 = x;
        while (x1 + 1 <= hi.x() && free_cell(x1 + 1, y, z)) ++x1;
        int y1 = y;
        for (;;) {
          if (y1 + 1 > hi.y()) break;
          bool ok = true;
          for (int xx = x; xx <= x1 && ok; ++xx) ok = free_cell(xx, y1 + 1, z);
          if (!ok) break;
          ++y1;
        }
        int z1 = z;
        for (;;) {
          if (z1 + 1 > hi.z()) break;
          bool ok = true;
          for (int yy = y; yy <= y1 && ok; ++yy)
            for (int xx = x; xx <= x1 && ok; ++xx) ok = free_cell(xx, yy, z1 + 1);
          if (!ok) break;
          ++z1;
        }
        for (int zz = z; zz <= z1; ++zz)
          for (int yy = y; yy <= y1; ++yy)
            for (int xx = x; xx <= x1; ++xx) cov(xx, yy, zz) = 1;
        ObstacleBox b;
        b.lo = origin_ + params_.resolution * Eigen::Vector3d(x, y, z);
        b.hi = origin_ + params_.resolution * Eigen::Vector3d(x1 + 1, y1 + 1, z1 + 1);
        out.push_back(b);
      }
    }
  }
  return out;
}

}  // namespace fact
