// The block-constrained SDP that every rotation estimate in fact reduces to:
//
//     minimize ⟨C, X⟩   subject to   X ⪰ 0,   X_ii = I_d for every d×d diagonal block.
//
// C is n×n real symmetric with n = d·N (N blocks, one per drone). d = 2 is the
// real SO(2)/O(2) relaxation the paper uses; d = 1 is the MaxCut-type problem.
// The complex U(1) form (Hermitian N×N, unit diagonal) is passed as its real embedding with
// d = 2 (see complex_form / real_embedding below); the solver recognises that structure and
// works on the N×N Hermitian matrix (Method::complex_low_rank).
//
// The solver is written here (no MOSEK, SDPA or CSDP). Every solve returns a
// Result that says how sure it is: a dual certificate Λ (block diagonal), the
// minimum eigenvalue of S = C − Λ, a rigorous dual bound, the duality gap, the
// numerical rank of X and the eigen-gap used to decide uniqueness.
#pragma once

#include <Eigen/Dense>
#include <string>
#include <vector>

namespace fact::sdp {

enum class Status {
  certified_unique,      // X is optimal (S ⪰ 0, small gap), S has nullity exactly d and X rank d
  certified_not_unique,  // X is optimal, but S has nullity > d: other optima may exist
  not_certified,         // no certificate of optimality was found
  invalid_input,         // C or d is unusable; reason names the field and value
};
const char* to_string(Status s);

enum class Method {
  automatic,         // complex_low_rank for a complex-form C (d = 2), otherwise rank-d Riemannian
                     // Newton (the whole staircase for d = 2 and n ≤ 8, and for n ≤ 12 after a
                     // steep rank-2 saddle) and null_space (real C);
                     // the interior point when they do not certify
  low_rank,          // Burer–Monteiro Riemannian staircase with block-coordinate updates
  interior_point,    // primal–dual path following (HKM direction, Mehrotra corrector); in
                     // automatic mode dual scaling (DSDP's method) takes the part up to the
                     // hand-off to Newton on the complex form (from the staircase's warm start)
                     // and on a real C without a warm start (n > 48, from X = I)
  complex_low_rank,  // d = 2 and C the real embedding of a Hermitian H (complex_form's output):
                     // Riemannian staircase on Y ∈ ℂ^{N×p}, unit rows, Newton steps in complex
                     // arithmetic; any other C is invalid_input for it
  null_space,        // C ⪰ 0 whose null space holds a feasible X: the optimum is 0, certified by
                     // Λ = 0 (Newton for P ⪰ 0 with X = V P Vᵀ, V a basis of null(C)); not_certified
                     // when it finds none. Automatic mode tries it on a real C, before rank-d
                     // Newton when a rank-d X cannot fit in the null space, after it otherwise.
};
const char* to_string(Method m);

struct Options {
  Method method = Method::automatic;
  double gap_tol = 1e-9;     // largest relative duality gap that certifies (problem scaled to ‖C‖_F = 1);
                             // a gap within bound_error (the bound's rounding) certifies too, and the
                             // reason says so
  double psd_tol = 1e-9;     // λ_min(S) ≥ −psd_tol (scaled problem) counts as S ⪰ 0
  double null_tol = 1e-10;   // eigenvalues of scaled S below this count toward the nullity
  int max_sweeps = 10;       // block-coordinate sweeps after each staircase escape, before Newton
  int max_ipm_iterations = 80;
  int max_newton_iterations = 60;  // Riemannian Newton steps per staircase level (automatic mode: 25 at rank d)
  int max_rank = 0;          // largest factor rank for the staircase; 0 = Pataki bound (negative:
                             // invalid_input, since session 29; it used to mean 0)
  unsigned seed = 1;         // deterministic initialisation
};

// One method a solve ran, in the order they ran: where its iterations and time went. Automatic
// mode may run several (rank-d Newton, the interior point, a Newton polish, …); an explicit
// method runs its own and the steps around it. A solve that returns invalid_input has none.
struct Stage {
  std::string method;     // "low_rank", "null_space", "complex_low_rank", "dual_scaling",
                          // "complex_dual_scaling", "interior_point", "complex_interior_point",
                          // "newton_polish", "complex_newton" or "unique_rank_newton"
  int iterations = 0;     // its own: sweeps and Newton steps, or interior-point iterations
  double time_ms = 0;     // its wall time
  std::string outcome;    // "certified", "not certified", "converged" (an interior point), "handed
                          // off" (to a Newton polish) or why it stopped
};

struct Result {
  Status status = Status::invalid_input;
  std::string reason;
  Method method_used = Method::automatic;
  int d = 0;                 // block size
  int blocks = 0;            // N
  // Primal solution as a factor: X = Y Yᵀ, Y is n × r (r = columns kept).
  Eigen::MatrixXd Y;
  // Dual certificate: Λ_ii stacked vertically, n × d (block i is rows d·i … d·i+d−1).
  Eigen::MatrixXd Lambda;
  double objective = 0;      // ⟨C, X⟩ (unscaled)
  double dual_bound = 0;     // tr Λ + n·min(0, λ_min(S)) (unscaled), λ_min(S) as computed: in exact
                             // arithmetic ⟨C, X⟩ ≥ it for every feasible X
  double bound_error = 0;    // (unscaled) what floating point can have raised dual_bound by: n·e with
                             // e = 4nε‖S‖₂ the eigensolver's error bound on λ_min(S), plus the rounding
                             // of tr Λ and of C's scaling; ⟨C, X⟩ ≥ dual_bound − bound_error for
                             // every feasible X
  double rel_gap = 0;        // (objective − dual_bound) / max(1e-4, |objective|, |dual_bound|), scaled problem
  double min_eig_S = 0;      // λ_min(S), S = C/‖C‖_F − Λ/‖C‖_F (scaled)
  double eig_gap = 0;        // λ_{d+1}(S) (scaled): > null_tol means nullity ≤ d
  int nullity = 0;           // eigenvalues of scaled S below null_tol
  int rank = 0;              // numerical rank of X
  int iterations = 0;        // sweeps, Newton steps and interior-point iterations of every stage, summed
  double time_ms = 0;        // wall time of the whole solve, certification included
  std::vector<Stage> stages;  // the methods it ran, in order
  // When no primal point was found (an explicit method that reports why, status not_certified),
  // Y and Lambda are empty and objective, dual_bound, bound_error, rel_gap, min_eig_S and eig_gap are NaN.
  double scale = 1;          // ‖C‖_F used to scale the problem

