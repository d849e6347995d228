// Peer SDP solvers (SDPA, CSDP) used only by the benchmarks and by the generator of the
// reference optima in test/data/sdp. Nothing in lib/ depends on this.
//
// Every function solves the same problem as fact::sdp::solve:
//
//     minimize ⟨C, X⟩   subject to   X ⪰ 0,   X_ii = I_d for every d×d diagonal block,
//
// C n×n real symmetric, n = d·N, d ∈ {1, 2}. As linear constraints (see block_constraints):
// for each block i and each a ≤ b in 0..d−1, X[d·i+a][d·i+b] = (a == b ? 1 : 0),
// m = N·d(d+1)/2 of them.
//
// The peers maximise, so they are given −C:
//   SDPA's dual  max ⟨F0, Y⟩ s.t. ⟨F_k, Y⟩ = c_k, Y ⪰ 0    with F0 = −C, F_k = A_k, c_k = b_k;
//   CSDP's primal max tr(C' X) s.t. tr(A_k X) = a_k, X ⪰ 0  with C' = −C.
// Every PeerResult::objective is converted back to OUR sign: ⟨C, X⟩ of the minimisation.
#pragma once

#include <Eigen/Dense>
#include <limits>
#include <string>
#include <vector>

namespace fact::bench {

struct PeerResult {
  bool available = false;  // the peer was compiled in (or its binary found)
  bool converged = false;  // the peer reports an optimal solution to its own tolerance
  double objective = std::numeric_limits<double>::quiet_NaN();  // ⟨C, X⟩ (minimisation sign)
  double ms = std::numeric_limits<double>::quiet_NaN();  // wall time, set-up and tear-down included
  std::string note;        // peer status or the reason it did not run
};

// One linear constraint ⟨A_k, X⟩ = rhs with A_k = ½(e_row e_colᵀ + e_col e_rowᵀ) (0-based
// row ≤ col), i.e. X[row][col] = rhs. Stored in the peers' upper-triangle convention as
// the single entry (row, col) with value `value` (1 on the diagonal, ½ off it).
struct BlockConstraint {
  int row = 0;
  int col = 0;
  double value = 1;
  double rhs = 1;
};

// The m = N·d(d+1)/2 constraints X_ii = I_d, ordered by block i, then a, then b ≥ a.
// Throws std::invalid_argument unless d ∈ {1, 2} and n is a positive multiple of d.
std::vector<BlockConstraint> block_constraints(int n, int d);

// Whether each peer was found when the benchmarks were configured.
bool sdpa_compiled_in();
bool csdp_compiled_in();
std::string csdp_binary_path();  // empty when the csdp executable was not found

// In-process solves. C must be square, symmetric and n a multiple of d (else
// std::invalid_argument). Console output of the peer is suppressed. Both use their
// default tolerances (relative gap ~1e-7 for SDPA, ~1e-8 for CSDP); SDPA's objective bounds
// are switched off and its starting point is scaled to ‖C‖_F (see peers.cpp). CSDP reads
// a param.csdp in the current directory if there is one.
// converged: SDPA phase pdOPT; CSDP return code 0 (3, "partial success", is not counted).
PeerResult solve_sdpa(const Eigen::MatrixXd& C, int d);
PeerResult solve_csdp(const Eigen::MatrixXd& C, int d);

// Writes the problem in SDPA-sparse format (.dat-s), one SDP block of size n:
//   "comment"      (names N and d)
//   m              = number of constraints
//   1              = number of blocks
//   n              = block size
//   b_1 … b_m      right-hand sides
//   0 1 i j v      entries of the objective matrix, 1-based, i ≤ j, v = −C(i,j) (nonzeros)
//   k 1 i j v      the single entry of constraint k (see block_constraints)
// The objective matrix is −C because the csdp binary (and SDPA's dual) MAXIMISE tr(F0 X):
// the file's optimum is −(our optimum). Values are written with 17 significant digits.
// Throws std::runtime_error when the file cannot be written.
void write_sdpa_sparse(const std::string& path, const Eigen::MatrixXd& C, int d);

// Process-level cross-check: writes the problem to a file in `workdir`, runs the csdp
// executable on it (cwd = workdir, so a param.csdp there applies), parses its
// "Primal objective value" line (8 significant digits) and deletes the file.
// ms is the wall time of the whole thing, process start-up included.
PeerResult solve_csdp_binary(const Eigen::MatrixXd& C, int d, const std::string& workdir);

// Same, on an existing .dat-s file written by write_sdpa_sparse (the file is kept).
PeerResult run_csdp_binary(const std::string& dat_path, const std::string& workdir);

}  // namespace fact::bench
