// Drone detection in one gray + depth frame (fact/frame.h), and what a box says about the target:
// its range and its vector in the gravity-aligned body frame. Plain functions over plain data; the
// implementation uses OpenCV's imgproc inside lib/detector, nothing of it shows here. No LCM, no I/O.
//
// Conventions (fact/camera.h): optical frame c (x right, y down, z forward), body frame b (FLU),
// gravity-aligned body frame g; depth images hold z_c in mm, 0 = invalid. Boxes (fact/frame.h)
// enclose their pixels: pixel centres are integers, so a blob of columns u_min … u_max has
// u = u_min − 0.5 and w = u_max − u_min + 1, and its centre is u + w/2 (as fact_sim's truth boxes).
#pragma once

#include "fact/camera.h"
#include "fact/frame.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace fact {

// "" when the frame can be processed, else what is wrong, naming the field and value: unusable
// intrinsics (intrinsics_error), a null gray or depth_mm buffer, or depth with no valid pixel.
std::string frame_error(const FrameView& frame);

// The depth-segmentation backend's parameters (units in the comments).
struct SegmentationOptions {
  double min_depth = 0.25;     // m: nearer pixels are ignored
  double max_depth = 8.0;      // m: farther pixels are background, never part of a blob
  // Working resolution: the depth is reduced by this factor (each f × f block → its nearest valid
  // depth, which keeps thin near structures) before segmentation; 0 = automatic (2 for images wider
  // than 480 px, else 1). Boxes are returned in full-resolution pixels.
  int decimation = 0;
  bool median_filter = true;   // 3 × 3 median of the (decimated) depth before segmentation
  // Two 4-neighbour pixels belong to one surface unless their depths differ by more than
  // edge_min + edge_sigmas · √2 · σ_w(z), σ_w the working image's noise: σ_z (from `noise` and
  // the full-resolution frame's fx, at the nearer depth) × 0.7 after decimation (nearest of 4)
  // × 0.5 after the median. On a flat wall at 6 m the largest neighbour difference of the working
  // image is 0.25 m and the threshold 0.34 m (it was 0.60 m while σ_z came from the working
  // image's fx, half the frame's, and a drone 0.6 m before a wall merged into it).
  double edge_min = 0.08;      // m
  double edge_sigmas = 3.5;    // noise standard deviations of a two-pixel difference
  DepthNoise noise;            // the camera's depth noise model (camera.h)
  // Physical size of a drone blob: its box's width and height at its depth (w·z/fx, h·z/fy).
  double min_size = 0.08;      // m: the larger side at least this
  double min_width = 0.08;     // m: the width at least this (the hub alone is 0.12 m wide from any side)
  double max_size = 0.50;      // m: both sides at most this (the drone is 0.41 m across its rotors)
  // A drone is flat: seen at elevation angle e (from the box centre's image row, camera assumed
  // near level) its height is at most flat_height + diameter · sin(min(90°, |e| + tilt_slack)),
  // and at most flat_height more than its width.
  double flat_height = 0.12;   // m: edge-on height (hub and rotors)
  double diameter = 0.45;      // m: rotor tip to rotor tip
  double tilt_slack = 0.35;    // rad: the target's and the observer's tilt, together
  int min_pixels = 4;          // full-resolution pixels in a blob (after merging its parts)
  int min_part_pixels = 2;     // working pixels; smaller components are noise, never a drone's part
  int max_parts = 2000;        // parts kept for merging, the largest by area (speckled depth made
                               // tens of thousands, and merging them took seconds a frame)
  // Parts of one drone (rotors, body) that the segmentation splits are merged when their mean
  // depths differ by less than merge_depth (or the edge threshold, if larger) and their boxes are
  // closer than merge_gap. A drone's rotor centres are 0.28 m apart, so seen from any side its
  // parts' depths differ by up to about that much.
  double merge_depth = 0.30;   // m
  double merge_gap = 0.08;     // m (at the parts' depth)
  // Surroundings: a ring `ring` wide (m, at the blob's depth, at least 2 px) around the box; a
  // drone is nearer than most of it by at least `background_gap` (invalid pixels count as far).
  double ring = 0.10;            // m
  double background_gap = 0.30;  // m
  // Fraction of the ring that must be farther, else no detection. The score is this fraction
  // (× border_factor for a blob touching the image border), so blobs between min_far_fraction
  // and the tracker's high_score are its low-score detections.
  double min_far_fraction = 0.3;
  // 0.5: below the tracker's high_score (0.6), so a blob cut by the image border (part of it
  // unseen, its size unknown) continues a track but never starts one.
  double border_factor = 0.5;
};

// What the segmentation found, before any tracking (score in [0, 1]: how clearly the blob stands
// out of its surroundings and how well its size fits a drone).
std::vector<BoxDetection> detect_depth(const FrameView& frame, const SegmentationOptions& options);

// Range of the target in a box (the paper's method).
struct RangeOptions {
  double smallest_percent = 20.0;  // % of the valid depths inside the box that are averaged (0 < X ≤ 100)
  // Distance from the visible near surface (the mean of the smallest depths) to the target's
  // centre, added along the box-centre ray (m). The drone model's bounding radius is 0.21 m, but
  // the mean of its nearest 20 % of pixels lies behind its foremost point; 0.17 m is the value
  // that makes the median range error on fact_sim's rendered drone ≈ 0 at 640 × 480 (README).
  double target_radius = 0.17;
  double min_depth = 0.2;          // m: depths outside [min_depth, max_depth] are not used
  double max_depth = 10.0;         // m
};

// The target seen in a box, in the observer's frames.
struct TargetVector {
  bool valid = false;              // false: no valid depth inside the box (the rest is unset)
  double surface_z = 0;            // m: mean of the smallest X % of the box's depths (optical z)
  double range = 0;                // m: observer centre → target centre, = |vector_g|
  Eigen::Vector3d ray_c = Eigen::Vector3d::Zero();     // unit ray through the box centre (optical)
  Eigen::Vector3d point_c = Eigen::Vector3d::Zero();   // target centre, optical frame (m)
  Eigen::Vector3d vector_b = Eigen::Vector3d::Zero();  // observer centre → target centre, body frame (m)
  Eigen::Vector3d vector_g = Eigen::Vector3d::Zero();  // the same, gravity-aligned body frame (m)
};

// Mean of the smallest X % of the valid depths inside the box (m, optical z), or NaN when the box
// (clipped to the image) holds no valid depth.
double near_surface_depth(const FrameView& frame, const BoxDetection& box, const RangeOptions& options);

// The box's target: near_surface_depth → range along the box-centre ray from the optical centre
// (z / ray_z + target_radius) → point in the optical frame → body frame (extrinsics) → gravity-
// aligned body frame by gravity_from_body(roll, pitch) (rad, the observer's IMU attitude).
TargetVector target_vector(const FrameView& frame, const BoxDetection& box, const CameraExtrinsics& extrinsics,
                           double roll, double pitch, const RangeOptions& options);

}  // namespace fact
