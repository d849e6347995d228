// Cost and random matrices shared by the SDP tests (test_sdp.cpp, test_sdp_interior_point.cpp,
// test_sdp_spectrum.cpp).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <random>

#include "fact/rotation_cost.h"
#include "fact/simgen.h"
#include "gaussian_matrix.h"

namespace fact::test {

// The paper's plain cost (2N × 2N) of a synthetic swarm of `drones` observed over `rounds` rounds
// with this noise.
inline Eigen::MatrixXd plain_cost(int drones, int rounds, double noise, std::uint64_t seed) {
  SyntheticOptions o;
  o.drones = drones;
  o.rounds = rounds;
  o.noise = noise;
  o.seed = seed;
  return paper_cost(make_synthetic_rounds(o).sums);
}

// Over drones + 2 rounds with 0.05 noise: a noisy instance whose optimum is usually of high rank.
inline Eigen::MatrixXd noisy_plain_cost(int drones, std::uint64_t seed) { return plain_cost(drones, drones + 2, 0.05, seed); }

// A matrix of standard Gaussian entries (bench/gaussian_matrix.h; the kernel benchmark draws its
// operands with it too).
using fact::bench::gaussian_matrix;

}  // namespace fact::test
