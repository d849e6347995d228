// The certificates' eigenvalues (lib/sdp/spectrum.cpp: Householder tridiagonalisation and the
// root-free QL iteration) against Eigen's SelfAdjointEigenSolver, on matrices shaped like the
// solver's S: random, positive semidefinite with a large null space (a non-unique optimum's S),
// clustered, and tridiagonal matrices that split into blocks; and the lowest eigenvectors
// (inverse iteration on the tridiagonal matrix) by their residuals and orthonormality.
#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "internal.h"
#include "sdp_test_costs.h"

namespace {

using fact::sdp::detail::eigenvalues_of;
using fact::sdp::detail::lowest_eigenpairs;

// Largest eigenvalue difference relative to the spectral radius.
double relative_difference(const Eigen::VectorXd& ours, const Eigen::VectorXd& reference) {
  const double scale = std::max(reference.cwiseAbs().maxCoeff(), 1e-300);
  return (ours - reference).cwiseAbs().maxCoeff() / scale;
}

using fact::test::gaussian_matrix;

// The real test matrices of size n: kind 0 B + Bᵀ (indefinite), kind 1 B Bᵀ with B n × n/3 (positive
// semidefinite with a null space), kind 2 B Bᵀ + cluster·I (eigenvalues clustered around cluster).
Eigen::MatrixXd real_test_matrix(int n, int kind, double cluster, std::mt19937& rng, std::normal_distribution<double>& gauss) {
  const Eigen::MatrixXd B = gaussian_matrix<Eigen::MatrixXd>(n, kind == 1 ? std::max(1, n / 3) : n, rng, gauss);
  Eigen::MatrixXd A = kind == 0 ? Eigen::MatrixXd(B + B.transpose()) : Eigen::MatrixXd(B * B.transpose());
  if (kind == 2) A += cluster * Eigen::MatrixXd::Identity(n, n);
  return A;
}

// B Bᴴ − I/2 with B complex n × n/4: an S with a null space, so a repeated lowest eigenvalue −1/2.
Eigen::MatrixXcd hermitian_test_matrix(int n, std::mt19937& rng, std::normal_distribution<double>& gauss) {
  const Eigen::MatrixXcd B = gaussian_matrix<Eigen::MatrixXcd>(n, std::max(1, n / 4), rng, gauss);
  return B * B.adjoint() - 0.5 * Eigen::MatrixXcd::Identity(n, n);
}

// Every size of the padded reduction (n ≤ 64, padded to 8, 12, … 64) and the in-place one above.
TEST(SdpSpectrum, RealEigenvaluesMatchEigen) {
  std::mt19937 rng(3);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int n = 1; n <= 70; ++n) {
    for (int kind = 0; kind < 3; ++kind) {
      SCOPED_TRACE("n = " + std::to_string(n) + ", kind " + std::to_string(kind));
      const Eigen::MatrixXd A = real_test_matrix(n, kind, 1e3, rng, gauss);
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
    const Eigen::MatrixXcd A = hermitian_test_matrix(n, rng, gauss);
    const Eigen::VectorXd reference = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>(A, Eigen::EigenvaluesOnly).eigenvalues();
    const Eigen::VectorXd ours = eigenvalues_of(A);
    ASSERT_EQ(ours.size(), n);
    EXPECT_LT(relative_difference(ours, reference), 1e-13);
  }
}

// The reduction reads A's lower triangle only (the upper one holds anything), on the padded path
// (n ≤ 64) and in place (n > 64), and a matrix that is already diagonal or tridiagonal (no
// reflection at some steps) keeps its eigenvalues.
TEST(SdpSpectrum, ReductionReadsTheLowerTriangleAndKeepsReducedColumns) {
  std::mt19937 rng(17);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int n : {3, 7, 8, 9, 16, 33, 48, 64, 65, 80}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    const Eigen::MatrixXd A = real_test_matrix(n, 0, 0.0, rng, gauss);
    Eigen::MatrixXd marred = A;  // A's lower triangle, garbage above
    marred.triangularView<Eigen::StrictlyUpper>() = 1e3 * Eigen::MatrixXd::Ones(n, n);
    Eigen::VectorXd diagonal(n), subdiagonal(n), scratch(2 * n);
    fact::sdp::detail::tridiagonalize(marred, diagonal, subdiagonal, scratch);
    Eigen::VectorXd squares = subdiagonal.cwiseAbs2();
    ASSERT_TRUE(fact::sdp::detail::tridiagonal_eigenvalues(diagonal, squares));
    const Eigen::VectorXd reference = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A, Eigen::EigenvaluesOnly).eigenvalues();
    EXPECT_LT(relative_difference(diagonal, reference), 1e-13);
    Eigen::MatrixXd T = Eigen::MatrixXd::Zero(n, n);  // tridiagonal with zeros on its off-diagonal
    for (int i = 0; i < n; ++i) T(i, i) = gauss(rng);
    for (int i = 0; i + 1 < n; i += 3) T(i + 1, i) = T(i, i + 1) = gauss(rng);
    const Eigen::VectorXd expected = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(T, Eigen::EigenvaluesOnly).eigenvalues();
    EXPECT_LT(relative_difference(eigenvalues_of(T), expected), 1e-14);
    // Dense 3 × 3 diagonal blocks: columns that need a reflection next to ones that do not.
    Eigen::MatrixXd blocks = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < n; i += 3) {
      const int size = std::min(3, n - i);
      const Eigen::MatrixXd G = real_test_matrix(size, 0, 0.0, rng, gauss);
      blocks.block(i, i, size, size) = G;
    }
    const Eigen::VectorXd block_values =
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(blocks, Eigen::EigenvaluesOnly).eigenvalues();
    EXPECT_LT(relative_difference(eigenvalues_of(blocks), block_values), 1e-13);
    // One column below the diagonal of entries near 1e-160 in an O(1) matrix: its reflector is
    // formed on the unit scale (τ overflowed to ∞ from the unscaled one).
    Eigen::MatrixXd tiny = real_test_matrix(n, 2, 1.0, rng, gauss);
    tiny.col(0).tail(n - 1).setConstant(1e-160);
    tiny.row(0).tail(n - 1).setConstant(1e-160);
    const Eigen::VectorXd tiny_values = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(tiny, Eigen::EigenvaluesOnly).eigenvalues();
    const Eigen::VectorXd ours = eigenvalues_of(tiny);
    ASSERT_TRUE(ours.allFinite());
    EXPECT_LT(relative_difference(ours, tiny_values), 1e-13);
  }
}

