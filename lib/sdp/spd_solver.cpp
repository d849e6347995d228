// SpdSolver (see spd_solver.h).
#include "spd_solver.h"

#include <algorithm>
#include <limits>

#include "internal.h"
#include "step_length.h"

namespace fact::sdp::detail {

SpdSolver::SpdSolver(Eigen::Index n) : L_(n, n) {}

namespace {

// A = L D Lᵀ (A n × n, n ≤ P, lower triangle read) into a (P × P, column-major, leading dimension
// P), right-looking two columns at a time: column k + 1 takes column k's multiple off, then both
// columns' multiples come off the trailing columns in one pass (n = 5 / 10 / 12: 36 / 124 / 170
// ns a factorisation one column at a time against 30 / 96 / 136; BENCHMARKS.md, session 49); then
// each is divided by its pivot and everything else in its padded column set to zero, and the
// columns from n on are set to zero (the buffer may hold a larger system's entries, or another
// P's layout; the factor itself reads only rows at or below each diagonal). D's reciprocals into
// inverse (P, zeros past n). So a holds L's strictly lower n × n triangle and zeros, and the
// substitutions' padding lanes stay at zero. False when a pivot is not usable (A not positive
// definite, or not finite).
template <int P>
bool ldl_padded(const Eigen::MatrixXd& A, double* a, double* inverse) {
  const int n = static_cast<int>(A.rows());
  for (int j = 0; j < n; ++j) std::copy(&A(j, j), &A(0, j) + n, a + j * P + j);
  int k = 0;
  for (; k + 1 < n; k += 2) {
    double* __restrict ak = a + k * P;
    double* __restrict next = a + (k + 1) * P;
    if (!usable_pivot(ak[k])) return false;
    const double reciprocal = 1.0 / ak[k];
    const double multiple = ak[k + 1] * reciprocal;  // L(k + 1, k)
    for (int i = k + 1; i < n; ++i) next[i] -= ak[i] * multiple;
    if (!usable_pivot(next[k + 1])) return false;
    const double next_reciprocal = 1.0 / next[k + 1];
    inverse[k] = reciprocal;
    inverse[k + 1] = next_reciprocal;
    for (int j = k + 2; j < n; ++j) {
      double* __restrict aj = a + j * P;
      const double factor = ak[j] * reciprocal, next_factor = next[j] * next_reciprocal;
      for (int i = j; i < n; ++i) aj[i] -= ak[i] * factor + next[i] * next_factor;
    }
    for (int i = 0; i < P; ++i) {  // the whole columns
      ak[i] = i > k && i < n ? ak[i] * reciprocal : 0.0;
      next[i] = i > k + 1 && i < n ? next[i] * next_reciprocal : 0.0;
    }
  }
  if (k < n) {  // the last column of an odd n: its pivot only
    double* __restrict ak = a + k * P;
    if (!usable_pivot(ak[k])) return false;
    inverse[k] = 1.0 / ak[k];
    std::fill(ak, ak + P, 0.0);
  }
  std::fill(a + n * P, a + P * P, 0.0);
  std::fill(inverse + n, inverse + P, 0.0);
  return true;
}

// x = A⁻¹ b (b: n ≤ P entries, the n factored) from ldl_padded's a and inverse, on a zero-padded
// P-vector: L z = b by columns of L, then D⁻¹, then Lᵀ x = y by columns of Lᵀ (rows of L, read
// with stride P). The zeros on and above L's diagonal leave the finished entries unchanged, so
// every step is a whole P-vector update with no remainder loop: n = 5 / 8 / 12 took 32 / 57 / 91
// ns a solve by loops over the remaining rows against 13 / 22–33 / 55 ns (BENCHMARKS.md, session 49).
template <int P>
void solve_padded(const double* a, const double* inverse, int n, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  eigen_assert(b.size() == n && n <= P);
  alignas(64) double y[P];
  for (int i = 0; i < P; ++i) y[i] = i < n ? b[i] : 0.0;
  for (int k = 0; k + 1 < n; ++k) {
    const double yk = y[k];
    const double* l = a + k * P;
    for (int i = 0; i < P; ++i) y[i] -= yk * l[i];
  }
  for (int i = 0; i < P; ++i) y[i] *= inverse[i];
  for (int k = n - 1; k > 0; --k) {
    const double yk = y[k];
    for (int i = 0; i < P; ++i) y[i] -= yk * a[i * P + k];
  }
  x.resize(n);
  std::copy(y, y + n, x.data());
}

}  // namespace

bool SpdSolver::factor(const Eigen::MatrixXd& A) {
  const Eigen::Index n = A.rows();
  path_ = n <= kLdlMaxSize ? Path::ldl : n <= kSmallSpdSize ? Path::loops : Path::blocked;
  if (path_ == Path::ldl) {
    padded_size_ = n <= 4 ? 4 : n <= 8 ? 8 : 12;
    padded_rows_ = static_cast<int>(n);
    factored_ = padded_size_ == 4    ? ldl_padded<4>(A, padded_.data(), padded_inverse_.data())
                : padded_size_ == 8 ? ldl_padded<8>(A, padded_.data(), padded_inverse_.data())
                                    : ldl_padded<12>(A, padded_.data(), padded_inverse_.data());
  } else if (path_ == Path::blocked) {
    L_ = A;
    factored_ = cholesky_in_place(L_);
  } else {
    L_.resize(n, n);
    factored_ = cholesky_lower(A, L_);
    if (factored_) inverse_diagonal_ = L_.diagonal().cwiseInverse();  // the substitutions multiply
  }
  return factored_;
}

void SpdSolver::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
  if (!factored_) {
    x.setConstant(b.size(), std::numeric_limits<double>::quiet_NaN());
    return;
  }
  if (path_ == Path::ldl) {
    const double* a = padded_.data();
    if (padded_size_ == 4) return solve_padded<4>(a, padded_inverse_.data(), padded_rows_, b, x);
    if (padded_size_ == 8) return solve_padded<8>(a, padded_inverse_.data(), padded_rows_, b, x);
    return solve_padded<12>(a, padded_inverse_.data(), padded_rows_, b, x);
  }
  if (&x != &b) x = b;
  if (path_ == Path::blocked) {
    L_.triangularView<Eigen::Lower>().solveInPlace(x);
    L_.triangularView<Eigen::Lower>().transpose().solveInPlace(x);
    return;
  }
  const Eigen::Index n = L_.rows();
  for (Eigen::Index k = 0; k < n; ++k) {  // L y = b, by columns of L
    const double* l = &L_(0, k);
    const double xk = x[k] * inverse_diagonal_[k];
    x[k] = xk;
    for (Eigen::Index i = k + 1; i < n; ++i) x[i] -= xk * l[i];
  }
  // Lᵀ x = y by columns of Lᵀ (rows of L, read with a stride): each x_k, once final, is taken off
  // the entries above it. By rows of Lᵀ (dot products with L's columns) every x_k waited on a
  // horizontal sum: n = 5 / 12 / 32 took 47 / 160 / 620 ns a solve against 40 / 105 / 350
  // (BENCHMARKS.md, session 48).
  for (Eigen::Index k = n - 1; k >= 0; --k) {
    const double xk = x[k] * inverse_diagonal_[k];
    x[k] = xk;
    for (Eigen::Index i = 0; i < k; ++i) x[i] -= xk * L_(k, i);
  }
}

}  // namespace fact::sdp::detail
