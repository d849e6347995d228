#include "evaluate.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <set>

namespace fact::report {

double wrap(double a) {
  a = std::remainder(a, 2 * M_PI);
  return a <= -M_PI ? a + 2 * M_PI : a;
}

namespace {
Eigen::Matrix3d rot_z(double yaw) { return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }
}  // namespace

Frame effective_frame(const Eigen::Vector3d& true_position, double true_yaw, const Eigen::Vector3d& vio_position,
                      double vio_yaw) {
  Frame f;
  f.yaw = wrap(true_yaw - vio_yaw);
  f.origin = true_position - rot_z(f.yaw) * vio_position;
  return f;
}

void FrameAverage::add(const Frame& f) {
  ++n_;
  origin_sum_ += f.origin;
  c_ += std::cos(f.yaw);
  s_ += std::sin(f.yaw);
}

Frame FrameAverage::mean() const {
  Frame f;
  if (n_ == 0) return f;
  f.origin = origin_sum_ / n_;
  f.yaw = std::atan2(s_, c_);
  return f;
}

Frame relative(const Frame& r, const Frame& j) {
  Frame f;
  f.yaw = wrap(j.yaw - r.yaw);
  f.origin = rot_z(-r.yaw) * (j.origin - r.origin);
  return f;
}

DroneError compare(int id, const Frame& estimate, const Frame& truth) {
  DroneError e;
  e.id = id;
  e.estimate = estimate;
  e.truth = truth;
  e.yaw_error = std::abs(wrap(estimate.yaw - truth.yaw));
  e.position_error = (estimate.origin - truth.origin).norm();
  return e;
}

ErrorSummary summarize(const std::vector<DroneError>& errors, int reference) {
  ErrorSummary s;
  std::vector<double> pos;
  double yaw_sum = 0;
  for (const DroneError& e : errors) {
    if (e.id == reference) continue;
    ++s.drones;
    yaw_sum += e.yaw_error;
    s.yaw_max = std::max(s.yaw_max, e.yaw_error);
    s.position_max = std::max(s.position_max, e.position_error);
    pos.push_back(e.position_error);
  }
  if (s.drones == 0) return s;
  s.yaw_mae = yaw_sum / s.drones;
  std::sort(pos.begin(), pos.end());
  const size_t m = pos.size() / 2;
  s.position_median = pos.size() % 2 ? pos[m] : 0.5 * (pos[m - 1] + pos[m]);
  return s;
}

int nearest_drone(const Eigen::Vector3d& point, int observer, const std::map<int, Eigen::Vector3d>& positions,
                  double gate, double* distance) {
  int best = -1;
  double best_d = gate;
  for (const auto& [id, p] : positions) {
    if (id == observer) continue;
    const double d = (p - point).norm();
    if (d <= best_d) {
      best = id;
      best_d = d;
    }
  }
  if (distance) *distance = best >= 0 ? best_d : NAN;
  return best;
}

std::vector<std::pair<int, int>> mutual_edges(const std::vector<Sighting>& sightings) {
  std::set<std::tuple<int, int, int>> seen;  // (round, observer, target)
  for (const Sighting& s : sightings)
    if (s.target >= 0) seen.insert({s.round, s.observer, s.target});
  std::set<std::pair<int, int>> edges;
  for (const auto& [round, i, j] : seen)
    if (seen.count({round, j, i})) edges.insert({std::min(i, j), std::max(i, j)});
  return {edges.begin(), edges.end()};
}

}  // namespace fact::report