// The symmetric tridiagonal matrix with diagonal a (k) and subdiagonal b (k − 1), dense k × k.
Eigen::MatrixXd dense_tridiagonal(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  Eigen::MatrixXd T = a.asDiagonal();
  for (Eigen::Index i = 0; i < b.size(); ++i) T(i + 1, i) = T(i, i + 1) = b[i];
  return T;
}

// The smallest eigenvalue of a Lanczos-sized tridiagonal matrix (Laguerre's iteration from below,
// its bracket bisected after 12 steps; T scaled into range first) against Eigen's: random, diagonal
// (whose Gershgorin end is λ_min itself), split, equal diagonals, tiny, huge, zero, and a λ_min
// repeated k/2 times.
TEST(SdpSpectrum, LowestTridiagonalEigenvalueMatchesEigen) {
  std::mt19937 rng(19);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int k = 1; k <= 24; ++k) {
    for (int kind = 0; kind < 9; ++kind) {
      SCOPED_TRACE("k = " + std::to_string(k) + ", kind " + std::to_string(kind));
      Eigen::VectorXd a(k), b(std::max(k - 1, 0));
      for (int i = 0; i < k; ++i) a[i] = gauss(rng);
      for (int i = 0; i + 1 < k; ++i) b[i] = gauss(rng);
      if (kind == 1) b.setZero();
      if (kind == 2) for (int i = 0; i + 1 < k; i += 2) b[i] = 0;
      if (kind == 3) a.setConstant(0.3);
      if (kind == 7) {  // λ_min = −1 repeated k/2 times (Laguerre alone converges only linearly there)
        b.setZero();
        for (int i = 0; i < k; ++i) a[i] = i % 2 ? 2.0 + i : -1.0;
      }
      if (kind == 8) {  // identical 2 × 2 blocks: λ_min repeated ⌊k/2⌋ times
        for (int i = 0; i < k; ++i) a[i] = i % 2 ? 2.0 : 1.0;
        for (int i = 0; i + 1 < k; ++i) b[i] = i % 2 ? 0.0 : 0.7;
      }
      const double scale = kind == 4 ? 1e-200 : kind == 5 ? 1e200 : kind == 6 ? 0.0 : 1.0;
      a *= scale;
      b *= scale;
      const Eigen::MatrixXd T = dense_tridiagonal(a, b);
      const double exact = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(T, Eigen::EigenvaluesOnly).eigenvalues()[0];
      const double lowest = fact::sdp::detail::lowest_tridiagonal_eigenvalue(a, b);
      EXPECT_LE(std::abs(lowest - exact), 1e-13 * T.cwiseAbs().maxCoeff()) << lowest << " against " << exact;
    }
  }
  // Entries near the largest double, whose Gershgorin sum overflows (scaled by the largest entry).
  Eigen::VectorXd a(3), b(2);
  a << 1e308, -1e308, 5e307;
  b << 1e308, 1e308;
  const Eigen::MatrixXd T = dense_tridiagonal(a, b);
  const double exact = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(T / 1e308, Eigen::EigenvaluesOnly).eigenvalues()[0];
  EXPECT_NEAR(fact::sdp::detail::lowest_tridiagonal_eigenvalue(a, b) / 1e308, exact, 1e-13);
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

