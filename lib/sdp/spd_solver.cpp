// SpdSolver (see spd_solver.h).
#include "spd_solver.h"

#include <algorithm>
#include <limits>

#include "internal.h"
#include "step_length.h"

namespace fact::sdp::detail {

SpdSolver::SpdSolver(Eigen::Index n) : L_(n, n) {}

namespace {

// A = L D Lᵀ into L (n × n: L's strictly lower triangle; D's reciprocals into inverse_diagonal,
// n), right-looking: column k's multiples of the pivot's row come off the trailing columns, then
// it is divided by the pivot. False when a pivot is not positive (A not positive definite) or not
// finite (an infinite one would leave D⁻¹ = 0 and a finite x; the loops path takes it as it did
// before, session 48's review).
bool ldl_lower(const Eigen::MatrixXd& A, Eigen::MatrixXd& L, Eigen::VectorXd& inverse_diagonal) {
  const Eigen::Index n = A.rows();
  L.resize(n, n);
  inverse_diagonal.resize(n);
  for (Eigen::Index j = 0; j < n; ++j)  // the lower triangle of A, column by column
    std::copy(&A(j, j), &A(0, j) + n, &L(j, j));
  for (Eigen::Index k = 0; k < n; ++k) {
    const double pivot = L(k, k);
    if (!(pivot > 0 && pivot <= std::numeric_limits<double>::max())) return false;
    const double reciprocal = 1.0 / pivot;
    inverse_diagonal[k] = reciprocal;
    double* __restrict lk = &L(0, k);
    for (Eigen::Index j = k + 1; j < n; ++j) {
      double* __restrict lj = &L(0, j);
      const double factor = lk[j] * reciprocal;
      for (Eigen::Index i = j; i < n; ++i) lj[i] -= lk[i] * factor;
    }
    for (Eigen::Index i = k + 1; i < n; ++i) lk[i] *= reciprocal;
  }
  return true;
}

}  // namespace

bool SpdSolver::factor(const Eigen::MatrixXd& A) {
  const Eigen::Index n = A.rows();
  path_ = n <= kLdlMaxSize ? Path::ldl : n <= kSmallSpdSize ? Path::loops : Path::blocked;
  if (path_ == Path::ldl) {
    factored_ = ldl_lower(A, L_, inverse_diagonal_);
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
  if (&x != &b) x = b;
  if (path_ == Path::blocked) {
    L_.triangularView<Eigen::Lower>().solveInPlace(x);
    L_.triangularView<Eigen::Lower>().transpose().solveInPlace(x);
    return;
  }
  const Eigen::Index n = L_.rows();
  if (path_ == Path::ldl) {
    for (Eigen::Index k = 0; k < n; ++k) {  // L y = b, by columns of L (unit diagonal)
      const double* l = &L_(0, k);
      const double xk = x[k];
      for (Eigen::Index i = k + 1; i < n; ++i) x[i] -= xk * l[i];
    }
    x.array() *= inverse_diagonal_.array();  // D z = y
    for (Eigen::Index k = n - 1; k >= 0; --k) {  // Lᵀ x = z, by columns of Lᵀ as below
      const double xk = x[k];
      for (Eigen::Index i = 0; i < k; ++i) x[i] -= xk * L_(k, i);
    }
    return;
  }
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
