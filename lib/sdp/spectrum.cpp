// Eigenvalues without eigenvectors, for the certificates (S = C − Λ, real n × n, or
// S = H − diag μ, complex N × N) and the exact step lengths (step_length.cpp): Householder
// reduction to a real symmetric tridiagonal matrix, then the root-free QL iteration of Pal, Walker
// and Kahan (EISPACK's tqlrat) on the squares of its off-diagonal. Eigen's SelfAdjointEigenSolver
// spent 1–3 µs of an 8-drone solve's 14 µs in its tridiagonal QR, whose Givens rotations take a
// square root each (BENCHMARKS.md, session 17).
#include <cmath>
#include <complex>
#include <limits>

#include "internal.h"

namespace fact::sdp::detail {
namespace {

double conj_of(double x) { return x; }
std::complex<double> conj_of(const std::complex<double>& x) { return std::conj(x); }

// Householder reduction of the self-adjoint A (n × n, lower triangle used; destroyed) to the real
// symmetric tridiagonal matrix with the same eigenvalues: diagonal (n) and subdiagonal (n − 1;
// only its entries' magnitudes are defined). scratch is 2n. Step k reflects the column below the
// diagonal, x (m = n − k − 1 entries), onto −phase(x₀)‖x‖e₁ with H = I − τ v vᴴ,
// v = x + phase(x₀)‖x‖e₁, and updates the trailing m × m block A₂₂ ← H A₂₂ H = A₂₂ − v wᴴ − w vᴴ
// with w = τ A₂₂ v − (τ² vᴴA₂₂v / 2) v.
template <class Matrix, class Vector>
void tridiagonalize_impl(Matrix& A, Eigen::VectorXd& diagonal, Eigen::VectorXd& subdiagonal, Vector& scratch) {
  using Scalar = typename Matrix::Scalar;
  const Eigen::Index n = A.rows(), lda = A.outerStride();
  Scalar* v = scratch.data();      // Householder vector, m
  Scalar* w = scratch.data() + n;  // w above, m
  for (Eigen::Index k = 0; k + 2 < n; ++k) {
    const Eigen::Index m = n - k - 1;  // size of the trailing block
    const Scalar* x = &A(k + 1, k);    // the column below the diagonal
    double tail = 0;
    for (Eigen::Index i = 1; i < m; ++i) tail += std::norm(x[i]);
    diagonal[k] = std::real(A(k, k));
    if (tail == 0) {  // already tridiagonal in this column
      subdiagonal[k] = std::abs(x[0]);
      continue;
    }
    const double norm = std::sqrt(std::norm(x[0]) + tail), size0 = std::abs(x[0]);
    const Scalar phase = size0 > 0 ? x[0] / size0 : Scalar(-1);
    subdiagonal[k] = norm;
    std::copy(x, x + m, v);
    v[0] += phase * norm;
    const double tau = 2.0 / (std::norm(v[0]) + tail);
    Scalar* a22 = &A(k + 1, k + 1);
    for (Eigen::Index i = 0; i < m; ++i) w[i] = 0;
    for (Eigen::Index j = 0; j < m; ++j) {  // w = τ A₂₂ v, one pass over the lower triangle
      const Scalar* __restrict col = a22 + j * lda;
      const Scalar vj = tau * v[j];
      Scalar dot = 0;
      w[j] += std::real(col[j]) * vj;
      for (Eigen::Index i = j + 1; i < m; ++i) {
        w[i] += col[i] * vj;
        dot += conj_of(col[i]) * v[i];
      }
      w[j] += tau * dot;
    }
    double vw = 0;  // Re vᴴ w (real: A₂₂ is self-adjoint)
    for (Eigen::Index i = 0; i < m; ++i) vw += std::real(conj_of(v[i]) * w[i]);
    const double half = 0.5 * tau * vw;
    for (Eigen::Index i = 0; i < m; ++i) w[i] -= half * v[i];
    for (Eigen::Index j = 0; j < m; ++j) {  // A₂₂ −= v wᴴ + w vᴴ on the lower triangle
      Scalar* __restrict col = a22 + j * lda;
      const Scalar vj = conj_of(v[j]), wj = conj_of(w[j]);
      for (Eigen::Index i = j; i < m; ++i) col[i] -= v[i] * wj + w[i] * vj;
    }
  }
  if (n >= 2) {
    diagonal[n - 2] = std::real(A(n - 2, n - 2));
    subdiagonal[n - 2] = std::abs(A(n - 1, n - 2));
  }
  diagonal[n - 1] = std::real(A(n - 1, n - 1));
}

template <class Matrix>
Eigen::VectorXd eigenvalues_impl(const Matrix& original) {
  const Eigen::Index n = original.rows();
  Matrix A = original;  // n × n, destroyed by the reduction
  Eigen::VectorXd diagonal(n), subdiagonal(std::max<Eigen::Index>(n, 1));  // one spare entry for tqlrat
  Eigen::Matrix<typename Matrix::Scalar, Eigen::Dynamic, 1> scratch(2 * n);
  tridiagonalize_impl(A, diagonal, subdiagonal, scratch);
  Eigen::VectorXd squares = subdiagonal.cwiseAbs2();  // n (the last entry is tqlrat's zero)
  if (tridiagonal_eigenvalues(diagonal, squares)) return diagonal;
  // 30 QL sweeps without convergence on one eigenvalue (not seen in tests): Eigen's QR.
  return Eigen::SelfAdjointEigenSolver<Matrix>(original, Eigen::EigenvaluesOnly).eigenvalues();
}

}  // namespace

void tridiagonalize(Eigen::MatrixXd& A, Eigen::VectorXd& diagonal, Eigen::VectorXd& subdiagonal, Eigen::VectorXd& scratch) {
  tridiagonalize_impl(A, diagonal, subdiagonal, scratch);
}

bool tridiagonal_eigenvalues(Eigen::VectorXd& d, Eigen::VectorXd& e2) {
  const Eigen::Index n = d.size();
  if (n <= 1) return true;
  e2[n - 1] = 0;  // stops the search for a negligible off-diagonal entry
  double shifted = 0, norm = 0, b = 0, c = 0;  // total shift; running bound on ‖T‖, ε·it and its square
  for (Eigen::Index l = 0; l < n; ++l) {
    double h = std::abs(d[l]) + std::sqrt(e2[l]);
    if (norm <= h) {
      norm = h;
      b = std::numeric_limits<double>::epsilon() * norm;
      c = b * b;
    }
    Eigen::Index m = l;  // the first negligible squared off-diagonal entry from l on
    while (e2[m] > c) ++m;
    for (int sweep = 0; m != l; ++sweep) {  // until e2[l] is negligible (a break)
      if (sweep == 30) return false;
      // Shift by the eigenvalue of the leading 2 × 2 block nearer to d[l].
      double s = std::sqrt(e2[l]), g = d[l];
      double p = (d[l + 1] - g) / (2.0 * s);
      double r = std::hypot(p, 1.0);
      d[l] = s / (p + std::copysign(r, p));
      h = g - d[l];
      for (Eigen::Index i = l + 1; i < n; ++i) d[i] -= h;
      shifted += h;
      // Rational QL transformation from m − 1 up to l.
      g = d[m] != 0 ? d[m] : b;
      h = g;
      s = 0;
      for (Eigen::Index i = m - 1; i >= l; --i) {
        p = g * h;
        r = p + e2[i];
        e2[i + 1] = s * r;
        s = e2[i] / r;
        d[i + 1] = h + s * (h + d[i]);
        g = d[i] - e2[i] / g;
        if (g == 0) g = b;
        h = g * p / r;
      }
      e2[l] = s * g;
      d[l] = h;
      if (h == 0 || std::abs(e2[l]) <= std::abs(c / h)) break;  // converged (guarded against underflow)
      e2[l] = h * e2[l];
      if (e2[l] == 0) break;
    }
    const double eigenvalue = d[l] + shifted;  // inserted in order among the l found so far
    Eigen::Index i = l;
    for (; i > 0 && eigenvalue < d[i - 1]; --i) d[i] = d[i - 1];
    d[i] = eigenvalue;
  }
  return true;
}

Eigen::VectorXd eigenvalues_of(const Eigen::MatrixXd& A) { return eigenvalues_impl(A); }
Eigen::VectorXd eigenvalues_of(const Eigen::MatrixXcd& A) { return eigenvalues_impl(A); }

}  // namespace fact::sdp::detail
