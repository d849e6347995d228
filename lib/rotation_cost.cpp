#include "fact/rotation_cost.h"

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace fact {

Eigen::MatrixXd paper_cost(const std::vector<std::vector<Eigen::Vector2d>>& sums) {
  if (sums.empty()) throw std::invalid_argument("paper_cost: no rounds");
  const int n_drones = static_cast<int>(sums.front().size());
  if (n_drones < 2) throw std::invalid_argument("paper_cost: rounds[0] has " + std::to_string(n_drones) + " drones, need ≥ 2");
  Eigen::MatrixXd q = Eigen::MatrixXd::Zero(2 * n_drones, 2 * n_drones);
  Eigen::VectorXd s(2 * n_drones);  // stacked s_k, 2N
  for (std::size_t k = 0; k < sums.size(); ++k) {
    if (static_cast<int>(sums[k].size()) != n_drones)
      throw std::invalid_argument("paper_cost: rounds[" + std::to_string(k) + "] has " +
                                  std::to_string(sums[k].size()) + " drones, expected " +
                                  std::to_string(n_drones));
    for (int j = 0; j < n_drones; ++j) s.segment<2>(2 * j) = sums[k][j];
    q.selfadjointView<Eigen::Lower>().rankUpdate(s);
  }
  q.triangularView<Eigen::StrictlyUpper>() = q.transpose();
  return q;
}

SyntheticRounds make_synthetic_rounds(const SyntheticOptions& o) {
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  SyntheticRounds out;
  std::vector<Eigen::Vector3d> p(o.drones);  // world positions (m)
  for (int j = 0; j < o.drones; ++j) {
    p[j] = {o.room * unit(rng), o.room * unit(rng), 0.8 + 1.2 * unit(rng)};
    out.yaw.push_back(M_PI * (2.0 * unit(rng) - 1.0));
  }
  for (int k = 0; k < o.rounds; ++k) {
    std::vector<Eigen::Vector2d> round(o.drones, Eigen::Vector2d::Zero());
    for (int j = 0; j < o.drones; ++j) {
      const Eigen::Matrix2d r_j = Eigen::Rotation2Dd(out.yaw[j]).toRotationMatrix();
      for (int i = 0; i < o.drones; ++i) {
        if (i == j) continue;
        Eigen::Vector3d v = p[i] - p[j];  // world vector from j to i
        const double range = v.norm();
        for (int a = 0; a < 3; ++a) v[a] += o.noise * range * gauss(rng);
        round[j] += r_j.transpose() * v.head<2>();
      }
    }
    out.sums.push_back(round);
    for (int j = 0; j < o.drones; ++j) {  // move for the next round
      const double a = 2 * M_PI * unit(rng), r = o.move * unit(rng);
      p[j].head<2>() += r * Eigen::Vector2d(std::cos(a), std::sin(a));
    }
  }
  return out;
}

}  // namespace fact
