// Internal pieces of the SDP solver: each is one named step (SE-Sync style).
// All functions work on the scaled problem (‖C‖_F = 1).
#pragma once

#include "fact/sdp.h"

namespace fact::sdp::detail {

// A dual certificate for a candidate primal factor.
struct Certificate {
  Eigen::MatrixXd lambda;     // n × d, Λ_ii stacked: Λ_ii = sym((C Y)_i Y_iᵀ)
  Eigen::VectorXd eigenvalues;  // all eigenvalues of S = C − Λ, ascending, n
  Eigen::VectorXd min_vector;   // unit eigenvector of λ_min(S), n (only when asked for)
  double trace_lambda = 0;    // tr Λ: the dual objective
  double min_eig = 0;         // λ_min(S)
  double dual_bound = 0;      // tr Λ + n·min(0, λ_min(S)): a lower bound on the optimum
};

// Λ from a primal factor Y (n × r) whose d×d diagonal blocks of Y Yᵀ are I.
Eigen::MatrixXd lambda_from_factor(const Eigen::MatrixXd& C, const Eigen::MatrixXd& Y, int d);

// S = C − blkdiag(Λ), n × n: returned, or written into S (no allocation when S is already n × n).
Eigen::MatrixXd certificate_matrix(const Eigen::MatrixXd& C, const Eigen::MatrixXd& lambda, int d);
void certificate_matrix(const Eigen::MatrixXd& C, const Eigen::MatrixXd& lambda, int d, Eigen::MatrixXd& S);

// Eigen-analysis of S for a given Λ. With want_vector, also the eigenvector of λ_min.
Certificate certify(const Eigen::MatrixXd& C, const Eigen::MatrixXd& lambda, int d, bool want_vector);

// Burer–Monteiro block-coordinate minimisation at fixed rank: sweeps over blocks, each
// block set to −polar((C Y)_i − C_ii Y_i), until the largest block change < tol.
// Y is n × r with orthonormal-row blocks on entry and exit. Returns the sweeps done.
int block_coordinate_sweeps(const Eigen::MatrixXd& C, int d, Eigen::MatrixXd& Y, int max_sweeps, double tol);

// Damped Riemannian Newton at fixed rank until ‖grad‖ < grad_tol. Returns the steps taken.
int newton_refine(const Eigen::MatrixXd& C, int d, Eigen::MatrixXd& Y, int max_iterations, double grad_tol);

// Projects every d-row block of Y to orthonormal rows (polar_rows), in place. Returns false,
// leaving the rest untouched, at the first block with no direction (all zero).
bool project_blocks(Eigen::MatrixXd& Y, int d);

// The nearest matrix with orthonormal rows to G (d × r, d ≤ r): (G Gᵀ)^{-1/2} G.
Eigen::MatrixXd polar_rows(const Eigen::MatrixXd& G);

struct LowRankOutcome {
  Eigen::MatrixXd Y;        // n × r factor
  Certificate certificate;  // for Y
  int iterations = 0;       // total sweeps
  bool certified = false;   // λ_min(S) ≥ −psd_tol at the end
};

// Riemannian staircase: block-coordinate minimisation at rank r, certify, and if S has a
// negative eigenvalue, add a column along its eigenvector and continue, up to max_rank.
LowRankOutcome solve_low_rank(const Eigen::MatrixXd& C, int d, const Options& options);

struct InteriorPointOutcome {
  Eigen::MatrixXd X;        // n × n primal
  Eigen::MatrixXd lambda;   // n × d dual multipliers, Λ_ii stacked
  int iterations = 0;
  bool converged = false;   // relative gap below 0.1·gap_tol
  bool handed_off = false;  // stopped at the handoff gap, before convergence (X, lambda resume it)
  std::string reason;       // why it stopped when not converged
};

// Primal–dual path following with the HKM direction and a Mehrotra corrector. It stops once
// the relative gap is below handoff_gap (> 0: handed_off is set), so a caller can try a cheaper
// finish; `resume` (an outcome that handed off) continues from its X and Λ, which are strictly
// feasible, instead of X = I.
InteriorPointOutcome solve_interior_point(const Eigen::MatrixXd& C, int d, const Options& options,
                                          double handoff_gap = 0, const InteriorPointOutcome* resume = nullptr);

// The factor of largest rank r ≤ n with X = Y Yᵀ (eigenvalues below tol·max dropped).
Eigen::MatrixXd factor_psd(const Eigen::MatrixXd& X, double tol);

// Largest factor rank the staircase needs: the Pataki bound for N·d(d+1)/2 constraints.
int pataki_rank(int blocks, int d);

}  // namespace fact::sdp::detail
