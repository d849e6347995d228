// A ByteTrack-style multi-object tracker for detection boxes, with the observer's own rotation
// compensated by the homography H = K·R·K⁻¹, and the helpers that compute H from two attitudes.
// Plain data, no OpenCV, no LCM, no I/O.
//
// Each track has a constant-velocity Kalman filter on its box: state x (8) = (cx, cy, w, h, vcx,
// vcy, vw, vh) in pixels and pixels per frame; covariance P (8×8); measurement z (4) = (cx, cy, w, h).
// Per frame (update): (1) every track's predicted centre is moved by H (the camera's rotation since
// the previous frame), then the filter predicts one frame; (2) detections with score ≥ high_score
// are matched to confirmed and lost tracks by IoU (fact::solve_assignment, cost 1 − IoU, no-match
// cost 1 − min_iou_high); (3) detections with low_score ≤ score < high_score are matched to the
// confirmed tracks still unmatched (min_iou_low); (4) remaining high detections to tentative tracks
// (min_iou_tentative); (5) unmatched tentative tracks are removed, unmatched confirmed tracks become
// lost, lost tracks unmatched for more than max_lost frames are removed; (6) high detections still
// unmatched with score ≥ new_track_score start tentative tracks, which are confirmed after
// confirm_hits consecutive matches. Track ids are never reused.
#pragma once

#include "fact/camera.h"
#include "fact/frame.h"

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace fact {

// Camera rotation from the previous frame to this one, cam_now-from-cam_prev (3×3), for a camera
// mounted by `extrinsics` on a body whose world attitudes were body_attitude(yaw, pitch, roll)
// (rad) at the two frames: R = (R_wb_now·R_bc)ᵀ · (R_wb_prev·R_bc). A direction d fixed in the
// world seen as d_prev in the previous camera frame is R·d_prev now.
Eigen::Matrix3d camera_rotation(double yaw_prev, double pitch_prev, double roll_prev, double yaw_now,
                                double pitch_now, double roll_now, const CameraExtrinsics& extrinsics);

// Pixel homography of a pure camera rotation R (cam_now-from-cam_prev): H = K·R·K⁻¹ (3×3), K the
// intrinsics matrix [fx 0 cx; 0 fy cy; 0 0 1]. Maps homogeneous pixels of the previous frame to
// this one (exact for distant points; the camera's 0.1 m lever arm is ignored).
Eigen::Matrix3d rotation_homography(const CameraIntrinsics& k, const Eigen::Matrix3d& R);

// A pixel (u, v) moved by H (3×3, homogeneous).
Eigen::Vector2d apply_homography(const Eigen::Matrix3d& H, const Eigen::Vector2d& uv);

// Intersection over union of two boxes (0 when either is empty).
double box_iou(const BoxDetection& a, const BoxDetection& b);

struct TrackerOptions {
  float high_score = 0.6f;        // first-stage detections
  float low_score = 0.1f;         // below: ignored
  float new_track_score = 0.8f;   // a new track needs at least this
  double min_iou_high = 0.2;      // stage 1: match only when IoU ≥ this
  double min_iou_low = 0.4;       // stage 2
  double min_iou_tentative = 0.3; // stage 3
  // IoU is computed on boxes grown about their centres to at least this many pixels per side, so
  // that small, thin, far drones (a few pixels tall) still overlap under a pixel or two of jitter.
  float iou_min_side = 16.0f;     // px
  int confirm_hits = 2;           // consecutive matched frames to confirm a tentative track (ByteTrack: 2)
  int max_lost = 30;              // frames a lost track waits for a detection before removal
  // Kalman noise, as fractions of the box height (ByteTrack's weights), per frame.
  double std_position = 1.0 / 20;
  double std_velocity = 1.0 / 160;
};

enum class TrackState { tentative, confirmed, lost };

struct Track {
  int id = 0;                       // persistent, ≥ 1, never reused
  TrackState state = TrackState::tentative;
  Eigen::Matrix<double, 8, 1> x;    // Kalman state (cx, cy, w, h, vcx, vcy, vw, vh), px, px/frame
  Eigen::Matrix<double, 8, 8> P;    // its covariance
  BoxDetection box;                 // the last matched detection (its box and score)
  int detection = -1;               // index of this frame's matched detection, −1 if none
  int hits = 0;                     // consecutive matched frames
  int age = 0;                      // frames since the track started
  int missed = 0;                   // consecutive unmatched frames
  BoxDetection predicted() const;   // the filter's box (score of the last match)
};

class Tracker {
 public:
  explicit Tracker(const TrackerOptions& options = {});

  // One frame's detections; H (3×3) maps the previous frame's pixels to this frame's (identity when
  // the observer did not rotate; see rotation_homography). Returns the live tracks (confirmed,
  // tentative and lost); Track::detection tells which detection each matched this frame.
  const std::vector<Track>& update(const std::vector<BoxDetection>& detections,
                                   const Eigen::Matrix3d& H = Eigen::Matrix3d::Identity());

  const std::vector<Track>& tracks() const { return tracks_; }
  // The confirmed tracks matched this frame (the ones a detector publishes).
  std::vector<const Track*> confirmed_matched() const;
  void reset();

 private:
  void predict(Track& t, const Eigen::Matrix3d& H) const;
  void correct(Track& t, const BoxDetection& d, int index) const;
  Track start(const BoxDetection& d, int index);

  TrackerOptions options_;
  std::vector<Track> tracks_;
  int next_id_ = 1;
};

}  // namespace fact
