// Internal pieces of the SDP solver: each is one named step (SE-Sync style).
// All functions work on the scaled problem (‖C‖_F = 1).
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "fact/sdp.h"
#include "spd_solver.h"
#include "step_length.h"

namespace fact::sdp::detail {

// printf into a std::string (validate.cpp), for the solve's reason and validate's messages. The
// reason is written on every solve, and an std::ostringstream's construction (its locale) and
// insertions cost ~1 µs, 4 % of a tight_noisy N = 5 solve; %g prints a double as a stream's
// default format does.
[[gnu::format(printf, 1, 2)]] std::string printed(const char* format, ...);

// A dual certificate for a candidate primal factor.
struct Certificate {
  Eigen::MatrixXd lambda;     // n × d, Λ_ii stacked: Λ_ii = sym((C Y)_i Y_iᵀ)
  Eigen::VectorXd eigenvalues;  // all eigenvalues of S = C − Λ, ascending, n
  Eigen::VectorXd min_vector;   // unit eigenvector of λ_min(S), n (only when asked for)
  double trace_lambda = 0;    // tr Λ: the dual objective
  double min_eig = 0;         // λ_min(S)
  double dual_bound = 0;      // tr Λ + n·min(0, λ_min(S)): a lower bound on the optimum
  double bound_error = 0;     // what rounding can have raised dual_bound by (bound_from_spectrum):
                              // the eigensolver's error on λ_min(S) (n·e), tr Λ's sum, C's scaling
};

// Λ from a primal factor Y (n × r) whose d×d diagonal blocks of Y Yᵀ are I.
Eigen::MatrixXd lambda_from_factor(const Eigen::MatrixXd& C, const Eigen::MatrixXd& Y, int d);

// S = C − blkdiag(Λ), n × n: returned, or written into S (no allocation when S is already n × n).
Eigen::MatrixXd certificate_matrix(const Eigen::MatrixXd& C, const Eigen::MatrixXd& lambda, int d);
void certificate_matrix(const Eigen::MatrixXd& C, const Eigen::MatrixXd& lambda, int d, Eigen::MatrixXd& S);

// min_eig, dual_bound and bound_error of cert from its eigenvalues (all n of S) and trace_lambda.
void bound_from_spectrum(Certificate& cert);
// 4nε·scale: the backward error of a symmetric eigensolver on an n × n matrix of 2-norm scale (at
// least the smallest normal double), within which an eigenvalue counts as 0.
double eigensolver_error(Eigen::Index n, double scale);

// tr Λ for Λ's d × d diagonal blocks stacked (n × d): Σ_i tr Λ_ii.
double block_trace(const Eigen::MatrixXd& lambda, int d);

// Eigen-analysis of S for a given Λ. With want_vector, also the eigenvector of λ_min.
Certificate certify(const Eigen::MatrixXd& C, const Eigen::MatrixXd& lambda, int d, bool want_vector);

// Burer–Monteiro block-coordinate minimisation at fixed rank: sweeps over blocks, each
// block set to −polar((C Y)_i − C_ii Y_i), until the largest block change < tol.
// Y is n × r with orthonormal-row blocks on entry and exit. Returns the sweeps done.
int block_coordinate_sweeps(const Eigen::MatrixXd& C, int d, Eigen::MatrixXd& Y, int max_sweeps, double tol);

// The block constraints X_ii = I_d as entries (interior_point.cpp): constraint p fixes X(u, v),
// u ≤ v in the same d × d diagonal block, A_p = e_u e_uᵀ (u = v) or e_u e_vᵀ + e_v e_uᵀ, with
// right-hand side 1 (u = v) or 0; m = N·d(d+1)/2 of them, block by block.
struct Entry {
  int u, v;  // the (row, column) of X this constraint fixes, u ≤ v
};
std::vector<Entry> constraint_entries(int n, int d);
// Aᵀ(y) = blkdiag(Λ) as Λ (n × d, blocks stacked) from y (m); every entry of lambda is written.
void lambda_from_y(const Eigen::VectorXd& y, const std::vector<Entry>& entries, int d, Eigen::MatrixXd& lambda);
// M_pq = tr(A_p X A_q W) (m × m, both triangles) for symmetric X and W (n × n): the interior
// point's Schur complement (W = Z⁻¹), and Newton's in Schur form (X = Y Yᵀ, W = (S + λI)⁻¹).
void schur_complement(const Eigen::MatrixXd& X, const Eigen::MatrixXd& W, const std::vector<Entry>& entries,
                      Eigen::MatrixXd& M);

// How newton_refine solves its Newton system (newton.cpp): automatic takes tangent_basis while the
// t = d·r − d(d+1)/2 tangent directions of a block are at most its d(d+1)/2 normal ones (the
// Hessian formed in tangent bases, N·t unknowns) and schur above (N·d(d+1)/2 unknowns, through
// (S + λI)⁻¹, whatever r is). Both take the same damped steps (the tests compare them).
enum class NewtonSystem { automatic, tangent_basis, schur };
// Unknowns of the system newton_refine factors in automatic mode at rank r (blocks = N): N·t in
// tangent bases, N·d(d+1)/2 in Schur form, so N·min(t, d(d+1)/2), t = d·r − d(d+1)/2.
inline int newton_unknowns(int blocks, int d, int r) {
  return blocks * std::min(d * r - d * (d + 1) / 2, d * (d + 1) / 2);
}

// A Newton run that crawls: from step kCrawlMinSteps on, f has fallen by less than
// `decrease`·|f| over the last kCrawlSpan steps while ‖grad‖ is still above kCrawlGrad. A level
// whose optimum has a higher rank does that for many steps at a saddle of this rank (random
// full-rank C, N = 32, rank 2: 19 steps at ‖grad‖ ≈ 2e-2 … 4e-2, f falling 1.5–8 % per 3 steps);
// one that converges falls faster or reaches a small gradient. decrease = 0 never stops. The
// fraction is of |f|, which includes the constant Σ tr C_ii (X_ii = I), so it is a heuristic: near
// a nonzero optimum only ‖grad‖ ≤ kCrawlGrad keeps a converging run going, and a run it stops
// wrongly only costs time (the interior point follows). A review compared watched and unwatched
// runs on 570 instances (N = 25 … 64, the paper's plain and complex costs, random C of rank 1 … 2N,
// C ± cI): none lost its certificate.
constexpr int kCrawlMinSteps = 6;
constexpr int kCrawlSpan = 3;
constexpr double kCrawlGrad = 1e-4;
class CrawlWatch {
 public:
  explicit CrawlWatch(double decrease) : decrease_(decrease) {}
  // True when the run, at `step` (0, 1, …) with cost f and gradient norm grad_norm, crawls.
  bool crawls(int step, double f, double grad_norm) {
    const bool crawling = decrease_ > 0 && step >= kCrawlMinSteps && grad_norm > kCrawlGrad &&
                          recent_[(step - kCrawlSpan) % (kCrawlSpan + 1)] - f < decrease_ * std::abs(f);
    recent_[step % (kCrawlSpan + 1)] = f;
    return crawling;
  }

