// The certificates' eigenvalues (lib/sdp/spectrum.cpp: Householder tridiagonalisation and the
// root-free QL iteration) against Eigen's SelfAdjointEigenSolver, on matrices shaped like the
// solver's S: random, positive semidefinite with a large null space (a non-unique optimum's S),
// clustered, and tridiagonal matrices that split into blocks.
#include <gtest/gtest.h>

#include <random>

#include "internal.h"

namespace {

using fact::sdp::detail::eigenvalues_of;

// Largest eigenvalue difference relative to the spectral radius.
double relative_difference(const Eigen::VectorXd& ours, const Eigen::VectorXd& reference) {
  const double scale = std::max(reference.cwiseAbs().maxCoeff(), 1e-300);
  return (ours - reference).cwiseAbs().maxCoeff() / scale;
}

TEST(SdpSpectrum, RealEigenvaluesMatchEigen) {
  std::mt19937 rng(3);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int n = 1; n <= 40; ++n) {
    for (int kind = 0; kind < 3; ++kind) {
      SCOPED_TRACE("n = " + std::to_string(n) + ", kind " + std::to_string(kind));
      Eigen::MatrixXd B(n, kind == 1 ? std::max(1, n / 3) : n);  // kind 1: rank n/3, PSD
      for (Eigen::Index j = 0; j < B.cols(); ++j)
        for (Eigen::Index i = 0; i < n; ++i) B(i, j) = gauss(rng);
      Eigen::MatrixXd A = kind == 0 ? Eigen::MatrixXd(B + B.transpose()) : Eigen::MatrixXd(B * B.transpose());
      if (kind == 2) A += 1e3 * Eigen::MatrixXd::Identity(n, n);  // clustered around 1000
      const Eigen::VectorXd reference = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A, Eigen::EigenvaluesOnly).eigenvalues();
      const Eigen::VectorXd ours = eigenvalues_of(A);
      ASSERT_EQ(ours.size(), n);
      EXPECT_LT(relative_difference(ours, reference), 1e-13);
      if (kind == 1 && n >= 3) {  // a null space: the smallest eigenvalue is zero to rounding
        EXPECT_LT(std::abs(ours[0]), 1e-12 * reference.cwiseAbs().maxCoeff());
      }
    }
  }
}

TEST(SdpSpectrum, HermitianEigenvaluesMatchEigen) {
  std::mt19937 rng(5);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int n = 1; n <= 40; ++n) {
    SCOPED_TRACE("n = " + std::to_string(n));
    Eigen::MatrixXcd B(n, std::max(1, n / 4));  // rank n/4: an S with a null space
    for (Eigen::Index j = 0; j < B.cols(); ++j)
      for (Eigen::Index i = 0; i < n; ++i) B(i, j) = {gauss(rng), gauss(rng)};
    const Eigen::MatrixXcd A = B * B.adjoint() - 0.5 * Eigen::MatrixXcd::Identity(n, n);
    const Eigen::VectorXd reference = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>(A, Eigen::EigenvaluesOnly).eigenvalues();
    const Eigen::VectorXd ours = eigenvalues_of(A);
    ASSERT_EQ(ours.size(), n);
    EXPECT_LT(relative_difference(ours, reference), 1e-13);
  }
}

TEST(SdpSpectrum, TridiagonalThatSplitsAndHasZeros) {
  // diag(2, 2, 0, 0, 5) with T(1,0) = 1 and the rest of the off-diagonal zero: eigenvalues
  // 1, 3 (the first 2 × 2 block), 0, 0 and 5.
  Eigen::VectorXd d(5), e2(5);
  d << 2, 2, 0, 0, 5;
  e2 << 1, 0, 0, 0, 0;
  ASSERT_TRUE(fact::sdp::detail::tridiagonal_eigenvalues(d, e2));
  Eigen::VectorXd expected(5);
  expected << 0, 0, 1, 3, 5;
  EXPECT_LT((d - expected).cwiseAbs().maxCoeff(), 1e-14);
}

}  // namespace
