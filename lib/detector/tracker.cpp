// The ByteTrack-style tracker and the own-rotation homography (fact/tracker.h).
#include "fact/tracker.h"

#include "fact/hungarian.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fact {

Eigen::Matrix3d camera_rotation(double yaw_prev, double pitch_prev, double roll_prev, double yaw_now,
                                double pitch_now, double roll_now, const CameraExtrinsics& extrinsics) {
  // World-from-camera rotations (3×3) at the two frames.
  const Eigen::Matrix3d R_wc_prev = body_attitude(yaw_prev, pitch_prev, roll_prev) * extrinsics.R_body_cam;
  const Eigen::Matrix3d R_wc_now = body_attitude(yaw_now, pitch_now, roll_now) * extrinsics.R_body_cam;
  return R_wc_now.transpose() * R_wc_prev;
}

Eigen::Matrix3d rotation_homography(const CameraIntrinsics& k, const Eigen::Matrix3d& R) {
  Eigen::Matrix3d K;  // intrinsics matrix (3×3): optical-frame direction → homogeneous pixel
  K << k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1;
  Eigen::Matrix3d K_inv;
  K_inv << 1 / k.fx, 0, -k.cx / k.fx, 0, 1 / k.fy, -k.cy / k.fy, 0, 0, 1;
  return K * R * K_inv;
}

Eigen::Vector2d apply_homography(const Eigen::Matrix3d& H, const Eigen::Vector2d& uv) {
  const Eigen::Vector3d p = H * Eigen::Vector3d(uv.x(), uv.y(), 1.0);
  return p.head<2>() / p.z();
}

double box_iou(const BoxDetection& a, const BoxDetection& b) {
  const double iw = std::min(a.u + a.w, b.u + b.w) - std::max(a.u, b.u);
  const double ih = std::min(a.v + a.h, b.v + b.h) - std::max(a.v, b.v);
  if (iw <= 0 || ih <= 0 || a.w <= 0 || a.h <= 0 || b.w <= 0 || b.h <= 0) return 0.0;
  const double inter = iw * ih;
  return inter / (double(a.w) * a.h + double(b.w) * b.h - inter);
}

namespace {

using Vec4 = Eigen::Matrix<double, 4, 1>;
using Mat4 = Eigen::Matrix<double, 4, 4>;
using Mat48 = Eigen::Matrix<double, 4, 8>;

Vec4 measurement(const BoxDetection& d) {  // (cx, cy, w, h), px
  return Vec4(d.u + d.w * 0.5, d.v + d.h * 0.5, d.w, d.h);
}

// Noise scale of a box (px): its larger side, at least 8 px, so small far boxes are not overconfident.
double noise_scale(double w, double h) { return std::max({w, h, 8.0}); }

BoxDetection grown(const BoxDetection& b, float min_side) {
  BoxDetection g = b;
  if (g.w < min_side) {
    g.u -= (min_side - g.w) * 0.5f;
    g.w = min_side;
  }
  if (g.h < min_side) {
    g.v -= (min_side - g.h) * 0.5f;
    g.h = min_side;
  }
  return g;
}

// Matches tracks (indices into `tracks`) to detections (indices into `dets`) by 1 − IoU of the grown
// boxes; pairs with IoU below min_iou are never matched. Unmatched entries are left in the lists.
void associate(std::vector<Track>& tracks, std::vector<int>& track_idx, const std::vector<BoxDetection>& dets,
               std::vector<int>& det_idx, double min_iou, float min_side,
               std::vector<std::pair<int, int>>& matches) {
  if (track_idx.empty() || det_idx.empty()) return;
  Eigen::MatrixXd cost(track_idx.size(), det_idx.size());  // rows tracks, cols detections: 1 − IoU
  for (size_t r = 0; r < track_idx.size(); ++r) {
    const BoxDetection p = grown(tracks[static_cast<size_t>(track_idx[r])].predicted(), min_side);
    for (size_t c = 0; c < det_idx.size(); ++c) {
      const double iou = box_iou(p, grown(dets[static_cast<size_t>(det_idx[c])], min_side));
      cost(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) =
          iou >= min_iou ? 1.0 - iou : std::numeric_limits<double>::infinity();
    }
  }
  const Assignment a = solve_assignment(cost, 1.0 - min_iou);
  std::vector<int> rest_tracks, rest_dets;
  for (size_t r = 0; r < track_idx.size(); ++r) {
    const int c = a.row_to_col[r];
    if (c >= 0)
      matches.emplace_back(track_idx[r], det_idx[static_cast<size_t>(c)]);
    else
      rest_tracks.push_back(track_idx[r]);
  }
  for (size_t c = 0; c < det_idx.size(); ++c)
    if (a.col_to_row[c] < 0) rest_dets.push_back(det_idx[c]);
  track_idx.swap(rest_tracks);
  det_idx.swap(rest_dets);
}

}  // namespace

BoxDetection Track::predicted() const {
  BoxDetection b;
  b.w = static_cast<float>(std::max(1.0, x(2)));
  b.h = static_cast<float>(std::max(1.0, x(3)));
  b.u = static_cast<float>(x(0) - b.w * 0.5);
  b.v = static_cast<float>(x(1) - b.h * 0.5);
  b.score = box.score;
  return b;
}

Tracker::Tracker(const TrackerOptions& options) : options_(options) {}

