// Deterministic SDP instances shared by fact-bench-sdp and fact-sdp-reference.
// Every function returns C, the n×n symmetric cost of
//     minimize ⟨C, X⟩  s.t.  X ⪰ 0, X_ii = I_d.
#pragma once

#include <Eigen/Dense>
#include <cstdint>

namespace fact::bench {

// The paper's cost Q (2N × 2N, d = 2) from make_synthetic_rounds with N drones, the given
// rounds and noise; with tight = true, its complex (U(1)) form complex_form(Q).
Eigen::MatrixXd synthetic_cost(int drones, int rounds, double noise, bool tight, std::uint64_t seed);
// The same with N + 1 rounds (fact-bench-sdp's instances).
Eigen::MatrixXd synthetic_cost(int drones, double noise, bool tight, std::uint64_t seed);

// Random PSD C = B Bᵀ, n × n, with B n × rank of i.i.d. standard normals (rank = n: full rank).
Eigen::MatrixXd random_psd(int n, int rank, std::uint64_t seed);

}  // namespace fact::bench
