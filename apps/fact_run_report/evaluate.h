// Evaluation of a simulated run against its ground truth (fact-run-report; evaluation only, so it
// lives beside the app, not in lib/). Plain data, no LCM.
//
// The simulator's VIO drifts, so drone i's odometry frame f_i is not fixed in the world: at time
// t it is the *effective* frame that maps the VIO pose onto the true pose,
//   yaw_i(t)    = wrap(true_yaw_i(t) − vio_yaw_i(t))                       (rad)
//   origin_i(t) = true_position_i(t) − R_z(yaw_i(t)) · vio_position_i(t)    (m, world)
// An estimate made from observations over a window of time describes these frames over that
// window, so the reference truth is their average over the window (yaw averaged on the circle);
// the truth at the result's time alone is reported too.
#pragma once

#include <Eigen/Core>

#include <map>
#include <string>
#include <vector>

namespace fact::report {

double wrap(double a);  // to (−π, π]

// One drone's frame in the world (or in the reference frame): yaw (rad) and origin (m).
struct Frame {
  double yaw = 0;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
};

// The effective frame from one true pose and the VIO pose at the same time.
Frame effective_frame(const Eigen::Vector3d& true_position, double true_yaw, const Eigen::Vector3d& vio_position,
                      double vio_yaw);

// Running average of frames: origins averaged, yaws averaged as unit vectors.
class FrameAverage {
 public:
  void add(const Frame& f);
  bool empty() const { return n_ == 0; }
  Frame mean() const;

 private:
  int n_ = 0;
  Eigen::Vector3d origin_sum_ = Eigen::Vector3d::Zero();
  double c_ = 0, s_ = 0;
};

// Frame j expressed in frame r (both in the world): yaw_j − yaw_r and R_z(−yaw_r)(origin_j − origin_r).
Frame relative(const Frame& r, const Frame& j);

// One drone's estimate against the truth, in the reference frame.
struct DroneError {
  int id = 0;
  Frame estimate, truth;
  double yaw_error = 0;       // |wrap(est − true)| (rad)
  double position_error = 0;  // ‖est − true‖ (m, 3-D)
};

DroneError compare(int id, const Frame& estimate, const Frame& truth);

// Summary over the non-reference drones (the reference's error is 0 by construction).
struct ErrorSummary {
  int drones = 0;
  double yaw_mae = 0, yaw_max = 0;                  // rad
  double position_median = 0, position_max = 0;    // m
};
ErrorSummary summarize(const std::vector<DroneError>& errors, int reference);

// An observation of round `round` by drone `observer`, as a point in the world, and the true
// drone nearest to it (−1 when none is within the gate).
struct Sighting {
  int observer = 0, round = 0, target = -1;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // world (m)
  double distance = 0;                               // to the nearest true drone (m)
};

// Which drone an observed world point is: the nearest of `positions` (id → world centre) other
// than the observer, within gate metres; −1 if none.
int nearest_drone(const Eigen::Vector3d& point, int observer, const std::map<int, Eigen::Vector3d>& positions,
                  double gate, double* distance);

// Mutual-observation edges (i < j): i saw j and j saw i in one round.
std::vector<std::pair<int, int>> mutual_edges(const std::vector<Sighting>& sightings);

}  // namespace fact::report