// ‖A V − V diag(λ)‖ / ‖A‖ over the k columns of V, and ‖Vᴴ V − I‖; the reference eigenvalues and
// the residuals are taken on A / max|A_ij| (A at any scale; the zero matrix as it is).
template <class Matrix>
void expect_lowest_eigenpairs(const Matrix& A, int k) {
  Eigen::VectorXd eigenvalues;
  Matrix V;
  lowest_eigenpairs(A, k, eigenvalues, V);
  const double unit = A.cwiseAbs().maxCoeff() > 0 ? A.cwiseAbs().maxCoeff() : 1.0;
  const Matrix An = A / unit;  // entries of magnitude ≤ 1
  const Eigen::VectorXd values = eigenvalues / unit;
  const Eigen::VectorXd reference = Eigen::SelfAdjointEigenSolver<Matrix>(An, Eigen::EigenvaluesOnly).eigenvalues();
  ASSERT_EQ(eigenvalues.size(), A.rows());
  ASSERT_EQ(V.rows(), A.rows());
  ASSERT_EQ(V.cols(), k);
  EXPECT_LT(relative_difference(values, reference), 1e-13);
  const double scale = std::max(reference.cwiseAbs().maxCoeff(), 1e-300);
  for (int j = 0; j < k; ++j) {
    SCOPED_TRACE("vector " + std::to_string(j));
    EXPECT_LT((An * V.col(j) - values[j] * V.col(j)).norm() / scale, 1e-12);
  }
  EXPECT_LT((V.adjoint() * V - Matrix::Identity(k, k)).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(SdpSpectrum, LowestRealEigenvectorsHaveSmallResiduals) {
  std::mt19937 rng(7);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int n = 1; n <= 40; ++n) {
    for (int kind = 0; kind < 3; ++kind) {
      SCOPED_TRACE("n = " + std::to_string(n) + ", kind " + std::to_string(kind));
      expect_lowest_eigenpairs(real_test_matrix(n, kind, -1e3, rng, gauss), std::min(n, 3));
    }
  }
}

TEST(SdpSpectrum, LowestHermitianEigenvectorsHaveSmallResiduals) {
  std::mt19937 rng(9);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int n = 1; n <= 40; ++n) {
    SCOPED_TRACE("n = " + std::to_string(n));
    expect_lowest_eigenpairs(hermitian_test_matrix(n, rng, gauss), std::min(n, 2));
  }
}