 private:
  double decrease_;
  double recent_[kCrawlSpan + 1] = {};  // f at the last kCrawlSpan + 1 steps, by step modulo
};

// Damped Riemannian Newton at fixed rank until ‖grad‖ < grad_tol, or until it crawls (CrawlWatch
// with crawl_decrease; 0: never). Returns the steps taken.
int newton_refine(const Eigen::MatrixXd& C, int d, Eigen::MatrixXd& Y, int max_iterations, double grad_tol,
                  NewtonSystem system = NewtonSystem::automatic, double crawl_decrease = 0);

// One Levenberg–Marquardt-damped Newton step, shared by the real and the complex Newton: H + μI
// (H: the Hessian in tangent coordinates, restored on return) is factored with μ = damping,
// raised 10× while it is not positive definite or the trial cost trial(η) of η = −(H + μI)⁻¹ g
// exceeds f + noise, at most 12 times. Returns the accepted trial cost, or NaN when no try was
// accepted; after an accepted step damping becomes 10·max(1e-12, μ/100), i.e. 10× lower.
template <class Trial>
double damped_newton_step(Eigen::MatrixXd& H, SpdSolver& llt, const Eigen::VectorXd& g,
                          Eigen::VectorXd& eta, double& damping, double f, double noise, Trial trial) {
  for (int tries = 0; tries < 12; ++tries, damping *= 10) {
    H.diagonal().array() += damping;  // shifted in place: the factorisation copies H + μI
    const bool definite = llt.factor(H);
    H.diagonal().array() -= damping;
    if (!definite) continue;  // H + μI not positive definite: more damping
    llt.solve(g, eta);
    eta = -eta;
    const double f_next = trial(eta);
    if (f_next <= f + noise) {  // near the optimum the decrease is below rounding: accept
      damping = 10 * std::max(1e-12, damping / 100);
      return f_next;
    }
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// From this size on cholesky_in_place takes Eigen's blocked kernel, below it the unblocked one.
// Eigen's blocked kernel cuts blocks of size/8 rounded down to a multiple of 16 but at least 8,
// so every n from 32 to 127 gets 8-column blocks, whose triangular solves and rank-8 updates cost
// more than they save: n = 32 / 48 / 64 / 100 took 5.2 / 11.5 / 20.5 / 53 µs blocked against
// 1.9 / 4.8 / 10.3 / 31 µs unblocked (complex), 2.5 / 5.0 / 8.7 / 22 against 0.95 / 2.3 / 4.6 /
// 14 µs (real); below 32 Eigen itself calls the unblocked kernel, and from n = 128 blocked is as
// fast or faster (n = 200 complex 240 against 273 µs; BENCHMARKS.md, session 29). That was a
// machine with AVX-512; with AVX2 (AMD EPYC) the complex blocked kernel is slower up to n = 256:
// n = 128 / 160 / 200 / 256 took 232 / 421 / 788 / 1540 µs blocked against 168 / 330 / 602 /
// 1512 µs unblocked, the real one faster from 128 as before (BENCHMARKS.md, session 35).
constexpr Eigen::Index kBlockedCholeskyMinSize = 128;
constexpr Eigen::Index kBlockedComplexCholeskyMinSize = 256;
// From this size up to kBlockedCholeskyMinSize a real cholesky_in_place runs
// padded_cholesky_in_place instead of Eigen's unblocked kernel (n = 48: 2.09 against 2.18 µs).
constexpr Eigen::Index kPaddedCholeskyMinSize = 49;

// Below this size a complex cholesky_in_place runs complex_cholesky_by_loops instead of Eigen's
// unblocked kernel: tight_noisy N = 5 / 6 / 12 / 32 took 0.97 / 0.96 / 0.97 / 0.97 of the time,
// N = 64 … 200 the same (a threshold of 64 and of 128 measured alike at N = 32; 256 lost 9 % at
// N = 200). The same loop on real matrices gained nothing (BENCHMARKS.md, session 39). From this
// size (64 until session 47) up to kBlockedComplexCholeskyMinSize it runs
// complex_cholesky_by_panels: n = 40 / 48 / 64 / 100 / 128 / 200 took 2.8 / 4.1 / 8.1 / 23 / 43 /
// 140 µs against the loops' 3.2 / 5.2 and Eigen's unblocked kernel's 8.9 / 28 / 79 / 253 µs
// (complex_cholesky_by_panels is 1.0–1.07× Eigen's blocked kernel from 256; BENCHMARKS.md,
// session 47).
constexpr Eigen::Index kLoopComplexCholeskyMaxSize = 40;
// Columns per panel of complex_cholesky_by_panels (16 and 32 measured within 3 % of 24).
constexpr Eigen::Index kComplexCholeskyPanel = 24;

// A = L Lᴴ for a Hermitian A (n × n, a matrix or a diagonal block of one), in place into A's lower
// triangle (its upper one untouched). Right-looking as L D Lᴴ: column k's multiples of the pivot's
// row taken off the trailing columns, no square root on the path from one pivot to the next; then
// column k scaled by 1/√D_kk at the end (the roots independent of each other): n = 5 / 12 / 32
// took 79 / 258 / 2045 ns with column k scaled by its root before the update, 53 / 219 / 1955 ns
// this way (BENCHMARKS.md, session 48). False at the first pivot that is not positive (a NaN one
// too); a pivot below about 5.6e-309, whose reciprocal overflows, fails through the NaN it leaves.
bool complex_cholesky_by_loops(Eigen::Ref<Eigen::MatrixXcd, 0, Eigen::OuterStride<>> A);

// The same by panels of kComplexCholeskyPanel columns, right-looking: the panel's diagonal block
// by complex_cholesky_by_loops, the block below it by a triangular solve with that block's
// factor, and its product with its own adjoint taken off the trailing lower triangle by Eigen's
// Hermitian rank-k update (the matrix-product kernel, where the loops and Eigen's unblocked
// kernel go a column at a time). False at the first pivot that is not positive.
bool complex_cholesky_by_panels(Eigen::MatrixXcd& A);

// A = L Lᵀ for a real symmetric A of kPaddedCholeskyMinSize … kBlockedCholeskyMinSize − 1 rows, in
// place into its lower triangle (the upper one untouched), on a copy padded to a multiple of 8 rows
// (step_length.cpp): right-looking, two columns at a time, every update over whole 8-row blocks.
// Against Eigen's unblocked kernel (matrix–vector products a column), n = 64 / 72 / 96 / 120 took
// 4.39 / 5.91 / 11.8 / 20.6 µs, this way 3.51 / 4.54 / 8.83 / 16.9 µs (BENCHMARKS.md, session 50).
// False at the first pivot that is not positive (a NaN one too).
bool padded_cholesky_in_place(Eigen::MatrixXd& A);

// A = L Lᴴ for a self-adjoint A (n × n, real or complex), factored in place into A's lower
// triangle by Eigen's unblocked kernel below kBlockedCholeskyMinSize (real: padded_cholesky_in_place
// from kPaddedCholeskyMinSize; complex:
// complex_cholesky_by_loops below kLoopComplexCholeskyMaxSize, then complex_cholesky_by_panels
// below kBlockedComplexCholeskyMinSize) and its blocked one from it;
// false when A is not positive definite or its lower triangle has a NaN or infinite entry (of a
// complex diagonal only the real part is read, as for any self-adjoint A).
// Eigen::LLT::compute would also sum |a_ij| for a condition estimate that nothing here reads: for
// complex entries a hypot per entry, 8 % of the complex interior point's time at N = 100
// (BENCHMARKS.md, session 13).
template <class Matrix>
bool cholesky_in_place(Matrix& A) {
  using Kernel = Eigen::internal::llt_inplace<typename Matrix::Scalar, Eigen::Lower>;
  constexpr bool is_complex = Eigen::NumTraits<typename Matrix::Scalar>::IsComplex;
  const Eigen::Index blocked_from = is_complex ? kBlockedComplexCholeskyMinSize : kBlockedCholeskyMinSize;
  // Eigen tests its pivots by x <= 0, which a NaN passes, and an infinite pivot has an infinite
  // root: a NaN or infinite entry read from the lower triangle ends up on L's diagonal (or, off
  // the diagonal and infinite, makes a later pivot −∞), checked here.
  if constexpr (is_complex) {
    if (A.rows() < kLoopComplexCholeskyMaxSize) return complex_cholesky_by_loops(A) && A.diagonal().real().allFinite();
    if (A.rows() < blocked_from) return complex_cholesky_by_panels(A) && A.diagonal().real().allFinite();
  } else {
    if (A.rows() >= kPaddedCholeskyMinSize && A.rows() < blocked_from)
      return padded_cholesky_in_place(A) && A.diagonal().allFinite();
  }
  return (A.rows() < blocked_from ? Kernel::unblocked(A) : Kernel::blocked(A)) == -1 &&
         A.diagonal().real().allFinite();
}

// True when S + t·I passes a Cholesky test (S self-adjoint, n × n, real or complex; a copy is
// factored): λ_min(S) > −t, up to rounding at the boundary. O(n³/3), a fraction of S's spectrum.
// Real S by factor_lower (cholesky_lower's loops up to kGridStepMaxSize rows, where Eigen's
// unblocked kernel spends most of its time on overhead: the real staircase's test of a level at
// n = 6 … 12; BENCHMARKS.md, session 50).
template <class Matrix>
bool positive_definite_when_shifted(Matrix S, double t) {
  S.diagonal().array() += t;
  if constexpr (!Eigen::NumTraits<typename Matrix::Scalar>::IsComplex) {
    Matrix L(S.rows(), S.cols());  // the factor, lower triangle
    return factor_lower(S, L) && L.diagonal().allFinite();  // (an infinite pivot passes the loops)
  } else {
    return cholesky_in_place(S);
  }
}

// All eigenvalues of the self-adjoint A (n × n, n ≥ 1, real or complex), ascending, and unit
// eigenvectors of the k ≤ n smallest (n × k, orthonormal): tridiagonalize with the reflectors kept,
// tridiagonal_eigenvalues, then inverse iteration on the tridiagonal matrix at each of the k
// eigenvalues and the reflectors applied back (O(n²) a vector); unit vectors for A = 0; Eigen's full
// decomposition only if the QL iteration fails or a vector comes out non-finite or not of unit
// length. NaN eigenvalues and vectors for a non-finite A. With `below`, vectors only of those of
// the k smallest eigenvalues that are below it, but at least one (n × k', min(1, k) ≤ k' ≤ k),
// counted on the eigenvalues returned (Eigen's, when its decomposition was the fallback).
void lowest_eigenpairs(const Eigen::MatrixXd& A, int k, Eigen::VectorXd& eigenvalues, Eigen::MatrixXd& vectors,
                       double below = std::numeric_limits<double>::infinity());
void lowest_eigenpairs(const Eigen::MatrixXcd& A, int k, Eigen::VectorXd& eigenvalues, Eigen::MatrixXcd& vectors,
                       double below = std::numeric_limits<double>::infinity());

// The unit eigenvector of A's smallest eigenvalue (n × 1), as lowest_eigenpairs with k = 1 but
// without the spectrum: λ_min by lowest_tridiagonal_eigenvalue instead of the QL iteration, which
// was a quarter of a noise-free 8-drone solve (two 8 × 8 spectra, session 28).
Eigen::MatrixXd lowest_vector(const Eigen::MatrixXd& A);
Eigen::MatrixXcd lowest_vector(const Eigen::MatrixXcd& A);

// The shift δ of an inverse iteration toward M's bottom eigenvectors (M self-adjoint, real or
// complex, positive semidefinite in the cases that matter): 1e-10 of M's largest diagonal entry,
// at least 1e-10, so that M + δI factors when M is singular.
template <class Matrix>
double inverse_iteration_shift(const Matrix& M) {
  return 1e-10 * std::max(1.0, M.diagonal().real().cwiseAbs().maxCoeff());
}

// Entry i of the fixed, generic start vector number j of an inverse or power iteration:
// 1 + 0.5·frac(0.618…·(i + 1) + 0.37·j), in [1, 1.5) (no sin calls: they cost 6 a vector, 0.7 %
// of a tight N = 6 solve; BENCHMARKS.md, session 49).
inline double generic_start_entry(Eigen::Index i, int j) {
  const double turn = 0.6180339887498949 * static_cast<double>(i + 1) + 0.37 * j;
  return 1.0 + 0.5 * (turn - std::floor(turn));
}

// W = (M + δI)⁻¹ (n × n) for the self-adjoint M (real or complex), δ = inverse_iteration_shift(M),
// by the Schur-form Newton's kernels: inverse_by_sweeps up to kSweepInverseMaxSize rows, above it
// Cholesky, L⁻¹, L⁻ᴴ L⁻¹. False when M + δI is not positive definite (a pivot not positive; W then
// undefined). The spectral starts' power and subspace iterations multiply by it
// (bottom_vector_by_inverse, bottom_vectors_by_inverse).
template <class Matrix>
bool shifted_inverse(const Matrix& M, Matrix& W) {
  if (M.rows() <= kSweepInverseMaxSize) return inverse_by_sweeps(M, inverse_iteration_shift(M), W);
  Matrix L = M;  // M + δI, then its Cholesky factor (lower triangle), n × n
  L.diagonal().array() += inverse_iteration_shift(M);
  if (!cholesky_in_place(L)) return false;
  Matrix L_inv;  // L⁻¹, n × n
  invert_lower_factor(L, L_inv);
  gram_of_lower_factor(L_inv, W);
  return true;
}

// V's columns (n × m) made orthonormal in order: Gram–Schmidt twice, each column normalised.
template <class Matrix>
void orthonormalize_columns(Matrix& V) {
  for (Eigen::Index j = 0; j < V.cols(); ++j) {
    for (int pass = 0; pass < 2; ++pass)
      for (Eigen::Index i = 0; i < j; ++i) V.col(j) -= V.col(i).dot(V.col(j)) * V.col(i);
    V.col(j).normalize();
  }
}

// Rayleigh–Ritz on span(V) (V n × m, orthonormal columns): the k vectors (n × k) of M's smallest
// Ritz values there.
template <class Matrix>
Matrix bottom_ritz_vectors(const Matrix& M, const Matrix& V, int k) {
  const Matrix T = V.adjoint() * M * V;  // m × m
  const Eigen::SelfAdjointEigenSolver<Matrix> small(T);
  return V * small.eigenvectors().leftCols(k);
}

// The k eigenvectors of the smallest eigenvalues of the self-adjoint M (n × n, real or complex),
// n × k, by subspace inverse iteration on M + δI (δ: inverse_iteration_shift): one Cholesky
// factorisation, then O(n²) per step, with two guard vectors that speed up convergence of the
// first k. For n ≤ full_up_to, or when M + δI is not positive definite (M indefinite),
// lowest_eigenpairs (O(n³) once) is used instead. The real staircase and the complex one start
// from it.
template <class Matrix>
Matrix bottom_eigenvectors(const Matrix& M, int k, Eigen::Index full_up_to) {
  const Eigen::Index n = M.rows();
  const auto from_tridiagonal = [&] {
    if (k == 1) return Matrix(lowest_vector(M));
    Eigen::VectorXd eigenvalues;  // n, not used
    Matrix vectors;               // n × k
    lowest_eigenpairs(M, k, eigenvalues, vectors);
    return vectors;
  };
  if (n <= full_up_to) return from_tridiagonal();  // small: the reduction is as cheap
  const double shift = inverse_iteration_shift(M);
  Matrix L = M;  // n × n: M + δI, then its factor in the lower triangle (cholesky_in_place)
  L.diagonal().array() += shift;
  if (!cholesky_in_place(L)) return from_tridiagonal();
  const auto lower = L.template triangularView<Eigen::Lower>();
  Matrix V(n, k + 2);  // deterministic start, n × (k + 2)
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < V.cols(); ++j) V(i, j) = std::sin(1.0 + i * (j + 1.618) + 0.37 * j);
  for (int step = 0; step < 12; ++step) {
    lower.solveInPlace(V);             // L⁻¹ V
    lower.adjoint().solveInPlace(V);   // (M + δI)⁻¹ V
    orthonormalize_columns(V);
  }
  return bottom_ritz_vectors(M, V, k);
}

// Householder reduction of the symmetric A (n × n, lower triangle used; destroyed) to the
// tridiagonal matrix with the same eigenvalues: diagonal (n) and subdiagonal (n − 1, entries
// defined up to sign); scratch is 2n (spectrum.cpp).
void tridiagonalize(Eigen::MatrixXd& A, Eigen::VectorXd& diagonal, Eigen::VectorXd& subdiagonal, Eigen::VectorXd& scratch);

// The eigenvalues of the symmetric tridiagonal matrix with diagonal d (n) and squared
// off-diagonal entries e2 (e2[i] = T(i+1, i)², n entries, the last one scratch), ascending into d;
// e2 is destroyed. Root-free QL (EISPACK's tqlrat); false when an eigenvalue took more than 30
// sweeps (d is then undefined).
bool tridiagonal_eigenvalues(Eigen::VectorXd& d, Eigen::VectorXd& e2);

// All eigenvalues of the self-adjoint A (n × n, n ≥ 1, real or complex), ascending: tridiagonalize and
// tridiagonal_eigenvalues (Eigen's QR only if that fails); all NaN for a non-finite A.
Eigen::VectorXd eigenvalues_of(const Eigen::MatrixXd& A);
Eigen::VectorXd eigenvalues_of(const Eigen::MatrixXcd& A);

// The ends of the Gershgorin discs of the symmetric tridiagonal matrix with diagonal a (k ≥ 1) and
// subdiagonal b (k − 1): every eigenvalue lies in [lo, hi], and radius() = max(hi, −lo) bounds
// the spectral radius (step_length.cpp).
struct GershgorinBounds {
  double lo, hi;
  double radius() const { return std::max(hi, -lo); }
};
GershgorinBounds gershgorin_bounds(const Eigen::Ref<const Eigen::VectorXd>& a, const Eigen::Ref<const Eigen::VectorXd>& b);

// The smallest eigenvalue of the symmetric tridiagonal matrix with diagonal a (k) and
// subdiagonal b (k − 1), to within a few kε·‖T‖ (20 000 random, diagonal, zero, badly scaled and
// repeated-λ_min T up to k = 24: at most 52ε·‖T‖ from Eigen's), by Laguerre's iteration
// (step_length.cpp's lowest_from_below), T scaled into range first: a few hundred flops for the
// Lanczos matrices here (k ≤ 24), where Eigen's QR iteration with its allocations cost 6 % of a
// tight_noisy N = 32 solve. Bisection on Sturm counts to 4ε·‖T‖, until session 28, took 0.76 /
// 1.48 / 5.1 µs at k = 8 / 12 / 24, this 0.28 / 0.38 / 0.99 µs.
double lowest_tridiagonal_eigenvalue(const Eigen::Ref<const Eigen::VectorXd>& a, const Eigen::Ref<const Eigen::VectorXd>& b);

// The Lanczos start: near the all-ones vector, perturbed so that no symmetry of B hides its
// lowest eigenvector, unit length (n). Kept per thread for the last n asked and recomputed when n
// changes (n sines cost about as much as a 4-step Lanczos run's products at n = 10); the reference
// holds until the thread's next call with another n, so callers copy it at once.
inline const Eigen::VectorXd& lanczos_start(Eigen::Index n) {
  static thread_local Eigen::VectorXd start;
  if (start.size() != n) {
    start.resize(n);
    const double flat = 1.0 / std::sqrt(static_cast<double>(n));
    for (Eigen::Index i = 0; i < n; ++i) start[i] = flat + 1e-3 * std::sin(1.0 + 7.0 * i);
    start.normalize();
  }
  return start;
}

// The lowest Ritz value of a self-adjoint operator (n × n, real or complex: Vector is VectorXd or
// VectorXcd) after at most `steps` Lanczos steps with full reorthogonalisation (twice, against one
// basis vector at a time: the block form's temporaries were most of a 4-step run's 2 µs at
// n = 10; BENCHMARKS.md, session 39), from lanczos_start; apply(v, w) writes w = B v. Ritz values
// lie inside the spectrum, so the estimate is ≥ λ_min(B): the step lengths that use it confirm the
// step with a Cholesky test.
template <class Vector, class Apply>
double lanczos_lowest(Eigen::Index n, int steps, Apply apply) {
  using Basis = Eigen::Matrix<typename Vector::Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  const int k = static_cast<int>(std::min<Eigen::Index>(steps, n));
  Basis V(n, k);  // Lanczos basis, n × k
  Eigen::VectorXd alpha(k), beta(k);
  Vector v = lanczos_start(n).template cast<typename Vector::Scalar>(), w(n);
  int done = 0;
  for (int j = 0; j < k; ++j) {
    V.col(j) = v;
    apply(v, w);
    alpha[j] = std::real(v.dot(w));
    for (int pass = 0; pass < 2; ++pass)
      for (int q = 0; q <= j; ++q) w -= V.col(q).dot(w) * V.col(q);
    beta[j] = w.norm();
    done = j + 1;
    if (beta[j] < 1e-12) break;
    v = w / beta[j];
  }
  return lowest_tridiagonal_eigenvalue(alpha.head(done), beta.head(done - 1));
}

// polar_rows and Newton's retraction use the closed-form 2 × 2 polar factor while
// det(G Gᵀ) > kPolarClosedFormDet·tr(G Gᵀ)² and its rows come out orthonormal to
// kOrthonormalTol (checked in 2 × 2 before they are formed, when det < kPolarCheckDet·tr²);
// otherwise the SVD. det carries an absolute rounding error of about ε·tr², so for a nearly rank-1
// G the check is what decides; above 1e-8·tr² that error moves P Pᵀ by well under 1e-10.
constexpr double kPolarClosedFormDet = 1e-20;
constexpr double kOrthonormalTol = 1e-10;
constexpr double kPolarCheckDet = 1e-8;  // the check runs only below det = kPolarCheckDet·tr²
// (√M)⁻¹ = [[i00, i01], [i01, i11]] for M = G Gᵀ = [[m00, m01], [m01, m11]] (d = 2) in closed form,
// √M = (M + √det I)/√(tr M + 2√det); false when that form is not to be trusted (the rules above),
// and then the polar factor is to come from the SVD.
bool polar_closed_form(double m00, double m01, double m11, double& i00, double& i01, double& i11);

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
// negative eigenvalue, add a column along its eigenvector and continue, up to max_rank. Each
// level's Newton run stops early when it crawls (newton_refine's crawl_decrease). With
// spectrum_only_if_certifiable, a last level whose gradient alone proves λ_min(S) < −psd_tol
// (low_rank.cpp, provably_indefinite: a run stopped far from a critical point, by the crawl watch
// or by its step cap), or whose S + psd_tol·I fails a Cholesky test (a saddle), skips S's spectrum: its
// certificate has Λ and tr Λ, no eigenvalues, and NaN for λ_min and the bound, for a caller that
// goes on to another method. With climb_eig > 0 the staircase climbs past rank d only from a
// critical point with steep negative curvature: ‖S Y‖_F < climb_eig (S Y is half the gradient)
// and λ_min(S) < −climb_eig (a Cholesky test of S + climb_eig·I fails); otherwise rank d is its
// last level.
LowRankOutcome solve_low_rank(const Eigen::MatrixXd& C, int d, const Options& options, double crawl_decrease = 0,
                              bool spectrum_only_if_certifiable = false, double climb_eig = 0);

// Mehrotra's centring σ = min(1, (μ_aff/μ)^exponent) from the predictor's complementarity μ_aff
// (after the affine step) and the current μ, for both interior points; 0 when the ratio is not
// positive (⟨X + αΔX, Z + βΔZ⟩ < 0 only by rounding, or after a Lanczos estimate's predictor step
// past the boundary) or NaN (interior_point.cpp).
double mehrotra_centring(double mu_aff, double mu, int exponent);

// Below this relative gap both interior points form the primal direction's P Z⁻¹ through Z's
// Cholesky factor instead of the product P·W: near the optimum W's entries grow as 1/μ and the
// product loses the digits the last iterations need; before that the product is cheaper
// (primal_direction in interior_point.cpp and complex_interior_point.cpp).
constexpr double kAccurateDirectionGap = 1e-6;

// The stopping rules both interior points share. Each iteration's gap goes through next(); the
// iterate with the smallest gap so far is the one to keep (once rounding limits the last digits
// the gap can grow again). The interior point has converged below stop_fraction·gap_tol (0.1; the
// complex one 1), hands off below handoff_gap (an improving iterate only), and has stalled when
// the gap grew after reaching 1e-6 or has not halved in 4 iterations; reason() then says why.
class GapRule {
 public:
  enum class Verdict { go_on, converged, handed_off, stalled };
  // Converged below stop_fraction·gap_tol.
  GapRule(double gap_tol, double handoff_gap, double stop_fraction = 0.1)
      : handoff_gap_(handoff_gap), stop_gap_(stop_fraction * gap_tol) {}
  // gap = ⟨X, Z⟩, rel_gap relative to the objective; `improved` is set when this iterate is the best.
  Verdict next(double gap, double rel_gap, bool& improved);
  std::string reason(const char* solver, int iterations) const;  // for handed_off and stalled
  // Writes a verdict other than go_on into an interior point's outcome (converged, handed_off,
  // reason); true when the loop stops.
  template <class Outcome>
  bool stops(Verdict verdict, const char* solver, int iterations, Outcome& out) const {
    if (verdict == Verdict::go_on) return false;
    out.converged = verdict == Verdict::converged;
    out.handed_off = verdict == Verdict::handed_off;
    if (!out.converged) out.reason = reason(solver, iterations);
    return true;
  }

 private:
  double handoff_gap_, stop_gap_;
  double best_gap_ = std::numeric_limits<double>::infinity(), best_rel_gap_ = best_gap_, halved_gap_ = best_gap_;
  int stalled_ = 0;  // iterations since the gap last halved
  Verdict last_ = Verdict::go_on;
};

// Gap relative to the objective, on the scaled problem (‖C‖_F = 1): gap over
// max(1e-4, |primal|, |dual|), the floor keeping zero-optimum (noise-free) problems from
// dividing by nothing. solve()'s certificate, the real interior point and dual scaling.
inline double relative_gap(double gap, double primal, double dual) {
  return gap / std::max({1e-4, std::abs(primal), std::abs(dual)});
}

struct InteriorPointOutcome {
  Eigen::MatrixXd X;        // n × n primal
  Eigen::MatrixXd lambda;   // n × d dual multipliers, Λ_ii stacked
  int iterations = 0;
  bool converged = false;   // relative gap below 0.1·gap_tol (solve_dual_scaling: below gap_tol)
  bool handed_off = false;  // stopped at the handoff gap, before convergence (X, lambda resume it)
  std::string reason;       // why it stopped when not converged
};

// Primal–dual path following with the HKM direction and a Mehrotra corrector. It stops once
// the relative gap is below handoff_gap (> 0: handed_off is set), so a caller can try a cheaper
// finish; `resume` (an outcome that handed off, or an interior_start) continues from its X and Λ,
// which are strictly feasible, instead of X = I; its iterations count toward max_ipm_iterations.
InteriorPointOutcome solve_interior_point(const Eigen::MatrixXd& C, int d, const Options& options,
                                          double handoff_gap = 0, const InteriorPointOutcome* resume = nullptr);

// The interior point's cold start's dual shift s (Λ = −s·I, Z = C + s·I ≻ 0) for C scaled to ‖C‖_F = 1.
double cold_start_shift(const Eigen::MatrixXd& C);
// That start's multipliers Λ = −s·I as d × d blocks stacked (n × d).
Eigen::MatrixXd cold_start_lambda(const Eigen::MatrixXd& C, int d);

// X ← D^{-1/2} X D^{-1/2} with D = blkdiag(X_ii) (X n × n symmetric PSD, d × d blocks): every
// diagonal block I again after rounding drift, positive definiteness kept.
void unit_diagonal_blocks(Eigen::MatrixXd& X, int d);

// Dual scaling on the same problem (dual_scaling.cpp, the real counterpart of
// solve_complex_dual_scaling): Newton steps for the dual barrier from lambda0 (n × d, Λ_ii
// stacked, C − blkdiag(Λ₀) ≻ 0), with upper_bound the objective of some feasible X, stopping once
// the relative gap is below handoff_gap (handed_off) or gap_tol (converged), or giving up (a
// reason). X is its best primal point (identity blocks, positive definite up to rounding) and
// lambda its last dual iterate, a strictly feasible pair solve_interior_point can resume from,
// also when it gave up after finding one; without a primal point better than upper_bound X is
// empty. Neither flag is set when it gave up.
InteriorPointOutcome solve_dual_scaling(const Eigen::MatrixXd& C, int d, const Options& options, double handoff_gap,
                                        const Eigen::MatrixXd& lambda0, double upper_bound);

// Appends the Stage (Result::stages) of a method that started at `start` and has ended.
inline void record_stage(std::vector<Stage>& stages, const char* method, int iterations,
                         std::chrono::steady_clock::time_point start, std::string outcome) {
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  stages.push_back({method, iterations, ms, std::move(outcome)});
}
// An interior point's or dual scaling's Stage::outcome.
template <class InteriorPoint>
std::string outcome_of(const InteriorPoint& ip) {
  return ip.converged ? "converged" : ip.handed_off ? "handed off" : ip.reason;
}

// The interior point without a warm start, to handoff_gap (automatic mode in solve()): dual
// scaling from the cold start (cold_start_lambda, with tr C = ⟨C, I⟩ as the upper bound), and the
// primal–dual method when it gives up: from its pair when it found a primal point, else from
// X = I. iterations counts both methods' (the resumed primal–dual run counts from dual scaling's,
// so max_ipm_iterations bounds them together when it resumes); each method's own run is appended
// to stages ("dual_scaling", "interior_point").
InteriorPointOutcome dual_scaling_then_interior_point(const Eigen::MatrixXd& C, int d, const Options& options,
                                                      double handoff_gap, std::vector<Stage>& stages);

// A strictly feasible start for the interior point from a factor Y (n × r, orthonormal-row d × r
// blocks) of a point near the optimum and its multipliers lambda (n × d, Λ_ii stacked; the
// rank-d attempt's, which did not certify): X = (1 − mix)·Y Yᵀ + mix·I (identity blocks, positive
// definite for mix > 0) and Λ − s·I, with s the first of 1e-3, 1e-2, … 1 for which
// C − Λ + s·I passes a Cholesky test. iterations is 0. False, and start untouched, when no s
// passes. The real counterpart of complex_interior_start.
bool interior_start(const Eigen::MatrixXd& C, int d, const Eigen::MatrixXd& Y, const Eigen::MatrixXd& lambda,
                    double mix, InteriorPointOutcome& start);

// The dual shift s of near_zero_start, for C scaled to ‖C‖_F = 1.
constexpr double kNearZeroShift = 1e-3;
// A strictly feasible start for the interior point when the optimum may be near 0 against
// ‖C‖ (C ⪰ 0 with a null space that holds no feasible X: the plain form under noise): the dual
// Λ = −s·I (s = kNearZeroShift), whose objective −s·n is already near such an optimum, and the
// primal X = D (C + s·I)⁻¹ D, D making X's diagonal blocks I (unit_diagonal_blocks): the point
// the dual start is centred for, rescaled to be feasible. μ starts at about 3e-3 instead of the
// cold start's tr C/n + 1/√n (X = I; 0.32–0.42 on the plain form at N = 5 … 8). iterations is 0.
// False, and start untouched, when C + (s/2)·I fails a Cholesky test (λ_min(C) ≤ −s/2 or so).
bool near_zero_start(const Eigen::MatrixXd& C, int d, InteriorPointOutcome& start);

// Factors of a PSD X (factor.cpp).
// The factor of largest rank r ≤ n with X = Y Yᵀ (eigenvalues below tol·max dropped).
Eigen::MatrixXd factor_psd(const Eigen::MatrixXd& X, double tol);
// Cholesky with diagonal pivoting of a self-adjoint Z (n × n, real or complex), column after
// column while the largest remaining diagonal entry of Z − Y Yᴴ on the rows not yet pivoted is
// above tol. Y Yᴴ = Z on the `rank` pivot rows and columns.
template <class Matrix>
struct PivotedCholesky {
  Matrix Y;                   // n × n, columns 0 … rank − 1 in use; column p is zero on the rows
                              // pivoted before it
  Eigen::VectorXd rest;       // diagonal of Z − Y Yᴴ, n (rounding only, on the pivoted rows)
  std::vector<bool> pivoted;  // the rows chosen as pivots, n
  Eigen::Index rank = 0;
};
template <class Matrix>
PivotedCholesky<Matrix> pivoted_cholesky_above(const Matrix& Z, double tol);
// Its factor for a PSD Z: Y (n × p, at least one column) stopped when every remaining diagonal
// entry is at most cutoff × Z's largest diagonal entry (the part dropped then has trace
// ≤ n·cutoff·max Z_ii). n p² / 2 multiply-adds instead of an eigendecomposition.
template <class Matrix>
Matrix pivoted_cholesky(const Matrix& Z, double cutoff);
// X's leading part as a factor Y (n × r, columns orthogonal, largest first, ‖y_k‖² the Ritz values
// of X): r from pivoted_cholesky at `cutoff`, one subspace-iteration step X P from its factor P,
// then Rayleigh–Ritz on that range. O(n² r) against the full eigendecomposition's ~9 n³; what it
// drops is X's part below the cutoff, which the interior point's hand-off truncates anyway.
Eigen::MatrixXd leading_factor(const Eigen::MatrixXd& X, double cutoff);

// At the hand-off X still holds "ghost" eigenvalues that the converged interior point drives to
// 0, of 1e-6 … 1e-4 of the largest, often above the cutoff; Newton at a rank that counts them
// crawls toward the rank-deficient optimum, misses the certificate in its steps, and the interior
// point resumes (5–7 more iterations). polish_rank drops a Ritz value past the d-th that is below
// kGhostBelow of the largest and kGhostDrop times below the one before it. On the plain form
// (N + 1 rounds, noise 0.002 … 0.1) and random C of rank N + 1, N = 5 … 24, 6 seeds each, the
// rank so chosen was the converged optimum's in 161 of the 162 hand-offs, against 90 with the
// cutoff alone (genuine eigenvalues there went down to 2.7e-4 of the largest, behind drops of up
// to 1700×), and the polish failed 12 times instead of 38. Against near_zero_start alone, the
// plain form at noise 0.002 / 0.01 took 0.74–0.95 / 0.79–0.97 of the time at N = 5 … 9 / 6 … 10,
// at noise 0.05 N = 10 / 12 0.84 / 0.76, rank N + 1 N = 14 0.83, the rest 0.96–1.02; the paper's
// cost with 2N and 3N rounds, random C of rank 3 and of full rank (N = 5 … 48) 0.90–1.04, polish
// failures 7 → 2 (BENCHMARKS.md, session 43).
constexpr double kGhostBelow = 1e-4;
constexpr double kGhostDrop = 10.0;
// The rank of the Newton polish for a factor whose columns' squared norms are `values` (X's
// eigenvalues or Ritz values, largest first): the values above 1e-6 of the largest, at most
// max_rank; with drop_ghosts (the hand-off's factor), up to the first value past the d-th that is
// below kGhostBelow of the largest and kGhostDrop times below the one before it.
int polish_rank(const Eigen::VectorXd& values, int d, int max_rank, bool drop_ghosts);

// Largest factor rank the staircase needs: the Pataki bound for N·d(d+1)/2 constraints.
int pataki_rank(int blocks, int d);

// The zero optimum (null_space.cpp). C's spectrum and its null space (the eigenvectors of the
// eigenvalues within ±eigensolver_error of 0). A feasible X = V P Vᵀ needs C ⪰ 0 and k ≥ d.
struct NullSpace {
  Eigen::VectorXd eigenvalues;    // all n eigenvalues of C, ascending
  Eigen::MatrixXd basis;          // V: orthonormal basis of null(C), n × k
  bool positive_semidefinite = false;  // λ_min(C) ≥ −eigensolver_error
  int dimension = 0;              // k: eigenvalues within ±eigensolver_error
};
NullSpace null_space_of(const Eigen::MatrixXd& C);
// What a null space of dimension k leaves room for, C ⪰ 0 assumed (n rows, d × d blocks),
// generically: a feasible X = V P Vᵀ needs k(k+1)/2 ≥ N·d(d+1)/2 unknowns for the constraints,
// one of rank d (V A, A k × d, less its rotation) d·k − d(d−1)/2. Only a filter for automatic
// mode's order: dependent constraints can beat the counts (k = d with a feasible X in it).
struct NullSpaceRoom {
  bool feasible = false;  // k(k+1)/2 ≥ N·d(d+1)/2
  bool rank_d = false;    // d·k − d(d−1)/2 ≥ N·d(d+1)/2
  bool few_points = false;  // feasible with fewer than N unknowns to spare, k(k+1)/2 − N·d(d+1)/2 < N,
                            // at any N: the constraints leave a family of P of dimension below N,
                            // rarely one positive semidefinite (the plain form with N + 1 rounds at
                            // N = 7 and 8, k = 6 and 7: 0 and 4 to spare)
};
NullSpaceRoom room_in_null_space(int k, Eigen::Index n, int d);
// The rank of C by Cholesky with diagonal pivoting, stopped when the largest remaining diagonal
// entry is at most eigensolver_error(n, largest diagonal entry): O(n r² + (n − r)² r) for rank
// r, an estimate of n − k that costs far less than the spectrum when r is small; n when C is seen
// not to be PSD (a remaining diagonal entry below −tol, or a remaining off-diagonal entry above
// tol, which a PSD remainder with a diagonal below tol cannot have).
int pivoted_rank(const Eigen::MatrixXd& C);
// A factor Y (n × k, every block of Y Yᵀ = I) with C Y = 0 up to rounding, and the certificate
// Λ = 0 (S = C, its spectrum), when C's null space holds a feasible X; false when it cannot, or
// when Newton does not find one within its steps.
struct NullSpaceOutcome {
  Eigen::MatrixXd Y;        // n × k factor of X = V P Vᵀ, blocks projected to orthonormal rows
  Certificate certificate;  // Λ = 0: S = C, all n eigenvalues
  int steps = 0;            // Newton steps taken
  // When none was found: true when a step fitted neither at full nor at half length (the set of
  // feasible P ≻ 0 taken to be empty, as it generically is when the null space has just enough
  // room); false when the steps ran out or the Newton system would not factor (a feasible X of
  // low rank, on the set's boundary, may still exist: the noise-free plain form's zero optimum of
  // rank 2 ends that way). False when one was found.
  bool empty = false;
};
bool zero_optimum(const Eigen::MatrixXd& C, int d, const NullSpace& null, NullSpaceOutcome& out);

// The tight complex form (complex_low_rank.cpp).
// Empty when every 2×2 block of C is exactly [[a, −b], [b, a]], so that C is the real
// embedding of a Hermitian matrix (complex_form always returns one); otherwise the first
// entry that breaks the pattern, named with its value.
std::string complex_embedding_mismatch(const Eigen::MatrixXd& C);
// The top-left entry (i, j) of the first 2×2 block of M (rows and columns even in number), by
// columns, that is not exactly [[a, −b], [b, a]]; (−1, −1) when every block is, i.e. when M is the
// real embedding of a complex matrix (real_factor's layout; complex_embedding_mismatch's test).
std::pair<Eigen::Index, Eigen::Index> first_non_complex_block(const Eigen::MatrixXd& M);
// The Hermitian N × N matrix H whose real embedding is C (2N × 2N): H_ij = C(2i,2j) + i·C(2i+1,2j).
Eigen::MatrixXcd hermitian_of(const Eigen::MatrixXd& C);
// The real embedding of any complex matrix, entry by entry (N × p → 2N × 2p; forms.cpp, where
// real_embedding uses it for square H), so emb(Y) emb(Y)ᵀ = emb(Y Yᴴ).
Eigen::MatrixXd real_factor(const Eigen::MatrixXcd& Y);
// Its inverse: the N × p complex Y whose real_factor is Y_real (2N × 2p), read from the first
// column of every 2×2 block.
Eigen::MatrixXcd complex_of_real_factor(const Eigen::MatrixXd& Y_real);
// The multipliers μ_i = Re (H Y)_i y_iᴴ (N) of a factor Y (N × p, unit rows), from HY = H Y (N × p):
// S = H − diag(μ) is the certificate at Y (complex_low_rank.cpp).
void complex_multipliers(const Eigen::MatrixXcd& HY, const Eigen::MatrixXcd& Y, Eigen::VectorXd& mu);
// True when S + shift·I = H − diag(μ) + shift·I (N × N) passes a Cholesky test (N³/3 complex,
// against an eigendecomposition's ~4N³).
bool shifted_positive_definite(const Eigen::MatrixXcd& H, const Eigen::VectorXd& mu, double shift);
// Damped Riemannian Newton on unit rows of Y (N × p complex) for tr(Yᴴ H Y), until
// ‖grad‖ < grad_tol. Returns the steps taken. At p = 1 the Hessian is formed in tangent bases
// (N × N real); at p ≥ 2 each step solves the Newton system in Schur form through (S + λI)⁻¹
// and an N × N real system, O(N³) whatever p is. With saddle_exit (p ≥ 2) it returns early
// when S's negative curvature dominates the gradient (complex_low_rank.cpp). curvature (p ≥ 2):
// a known λ_min(S) near Y, such as the level below's after a staircase escape; the damping's
// first shift is then the decade at or below |curvature|/10 (at most 1) instead of 1e-8. S + λI
// must be positive definite, and after an escape the new S's λ_min is of the level below's
// order, a little less negative (tight_noisy N = 5 / 6 / 12: −1.1e-3 / −1.0e-4 / −2.8e-5 below,
// first accepted shifts 1e-3 / 1e-4 / 1e-4): the shifts from 1e-8 up only failed their tests.
// shift_per_gradient (p ≥ 2; 0 = off): from the second step on the shift is at most
// shift_per_gradient·‖grad‖, so that near an optimum it falls with the gradient rather than 10×
// a step (Levenberg–Marquardt with λ of the residual's order converges quadratically under a
// local error bound); for a polish from an interior point's X, which starts in the optimum's basin.
int complex_newton(const Eigen::MatrixXcd& H, Eigen::MatrixXcd& Y, int max_iterations, double grad_tol,
                   bool saddle_exit = false, double curvature = 0, double shift_per_gradient = 0);

// X = Y Yᴴ (N × N, both triangles, each entry computed, so Hermitian up to rounding) for Y N × p, p
// small, by plain loops: Eigen's lazy complex product for it took 6–9 % of tight_noisy N = 5 and 6
// (BENCHMARKS.md, session 39). X is resized; p = 0 gives X = 0.
void factor_gram(const Eigen::MatrixXcd& Y, Eigen::MatrixXcd& X);
// C = A B for A N × N and B N × p, p small (the factor's rank), by Eigen's lazy (coefficient-based)
// product. Its general product for this shape took 8 % of tight_noisy N = 12 (BENCHMARKS.md,
// session 39); the loops that replaced it then (column k of C as the sum of A's columns weighted
// by column k of B) loaded each complex weight as two doubles and read them back as one vector, a
// store-forwarding stall on every column (half of schur_complex_newton's own time at N = 12):
// tight_noisy N = 5 / 6 / 12 / 24 / 32 took 0.89 / 0.90 / 0.88 / 0.93 / 0.98 of the time with the
// lazy product, N = 48 … 200 the same (session 48). Not inlined: inlined into the Newton loop, it
// gained half as much at N = 5 and 6. C is resized to N × p and must not alias A or B.
void times_thin(const Eigen::MatrixXcd& A, const Eigen::MatrixXcd& B, Eigen::MatrixXcd& C);

// H's bottom eigenvector (N × 1, unit) by power iteration on W = (H + δI)⁻¹ (on W² up to 8 rows),
// δ as bottom_eigenvectors' shift, W formed once by the Schur-form Newton's kernels (Cholesky,
// L⁻¹, L⁻ᴴ L⁻¹), until two iterates agree to |wᴴ v| > 1 − 1e-14 (an angle of about 1.4e-7) or
// after 30 steps. Each step on W gains (λ₁ + δ)/(λ₂ + δ): 0.02–0.27 on the benchmark's noisy
// instances (5–15 steps), about 0 on noise-free data; where λ₁ and λ₂ nearly coincide any vector
// of their span is as good a start. N = 5 / 6 / 8 / 12 / 24 / 32: 0.90 / 1.12 / 1.6 / 3.2 / 11.9 /
// 19.3 µs by the tridiagonal reduction, 0.64 / 0.90 / 0.76 / 1.5 / 4.3 / 8.2 µs this way
// (BENCHMARKS.md, session 49). Empty when H + δI fails its Cholesky test (H not positive
// semidefinite). δ does not scale with H: for H of norm 1e-10 the vector was off by 1e-4 … 0.14
// (N = 6 … 32; review, session 49), so H must be of order 1, as the scaled problem's is.
Eigen::MatrixXcd bottom_vector_by_inverse(const Eigen::MatrixXcd& H);

// The real counterpart for the real staircase's spectral start (low_rank.cpp, 16 … 64 rows): C's
// bottom k eigenvectors (n × k, orthonormal) by kInverseStartSteps subspace steps on
// W = (C + δI)⁻¹ with two guard vectors and a Rayleigh–Ritz step, each step shrinking the error
// by (λ_k + δ)/(λ_{k+3} + δ); empty when C + δI fails its Cholesky test.
Eigen::MatrixXd bottom_vectors_by_inverse(const Eigen::MatrixXd& C, int k);
// Its steps. 6 against the 12 that bottom_eigenvectors' iteration takes: sweep (6 seeds; N = 8 …
// 32; the plain form and the paper's cost with 2N and 3N rounds at noise 0 … 0.05, random C of rank
// 3, N + 1 and full; interleaved, fastest of two runs): the paper's noise-free cost 0.86–0.97 of the
// time (the start is exact after 6 steps there; with 2N rounds from N = 16 one or two Newton steps
// more or fewer), random C of rank 3, whose start is any vector of a large null space, 0.79–1.01
// with iterations moving both ways, every other kind 0.90–1.03 with the same iterations, 0.99 in
// all; no status or objective changed. The start of random full-rank C is then off by up to 3e-4
// (n = 16), which its Newton steps do not feel (BENCHMARKS.md, session 51).
constexpr int kInverseStartSteps = 6;

// The shift a Schur-form Newton step skips past (0: none): carried_failure, the largest shift
// whose Cholesky failed (or that was skipped) in the last step, when it is at or above this step's
// first shift λ and ‖grad‖ is above 10× it; the step then starts 10× above it. After a staircase
// escape S keeps a negative eigenvalue for several steps, and the first shift of each, 10× below
// the last accepted one, failed again (tight_noisy N = 12: 6 of the first 10 steps). The bound on
// ‖grad‖ keeps the skip off the last steps, where S's negative eigenvalue is gone and the lower
// shift would be accepted. Not with shift_per_gradient > 0 (the polish caps its shift instead).
// Tight sweeps N = 5 … 24: 0.92–1.01 of the time (BENCHMARKS.md, session 49).
double skipped_shift(double lambda, double carried_failure, double grad_norm, double shift_per_gradient);

struct ComplexOutcome {
  Eigen::MatrixXcd Y;           // N × p factor with unit rows
  Eigen::VectorXd mu;           // multipliers μ_i = Re (H Y)_i y_iᴴ, N
  Eigen::VectorXd eigenvalues;  // of S = H − diag(μ), ascending, N (empty: not computed)
  Eigen::MatrixXcd eigenvectors;  // of S's lowest eigenvalues, N × (1 … min(N, 2)), only when asked for
  int iterations = 0;           // Newton steps, all levels
  bool certified = false;       // λ_min(S) ≥ −psd_tol
};

// The multipliers and the spectrum of S = H − diag(μ) at Y; with want_vectors, eigenvectors of
// its two lowest eigenvalues, only of those below vectors_below but at least one (the staircase's
// escape follows the negative ones).
ComplexOutcome complex_outcome(const Eigen::MatrixXcd& H, Eigen::MatrixXcd Y, int iterations, bool want_vectors);
// The same for given multipliers μ (the complex interior point's dual y).
ComplexOutcome complex_outcome(const Eigen::MatrixXcd& H, Eigen::MatrixXcd Y, Eigen::VectorXd mu, int iterations,
                               bool want_vectors, double vectors_below = std::numeric_limits<double>::infinity());

// A complex factor (N × p, unit rows) of the Hermitian Z whose embedding is nearest to X
// (2N × 2N, the K-average of X's blocks), by complex_factor at a cutoff of 1e-6. The interior
// point's handoff to Newton.
Eigen::MatrixXcd complex_factor_of(const Eigen::MatrixXd& X);

// A factor Y (N × p, unit rows) of the Hermitian PSD Z (N × N) with Y Yᴴ ≈ Z: pivoted_cholesky
// at `cutoff`, rows then normalised (an eigendecomposition took 1 ms at N = 100).
Eigen::MatrixXcd complex_factor(const Eigen::MatrixXcd& Z, double cutoff);

struct ComplexInteriorPointOutcome {
  Eigen::MatrixXcd X;       // N × N Hermitian primal, unit diagonal
  Eigen::VectorXd y;        // N dual multipliers: S = H − diag(y)
  int iterations = 0;
  bool converged = false;   // relative gap below gap_tol
  bool handed_off = false;  // stopped at the handoff gap, before convergence
  std::string reason;       // why it stopped when not converged
};

// The complex interior point's dual step-length operator: w = Lz⁻¹ ΔZ Lz⁻ᴴ v with ΔZ = −diag(dy)
// (Lz⁻¹ N × N lower triangular, zeros above; dy, v, u, w N; u is scratch). From
// kTriangularProductMinSize rows Lz⁻¹ is multiplied as a triangular matrix, below as a dense one:
// on an AVX2 machine Eigen's triangular matrix–vector product took n = 32 / 64 / 100 / 200:
// 0.56 / 1.46 / 2.96 / 10.0 µs (adjoint 0.39 / 1.18 / 2.51 / 9.5) against the dense product's
// 0.34 / 1.53 / 3.76 / 15.7 (0.42 / 1.58 / 3.64 / 15.2); on AVX-512 the dense product was the
// faster at n = 100 (BENCHMARKS.md, sessions 29 and 35).
constexpr Eigen::Index kTriangularProductMinSize = 64;
void dual_step_operator(const Eigen::MatrixXcd& Lz_inv, const Eigen::VectorXd& dy, const Eigen::VectorXcd& v,
                        Eigen::VectorXcd& u, Eigen::VectorXcd& w);

// Primal–dual path following on the Hermitian N × N problem min Re tr(H X), X_ii = 1, X ⪰ 0
// (complex_interior_point.cpp), HKM direction and Mehrotra corrector, stopping once the
// relative gap is below handoff_gap (> 0: handed_off is set). `resume` (an outcome that handed
// off, or a complex_interior_start) continues from its X and y, which are strictly feasible,
// instead of X = I; its iterations are added to the outcome's.
ComplexInteriorPointOutcome solve_complex_interior_point(const Eigen::MatrixXcd& H, const Options& options,
                                                         double handoff_gap,
                                                         const ComplexInteriorPointOutcome* resume = nullptr);

// Hermitian part in place: A ← (A + Aᴴ)/2 (A N × N; the diagonal made exactly real).
void hermitian_part(Eigen::MatrixXcd& A);
// X ← D^{-1/2} X D^{-1/2} with D = diag(X) (X N × N Hermitian PSD): a unit diagonal again after
// rounding drift, positive definiteness kept.
void rescale_to_unit_diagonal(Eigen::MatrixXcd& X);
// The complex interior points' relative gap (relative_gap's): gap over max(0.5e-4, |primal|, |dual|),
// the floor half of the d = 2 problem's 1e-4 since its objective is twice this one's.
inline double complex_relative_gap(double gap, double primal, double dual) {
  return gap / std::max({0.5e-4, std::abs(primal), std::abs(dual)});
}

// Dual scaling on the same problem (complex_dual_scaling.cpp): Newton steps for the dual barrier
// from y0 (H − diag(y0) ≻ 0), with upper_bound the objective of some feasible X (solve(): the
// primal–dual warm start's), stopping once the relative gap is below handoff_gap (handed_off) or
// gap_tol (converged), or giving up (a reason). X is its best primal point (unit diagonal,
// positive definite up to rounding: its margin shrinks with the gap) and y its last dual
// iterate, a strictly feasible pair the primal–dual method can resume from, also when it gave up
// after finding one; without a primal point better than upper_bound X is empty. Neither flag
// is set when it gave up.
ComplexInteriorPointOutcome solve_complex_dual_scaling(const Eigen::MatrixXcd& H, const Options& options,
                                                       double handoff_gap, const Eigen::VectorXd& y0,
                                                       double upper_bound);

// A strictly feasible start for the complex interior point from a factor Y (N × p, unit rows) of
// a point near the optimum (the staircase's last level, which did not certify):
// X = (1 − mix)·Y Yᴴ + mix·I (unit diagonal, positive definite for mix > 0) and y = μ(Y) − s·1, with
// s the first of 1e-3, 1e-2, … 1 for which H − diag(y) = S(Y) + sI passes a Cholesky test.
// iterations is 0. False, and start untouched, when no s passes.
bool complex_interior_start(const Eigen::MatrixXcd& H, const Eigen::MatrixXcd& Y, double mix,
                            ComplexInteriorPointOutcome& start);

// The certificate of the d = 2 problem on emb(H): Λ_ii = μ_i I₂, and S = emb(H − diag μ) has
// every eigenvalue of H − diag μ twice. An outcome without eigenvalues gives λ_min and the
// bound −∞.
Certificate complex_certificate(const ComplexOutcome& outcome);

// Unknowns of complex Newton's system for Y ∈ ℂ^{N×p}: 2p − 1 tangent directions per unit row.
inline Eigen::Index complex_newton_unknowns(Eigen::Index N, Eigen::Index p) { return N * (2 * p - 1); }

// Riemannian staircase in ℂ: spectral start at p = 1, Newton, and while S has a negative
// eigenvalue a column along its eigenvector, as long as the Newton system of the next rank
// has at most max_unknowns unknowns (complex_newton_unknowns). Without spectrum_if_not_psd, a
// last level whose S fails a Cholesky test at a shift of 2·psd_tol (so it cannot certify)
// returns without eigenvalues (its certificate then has no bound: complex_certificate).
ComplexOutcome solve_complex_low_rank(const Eigen::MatrixXcd& H, const Options& options, int max_unknowns,
                                      bool spectrum_if_not_psd = true);

}  // namespace fact::sdp::detail