void Tracker::reset() { tracks_.clear(); }

Track Tracker::start(const BoxDetection& d, int index) {
  Track t;
  t.id = next_id_++;
  t.state = options_.confirm_hits <= 1 ? TrackState::confirmed : TrackState::tentative;
  t.x.setZero();
  t.x.head<4>() = measurement(d);
  const double s = noise_scale(d.w, d.h);
  const double sp = 2 * options_.std_position * s, sv = 10 * options_.std_velocity * s;
  t.P.setZero();
  t.P.diagonal() << sp * sp, sp * sp, sp * sp, sp * sp, sv * sv, sv * sv, sv * sv, sv * sv;
  t.box = d;
  t.detection = index;
  t.hits = 1;
  return t;
}

void Tracker::predict(Track& t, const Eigen::Matrix3d& H) const {
  // Own rotation: the box centre moves with the image; the filter's velocity is the target's own motion.
  const Eigen::Vector2d c = apply_homography(H, t.x.head<2>());
  t.x(0) = c.x();
  t.x(1) = c.y();
  Eigen::Matrix<double, 8, 8> F = Eigen::Matrix<double, 8, 8>::Identity();  // constant velocity, one frame
  F.topRightCorner<4, 4>().setIdentity();
  const double s = noise_scale(t.x(2), t.x(3));
  const double sp = options_.std_position * s, sv = options_.std_velocity * s;
  Eigen::Matrix<double, 8, 1> q;
  q << sp * sp, sp * sp, sp * sp, sp * sp, sv * sv, sv * sv, sv * sv, sv * sv;
  t.x = F * t.x;
  t.P = F * t.P * F.transpose();
  t.P.diagonal() += q;
  t.detection = -1;
  ++t.age;
}

void Tracker::correct(Track& t, const BoxDetection& d, int index) const {
  Mat48 Hm = Mat48::Zero();  // measurement matrix (4×8): picks (cx, cy, w, h)
  Hm.leftCols<4>().setIdentity();
  const double s = noise_scale(d.w, d.h);
  const double r = options_.std_position * s;
  const Mat4 S = Hm * t.P * Hm.transpose() + Mat4::Identity() * (r * r);  // innovation covariance (4×4)
  const Eigen::Matrix<double, 8, 4> K = t.P * Hm.transpose() * S.inverse();  // Kalman gain (8×4)
  t.x += K * (measurement(d) - Hm * t.x);
  t.P = (Eigen::Matrix<double, 8, 8>::Identity() - K * Hm) * t.P;
  t.box = d;
  t.detection = index;
  t.missed = 0;
  ++t.hits;
  if (t.state == TrackState::lost || (t.state == TrackState::tentative && t.hits >= options_.confirm_hits))
    t.state = TrackState::confirmed;
}

const std::vector<Track>& Tracker::update(const std::vector<BoxDetection>& detections, const Eigen::Matrix3d& H) {
  for (Track& t : tracks_) predict(t, H);
  std::vector<int> high, low, pool, tentative;
  for (size_t i = 0; i < detections.size(); ++i) {
    const float s = detections[i].score;
    if (!(detections[i].w > 0 && detections[i].h > 0)) continue;
    if (s >= options_.high_score)
      high.push_back(static_cast<int>(i));
    else if (s >= options_.low_score)
      low.push_back(static_cast<int>(i));
  }
  for (size_t i = 0; i < tracks_.size(); ++i)
    (tracks_[i].state == TrackState::tentative ? tentative : pool).push_back(static_cast<int>(i));

  std::vector<std::pair<int, int>> matches;  // (track index, detection index)
  const float side = options_.iou_min_side;
  associate(tracks_, pool, detections, high, options_.min_iou_high, side, matches);  // stage 1
  std::vector<int> pool2;                                                           // stage 2: tracked only
  for (int i : pool)
    if (tracks_[static_cast<size_t>(i)].state == TrackState::confirmed) pool2.push_back(i);
  associate(tracks_, pool2, detections, low, options_.min_iou_low, side, matches);
  associate(tracks_, tentative, detections, high, options_.min_iou_tentative, side, matches);  // stage 3

  std::vector<bool> matched(tracks_.size(), false);
  for (const auto& [ti, di] : matches) {
    correct(tracks_[static_cast<size_t>(ti)], detections[static_cast<size_t>(di)], di);
    matched[static_cast<size_t>(ti)] = true;
  }
  std::vector<Track> kept;
  kept.reserve(tracks_.size() + high.size());
  for (size_t i = 0; i < tracks_.size(); ++i) {
    Track& t = tracks_[i];
    if (!matched[i]) {
      if (t.state == TrackState::tentative) continue;  // a tentative track dies at its first miss
      t.state = TrackState::lost;
      t.hits = 0;
      if (++t.missed > options_.max_lost) continue;
    }
    kept.push_back(t);
  }
  for (int di : high)
    if (detections[static_cast<size_t>(di)].score >= options_.new_track_score)
      kept.push_back(start(detections[static_cast<size_t>(di)], di));
  tracks_.swap(kept);
  return tracks_;
}

std::vector<const Track*> Tracker::confirmed_matched() const {
  std::vector<const Track*> out;
  for (const Track& t : tracks_)
    if (t.state == TrackState::confirmed && t.detection >= 0) out.push_back(&t);
  return out;
}

}  // namespace fact