TEST(SdpSpectrum, LowestEigenvectorsOfMatricesThatAreAlreadyReduced) {
  // Diagonal (every reflection skipped; the eigenvalue 1 is repeated) and a tridiagonal matrix
  // with a zero off-diagonal entry (the reduced matrix splits into two blocks).
  Eigen::MatrixXd D = Eigen::VectorXd::LinSpaced(6, 1.0, 6.0).asDiagonal();
  D(1, 1) = 1.0;
  expect_lowest_eigenpairs(D, 3);
  Eigen::MatrixXd T = Eigen::MatrixXd::Zero(6, 6);
  T.diagonal() << 4, 1, 3, 0.5, 2, 7;
  T(1, 0) = T(0, 1) = 0.7;
  T(3, 2) = T(2, 3) = -0.4;
  T(5, 4) = T(4, 5) = 1.1;  // T(2, 1) = T(4, 3) = 0: three 2 × 2 blocks
  expect_lowest_eigenpairs(T, 3);
  Eigen::MatrixXcd Z(2, 2);  // n = 2: no reflector at all, a complex off-diagonal entry
  Z << 1.0, std::complex<double>(0.3, -0.4), std::complex<double>(0.3, 0.4), -2.0;
  expect_lowest_eigenpairs(Z, 2);
}

// With `below`, vectors only of those of the k lowest eigenvalues below it, but at least one (the
// complex staircase's escape asks for the negative ones): a Hermitian matrix with eigenvalues −2,
// −1, 0.5, 1, 3 in a random basis, k = 2.
TEST(SdpSpectrum, LowestEigenvectorsOnlyBelowAThreshold) {
  std::mt19937 rng(31);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Eigen::MatrixXcd G = hermitian_test_matrix(5, rng, gauss);
  const Eigen::MatrixXcd Q = Eigen::HouseholderQR<Eigen::MatrixXcd>(G).householderQ();  // unitary, 5 × 5
  Eigen::VectorXd spectrum(5);
  spectrum << -2, -1, 0.5, 1, 3;
  const Eigen::MatrixXcd A = Q * spectrum.cast<std::complex<double>>().asDiagonal() * Q.adjoint();
  for (const auto& [below, columns] : {std::pair{std::numeric_limits<double>::infinity(), 2}, std::pair{0.0, 2},
                                       std::pair{-1.5, 1}, std::pair{-5.0, 1}}) {
    SCOPED_TRACE("below " + std::to_string(below));
    Eigen::VectorXd eigenvalues;
    Eigen::MatrixXcd V;
    lowest_eigenpairs(A, 2, eigenvalues, V, below);
    ASSERT_EQ(eigenvalues.size(), 5);
    EXPECT_LT((eigenvalues - spectrum).cwiseAbs().maxCoeff(), 1e-13);
    ASSERT_EQ(V.cols(), columns);
    for (int j = 0; j < columns; ++j) EXPECT_LT((A * V.col(j) - spectrum[j] * V.col(j)).norm(), 1e-12);
  }
}

// An eigenvalue split off from the rest by a coupling of 1e-120 (its row and column otherwise 0):
// the inverse iteration's pivot there is that small after a row swap, and the iterate used to grow
// until its norm overflowed and it normalised to a zero vector (review, session 28). Every vector,
// real (k = n) and complex (k = 2), with small residuals and orthonormal.
TEST(SdpSpectrum, LowestEigenvectorsOfANearlySplitMatrix) {
  std::mt19937 rng(23);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int n = 3; n <= 8; ++n) {
    SCOPED_TRACE("n = " + std::to_string(n));
    Eigen::MatrixXd A = real_test_matrix(n, 0, 0.0, rng, gauss);
    for (int i = 1; i < n; ++i) A(i, 0) = A(0, i) = 1e-120 * gauss(rng);
    expect_lowest_eigenpairs(A, n);
    Eigen::MatrixXcd H = hermitian_test_matrix(n, rng, gauss);
    for (int i = 1; i < n; ++i) {
      H(i, 0) = std::complex<double>(1e-120 * gauss(rng), 1e-120 * gauss(rng));
      H(0, i) = std::conj(H(i, 0));
    }
    H(0, 0) = -5.0;  // the split eigenvalue is the lowest
    expect_lowest_eigenpairs(H, 2);
  }
}

