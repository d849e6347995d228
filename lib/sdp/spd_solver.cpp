// SpdSolver (see spd_solver.h).
#include "spd_solver.h"

#include <limits>

#include "internal.h"
#include "step_length.h"

namespace fact::sdp::detail {

SpdSolver::SpdSolver(Eigen::Index n) : L_(n, n) {}

bool SpdSolver::factor(const Eigen::MatrixXd& A) {
  small_ = A.rows() <= kSmallSpdSize;
  if (!small_) {
    L_ = A;
    factored_ = cholesky_in_place(L_);
  } else {
    L_.resize(A.rows(), A.cols());
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
  if (!small_) {
    if (&x != &b) x = b;
    L_.triangularView<Eigen::Lower>().solveInPlace(x);
    L_.triangularView<Eigen::Lower>().transpose().solveInPlace(x);
    return;
  }
  const Eigen::Index n = L_.rows();
  if (&x != &b) x = b;
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
