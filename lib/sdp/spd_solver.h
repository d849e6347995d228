// Factor and solve of a symmetric positive definite system A x = b (A n × n, lower triangle
// read). Up to kSmallSpdSize rows plain loops (cholesky_lower and two substitutions); above it Eigen's
// blocked kernel in place (cholesky_in_place) and its triangular solves. Eigen::LLT also computes
// a condition estimate (the matrix's L1 norm) nothing reads: at the Newton systems' and Schur
// complements' usual sizes (6 … 48 unknowns) 2–5 % of tight_noisy N = 5 … 32 and plain_noisy N = 3
// (BENCHMARKS.md, session 23), and a quarter of the factorisation of the real interior point's
// Schur complement at N = 100 (300 × 300: 0.27 against 0.20 ms, session 27).
#pragma once

#include <Eigen/Dense>

namespace fact::sdp::detail {

constexpr Eigen::Index kSmallSpdSize = 64;

class SpdSolver {
 public:
  // Storage for an n × n system (resized if a later A needs it).
  explicit SpdSolver(Eigen::Index n = 0);
  // False when A is not positive definite.
  bool factor(const Eigen::MatrixXd& A);
  // x = A⁻¹ b for the last A factored; x may alias b. NaN when that factorisation failed.
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const;

 private:
  bool small_ = true;
  bool factored_ = false;
  Eigen::MatrixXd L_;                 // the factor, lower triangle, n × n
  Eigen::VectorXd inverse_diagonal_;  // 1 / L_ii on the small path, n
};

}  // namespace fact::sdp::detail