// lowest_vector (λ_min by Laguerre's iteration, no spectrum) against lowest_eigenpairs' first vector:
// the same eigenvector up to a unit factor, with a small residual, real and complex, n = 1 … 40.
TEST(SdpSpectrum, LowestVectorIsLowestEigenpairsFirst) {
  std::mt19937 rng(29);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int n = 1; n <= 40; n += (n < 10 ? 1 : 7)) {
    SCOPED_TRACE("n = " + std::to_string(n));
    const Eigen::MatrixXd A = real_test_matrix(n, 0, 0.0, rng, gauss);
    const Eigen::MatrixXcd G = gaussian_matrix<Eigen::MatrixXcd>(n, n, rng, gauss);
    const Eigen::MatrixXcd H = G + G.adjoint();  // a simple λ_min (hermitian_test_matrix repeats it)
    Eigen::VectorXd values;
    Eigen::MatrixXd vectors;
    lowest_eigenpairs(A, 1, values, vectors);
    const Eigen::MatrixXd v = fact::sdp::detail::lowest_vector(A);
    ASSERT_EQ(v.rows(), n);
    ASSERT_EQ(v.cols(), 1);
    const double scale = std::max(values.cwiseAbs().maxCoeff(), 1e-300);
    EXPECT_NEAR(std::abs(v.col(0).dot(vectors.col(0))), 1.0, 1e-10);
    EXPECT_LT((A * v - values[0] * v).norm() / scale, 1e-12);
    Eigen::MatrixXcd complex_vectors;
    lowest_eigenpairs(H, 1, values, complex_vectors);
    const Eigen::MatrixXcd w = fact::sdp::detail::lowest_vector(H);
    EXPECT_NEAR(std::abs(w.col(0).dot(complex_vectors.col(0))), 1.0, 1e-10);
    EXPECT_LT((H * w - values[0] * w).norm() / std::max(values.cwiseAbs().maxCoeff(), 1e-300), 1e-12);
  }
}

// Non-finite input gives NaN spectra and a NaN dual bound, never finite values that could pass for
// a certificate (the QL iteration made a NaN finite, and min(0, NaN) is 0).
TEST(SdpSpectrum, NonFiniteInputGivesNaNSpectraAndBounds) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int n : {2, 5, 70}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    Eigen::MatrixXd A = Eigen::MatrixXd::Identity(n, n);
    A(n - 1, 0) = A(0, n - 1) = nan;
    EXPECT_TRUE(eigenvalues_of(A).array().isNaN().all());
    Eigen::MatrixXcd H = Eigen::MatrixXcd::Identity(n, n);
    H(1, 0) = std::complex<double>(std::numeric_limits<double>::infinity(), 0.0);
    H(0, 1) = std::conj(H(1, 0));
    EXPECT_TRUE(eigenvalues_of(H).array().isNaN().all());
    Eigen::VectorXd values;
    Eigen::MatrixXd vectors;
    lowest_eigenpairs(A, 1, values, vectors);
    EXPECT_TRUE(values.array().isNaN().all());
    EXPECT_TRUE(vectors.array().isNaN().all());
  }
  fact::sdp::detail::Certificate cert;
  cert.lambda = Eigen::MatrixXd::Identity(4, 2);
  cert.trace_lambda = 2.0;
  cert.eigenvalues = Eigen::VectorXd::Constant(4, nan);
  fact::sdp::detail::bound_from_spectrum(cert);
  EXPECT_TRUE(std::isnan(cert.min_eig));
  EXPECT_TRUE(std::isnan(cert.dual_bound));
}

TEST(SdpSpectrum, LowestEigenvectorsAtAnyScale) {
  // The zero matrix (every vector an eigenvector: finite, orthonormal ones), and one random matrix
  // scaled by 1e-300 and 1e300 (the squared off-diagonal of the QL iteration and the inverse
  // iteration's pivots and growth stay in range).
  expect_lowest_eigenpairs(Eigen::MatrixXd(Eigen::MatrixXd::Zero(6, 6)), 2);
  expect_lowest_eigenpairs(Eigen::MatrixXcd(Eigen::MatrixXcd::Zero(5, 5)), 2);
  expect_lowest_eigenpairs(Eigen::MatrixXd(Eigen::MatrixXd::Zero(1, 1)), 1);
  std::mt19937 rng(11);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Eigen::MatrixXd A = real_test_matrix(8, 0, 0.0, rng, gauss);
  for (double scale : {1e-300, 1e300}) {
    SCOPED_TRACE("scale " + std::to_string(scale));
    expect_lowest_eigenpairs(Eigen::MatrixXd(scale * A), 2);
    const Eigen::VectorXd reference = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A, Eigen::EigenvaluesOnly).eigenvalues();
    EXPECT_LT(relative_difference(eigenvalues_of(Eigen::MatrixXd(scale * A)) / scale, reference), 1e-13);
  }
}

}  // namespace
