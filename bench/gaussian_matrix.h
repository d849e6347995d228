// Random matrices of standard Gaussian entries, for the kernel benchmark (sdp_kernels_bench.cpp)
// and the SDP tests (test/sdp_test_costs.h).
#pragma once

#include <Eigen/Core>
#include <complex>
#include <random>
#include <type_traits>

namespace fact::bench {

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

}  // namespace fact::bench
