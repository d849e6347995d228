// The paper's rotation cost and a small synthetic generator of observation rounds.
//
// Each round k, drone j sums its anonymous detections, rotated from the body frame at
// detection time into its odometry frame f_j; s_jk ∈ R² is the horizontal part of that sum.
// For mutual observations Σ_j R_j s_jk = 0 (R_j: f_j → world yaw rotation), so
//     Σ_k ‖Σ_j R_j s_jk‖² = tr(Q Z),  Z = Rᵀ R,  R = [R_1 … R_N] (2 × 2N),
//     Q = Σ_k s_k s_kᵀ,  s_k = [s_1k; …; s_Nk] ∈ R^{2N}.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

namespace fact {

// sums[k][j] = s_jk (metres, in f_j). Every round must have the same number of drones N ≥ 2.
// Returns Q, 2N × 2N, symmetric PSD, rank ≤ number of rounds.
Eigen::MatrixXd paper_cost(const std::vector<std::vector<Eigen::Vector2d>>& sums);

// A synthetic swarm observed over several rounds, for benchmarks and tests of the rotation
// solver (the full scenario generator is fact-simgen). Everyone sees everyone in every round.
struct SyntheticRounds {
  std::vector<double> yaw;                          // true yaw of f_j in the world, N
  std::vector<std::vector<Eigen::Vector2d>> sums;   // sums[k][j] = s_jk in f_j, K × N
};

struct SyntheticOptions {
  int drones = 4;             // N
  int rounds = 5;             // K
  double room = 10.0;         // positions uniform in a room × room square (m)
  double move = 1.5;          // each drone moves up to this far between rounds (m)
  double noise = 0.0;         // per-axis σ = noise × range (the paper uses 0.05)
  std::uint64_t seed = 1;     // deterministic
};

SyntheticRounds make_synthetic_rounds(const SyntheticOptions& options);

}  // namespace fact
