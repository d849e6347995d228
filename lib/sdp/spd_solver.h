// Factor and solve of a symmetric positive definite system A x = b (A n × n, lower triangle read).
// Up to kLdlMaxSize rows A = L D Lᵀ (L unit lower triangular, D diagonal) by plain loops on a
// zero-padded copy, solved by two substitutions of whole padded columns and a division by D between
// them; up to kSmallSpdSize the Cholesky factor by
// plain loops (cholesky_lower) and two substitutions. Above it cholesky_in_place (the padded
// kernel up to 127 rows, Eigen's blocked one from 128) and Eigen's triangular solves. Eigen::LLT also computes a condition estimate (the
// matrix's L1 norm) nothing reads: at the Newton systems' and Schur complements' usual sizes (6 …
// 48 unknowns) 2–5 % of tight_noisy N = 5 … 32 and plain_noisy N = 3 (BENCHMARKS.md, session 23),
// and a quarter of the factorisation of the real interior point's Schur complement at N = 100 (300
// × 300: 0.27 against 0.20 ms, session 27).
#pragma once

#include <array>

#include <Eigen/Dense>

namespace fact::sdp::detail {

constexpr Eigen::Index kSmallSpdSize = 64;
// L D Lᵀ has no square root on the path from one column's pivot to the next (a Cholesky column
// waits on its pivot's root, then on the division by it): n = 5 / 8 / 12 took 57 / 117 / 199 ns a
// factorisation against 32 / 70 / 147 ns; from 16 rows the Cholesky loops measured as fast or
// faster (up to 2× at 32; BENCHMARKS.md, session 48).
constexpr Eigen::Index kLdlMaxSize = 12;

class SpdSolver {
 public:
  // Storage for an n × n system (resized if a later A needs it).
  explicit SpdSolver(Eigen::Index n = 0);
  // False when A is not positive definite.
  bool factor(const Eigen::MatrixXd& A);
  // x = A⁻¹ b for the last A factored; x may alias b. NaN when that factorisation failed.
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const;

 private:
  enum class Path { ldl, loops, blocked };
  Path path_ = Path::loops;
  bool factored_ = false;
  Eigen::MatrixXd L_;                 // the loops' and the blocked factor, lower triangle, n × n;
                                      // the upper triangle is stale
  Eigen::VectorXd inverse_diagonal_;  // 1 / L_ii (the loops), n
  // The L D Lᵀ path: L on a P × P column-major copy (P = 4, 8 or 12, the smallest that holds n;
  // leading dimension P), its strictly lower n × n triangle and zeros everywhere else, so that each
  // substitution step is one whole P-vector operation with no remainder; padded_inverse_ holds
  // 1 / D_ii, zeros past n.
  int padded_size_ = 0;
  int padded_rows_ = 0;  // n
  alignas(64) std::array<double, kLdlMaxSize * kLdlMaxSize> padded_{};
  alignas(64) std::array<double, kLdlMaxSize> padded_inverse_{};
};

}  // namespace fact::sdp::detail