  bool certified() const {
    return status == Status::certified_unique || status == Status::certified_not_unique;
  }
  Eigen::MatrixXd X() const { return Y * Y.transpose(); }
};

// Solves the SDP. Never throws on bad input (validate's checks of C, d and the options): returns
// Status::invalid_input with a reason.
Result solve(const Eigen::MatrixXd& C, int d, const Options& options = {});

// C's usable range: max|C_ij| at most kLargestObjective/n² (so that the objective, the bound and
// every multiplier stay finite: |⟨C, X⟩| ≤ ‖C‖_F·n ≤ n²·max|C_ij|) and, unless C = 0, at least
// kSmallestEntry (below it the unscaled certificate Λ would be rounded to the subnormal grid,
// coarser than psd_tol·‖C‖_F).
constexpr double kLargestObjective = 1e300;
constexpr double kSmallestEntry = 1e-290;

// Checks C and d; returns an empty string when they are usable, otherwise the reason (the entry
// and its value). Usable: d = 1 or 2, C square with N = n/d ≥ 2 blocks, finite, in the range
// above, and symmetric up to 1e-9·max|C_ij| (solve averages C with Cᵀ).
std::string validate(const Eigen::MatrixXd& C, int d);
// Checks the options: tolerances finite and ≥ 0, iteration and rank limits ≥ 0, a Method value;
// the reason names the field and its value.
std::string validate(const Options& options);

// The tight complex (U(1)) form in real terms: Q̃ = Q + Kᵀ Q K with K = blkdiag(J, …, J),
// J the 90° rotation. Q is 2N×2N; so is the result.
Eigen::MatrixXd complex_form(const Eigen::MatrixXd& Q);

// Real embedding of a Hermitian N×N matrix H: 2N×2N, block (i,j) = [[Re h, −Im h], [Im h, Re h]].
// Then min ⟨H, Z⟩ over Hermitian Z ⪰ 0 with unit diagonal equals ½ of the d = 2 problem on it.
Eigen::MatrixXd real_embedding(const Eigen::MatrixXcd& H);

// Rounding (d = 2). Takes the top-2 eigenvectors of X = Y Yᵀ, fixes a reflection by a
// determinant vote, projects each 2×2 block to SO(2) and expresses block i relative to
// the reference block. With X_ij = R_iᵀ R_j (R_i the world-from-f_i rotation of drone i),
// element i of the result is R_refᵀ R_i: the rotation of f_i in f_ref (element ref = I).
// Requires a Result with d = 2 and a factor Y; throws std::invalid_argument otherwise.
std::vector<Eigen::Matrix2d> round_rotations(const Result& result, int reference);

// The angle of each rounded rotation, in (−π, π].
std::vector<double> rotation_angles(const std::vector<Eigen::Matrix2d>& rotations);

}  // namespace fact::sdp
