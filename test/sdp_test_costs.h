// Cost and random matrices shared by the SDP tests (test_sdp.cpp, test_sdp_interior_point.cpp,
// test_sdp_spectrum.cpp).
#pragma once

#include <Eigen/Core>
#include <complex>
#include <cstdint>
#include <random>
#include <type_traits>

#include "fact/rotation_cost.h"
#include "fact/simgen.h"

namespace fact::test {

// The paper's plain cost (2N × 2N) of a synthetic swarm of `drones` observed over drones + 2
// rounds with 0.05 noise: a noisy instance whose optimum is usually of high rank.
inline Eigen::MatrixXd noisy_plain_cost(int drones, std::uint64_t seed) {
  SyntheticOptions o;
  o.drones = drones;
  o.rounds = drones + 2;
  o.noise = 0.05;
  o.seed = seed;
  return paper_cost(make_synthetic_rounds(o).sums);
}

// A matrix of standard Gaussian entries (rows × cols), real or complex (each entry's real part,
// then its imaginary part), drawn column by column from rng through gauss.
template <class Matrix>
Matrix gaussian_matrix(Eigen::Index rows, Eigen::Index cols, std::mt19937& rng, std::normal_distribution<double>& gauss) {
  Matrix B(rows, cols);
  for (Eigen::Index j = 0; j < cols; ++j)
    for (Eigen::Index i = 0; i < rows; ++i) {
      if constexpr (std::is_same_v<typename Matrix::Scalar, double>) {
        B(i, j) = gauss(rng);
      } else {
        const double re = gauss(rng);
        B(i, j) = {re, gauss(rng)};
      }
    }
  return B;
}

}  // namespace fact::test
