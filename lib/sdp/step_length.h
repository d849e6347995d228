// Step lengths of the interior point: how far P + αΔ stays positive definite, for P = X (the
// primal, n × n) or P = Z (the dual slack, n × n) and a symmetric search direction Δ (n × n).
//
// With P = L Lᵀ, P + αΔ ≻ 0  ⇔  I + α B ≻ 0  for  B = L⁻¹ Δ L⁻ᵀ (n × n, symmetric), so the
// boundary is at α_max = −1/λ_min(B) (no boundary when λ_min(B) ≥ 0). For small n the step is
// the first point of a geometric grid 1, r, r², … whose P + (α/τ)Δ passes a Cholesky test, which
// needs neither B nor its spectrum; for large n λ_min(B) is a Lanczos estimate, and the
// corrector's step is confirmed by a Cholesky test. All work matrices live in a StepLength object
// that the interior point allocates once.
#pragma once

#include <algorithm>
#include <limits>

#include <Eigen/Dense>

namespace fact::sdp::detail {

// Largest n for which the step lengths are found on a grid by Cholesky tests (StepLength); above
// it a Lanczos estimate is confirmed by Cholesky tests. On the grid the predictor's step (τ = 1:
// it only sets the centring σ; the real interior point searches it at a run's first iteration only,
// interior_point.cpp's kAffineStepFraction) is the first of 1, 0.7, 0.7², … that passes, within a factor
// kPredictorStepRatio of min(1, α_max); the corrector's the first of 1, 0.95, 0.95², … (down to
// about ½, then 0.7 a step) for which P + (α/τ)Δ passes, so that α < τ·α_max and, on the fine
// part, α ≥ kCorrectorStepRatio·min(1, τ·α_max). Until session 45 both were exact up to 48 rows
// (B formed by two products, tridiagonalised, λ_min bounded by Laguerre's iteration: 1.0 / 1.2 /
// 1.6 / 1.8 µs a step at n = 10 / 12 / 14 / 16, against 0.11 / 0.17 / 0.21 / 0.25 µs a Cholesky
// test), the predictor's a 4-step Lanczos estimate from n = 16. With the grid (sweep, 12 seeds,
// N = 3 … 32; the plain form and the paper's cost with 2N rounds at noise 0.01 and 0.05, random
// C of rank 3, N + 1 and full): 0.69–0.92 of the time at N = 5 … 24 where the interior point
// runs (plain 0.69–0.79 at N = 5 … 8), iterations −8 … +2 % by row, no status or objective changed;
// the benchmark's plain_noisy N = 5 / 6 / 7 / 8 0.081 / 0.112 / 0.134 / 0.130 → 0.059 / 0.077 /
// 0.092 / 0.101 ms (BENCHMARKS.md, session 45). Above 48 rows the tests cost more than they
// save (the paper's cost and random full rank at N = 32 / 48, n = 64 / 96: 2.3–2.9× the time).
constexpr int kGridStepMaxSize = 48;
// Grid ratios, against 0.7 and 0.95 (N = 5 … 7, 24 seeds): the predictor's 0.5 took 1.13–1.3×
// the iterations, 0.6 / 0.8 / 0.85 1.03 / 1.03 / 1.04 of the time; the corrector's 0.9 2–4 % more
// iterations, 0.93 / 0.96 / 0.97 the same time to ±2 %.
constexpr double kPredictorStepRatio = 0.7;
constexpr double kCorrectorStepRatio = 0.95;
// Up to this n the Lanczos estimates multiply by an explicit L⁻¹ (two matrix–vector products a
// step) instead of solving with L: at n = 64 a pair of Eigen's triangular solves takes 1.2 µs,
// the two products 0.24 µs; at n = 128 2.5 against 2.0 µs, at n = 200 4.2 against 4.9 µs. Above
// n = 48 the primal's L⁻¹ is computed for it alone (n³/3): random full rank N = 32 / 40 / 48 /
// 64 (n = 64 … 128) took 0.90 / 0.93 / 0.98 / 1.02 of the time with a limit of 128 (BENCHMARKS.md,
// session 26).
constexpr int kInverseLanczosMaxSize = 96;

// A pivot that an L D Lᵀ factorisation or a Gauss–Jordan sweep accepts: positive and finite. An
// infinite one leaves a zero reciprocal, and with it a finite-looking factor, inverse or solution
// for a matrix with an infinite entry (session 48's review of SpdSolver). SpdSolver's L D Lᵀ, the
// padded kernels of cholesky_lower and the grid's tests, and inverse_by_sweeps.
inline bool usable_pivot(double pivot) { return pivot > 0 && pivot <= std::numeric_limits<double>::max(); }

// A = L Lᵀ for the symmetric A (n × n, lower triangle read) into the lower triangle of L
// (n × n, upper triangle untouched); false when A is not positive definite (up to
// kPaddedCholeskyMaxSize rows also when a pivot is not finite). Up to kPaddedCholeskyMaxSize rows the grid tests' padded LDLᵀ kernels (right-looking
// up to 32 rows, left-looking above; the factor scaled out at the end), above it left-looking by
// matrix–vector products. Eigen's LLT spends most of its time at these sizes on overhead. Against
// session 51's kernels (right-looking loops below 24 rows, matrix–vector products at 24 … 27, a
// padded left-looking LLᵀ from 28): n = 8 / 12 / 16 / 24 / 32 108 / 185 / 309 / 581 / 762 → 75 /
// 123 / 185 / 385 / 682 ns, at 36 / 48 even; random C of rank 3 at N = 5 (16 factorisations of
// the 18-unknown Newton system) 58.7 → 56.2 µs (BENCHMARKS.md, session 52).
constexpr Eigen::Index kPaddedCholeskyMaxSize = 48;
bool cholesky_lower(const Eigen::MatrixXd& A, Eigen::MatrixXd& L);

// Whether P + a·Δ (P and Δ symmetric n × n, their lower triangles decide, n ≤ kGridStepMaxSize) is
// positive definite, by the signs of its LDLᵀ pivots (all positive and finite): the grid's first
// test of each step length, whose factor is never used. The kernel forms P + aΔ in its own padded
// copy on the stack (right-looking up to 32 rows, left-looking above, where a test failing at
// pivot k reads k columns of P and Δ), instead of into an n × n matrix first. Against that and
// the LLᵀ tests (cholesky_lower's loops below 20 rows, a left-looking padded kernel from 20):
// random full rank N = 8 / 12 77 / 159 → 71 / 151 µs in-process, and 0.91–0.95 of the time where
// the interior point runs at N = 5 … 16 (sweep), iterations identical (BENCHMARKS.md, session 52).
bool sum_passes_cholesky_test(const Eigen::MatrixXd& P, double a, const Eigen::MatrixXd& delta);
// The same for Δ = blkdiag(D), D the d × d diagonal blocks stacked (n × d, the blocks' lower
// triangles decide).
bool block_sum_passes_cholesky_test(const Eigen::MatrixXd& P, double a, const Eigen::MatrixXd& D, int d);

// The same by the kernel for A's size: cholesky_lower up to kGridStepMaxSize rows, Eigen's
// (cholesky_in_place on a copy into L) above. The interior points' and dual scaling's factors
// of X, Z and their step tests.
bool factor_lower(const Eigen::MatrixXd& A, Eigen::MatrixXd& L);

// L⁻¹ for a lower-triangular L with a real positive diagonal (a Cholesky factor, n × n, upper
// triangle ignored), written into inverse (n × n, lower triangular, upper part zero). Real: by
// recursive 2 × 2 blocking, matrix products above 24 × 24 blocks and the blocks on padded
// fixed-size copies (every column at once). Complex: up to 32 rows on split real and imaginary
// padded copies, above it by panels of 24 columns from the last one up.
void invert_lower_factor(const Eigen::MatrixXd& L, Eigen::MatrixXd& inverse);
void invert_lower_factor(const Eigen::MatrixXcd& L, Eigen::MatrixXcd& inverse);

// Up to this many rows inverse_by_sweeps inverts a symmetric or Hermitian positive definite matrix.
constexpr Eigen::Index kSweepInverseMaxSize = 32;

// W = (A + shift·I)⁻¹ for a symmetric or Hermitian A (n × n, n ≤ kSweepInverseMaxSize), n × n with
// both triangles (the lower one mirrored, the diagonal real), by Gauss–Jordan sweeps on padded
// copies (complex: split real and imaginary parts): every pivot's update runs down whole padded
// columns, n³ multiply-adds in all. False when a pivot is not positive (A + shift·I not positive
// definite: the pivots are those of its L D Lᴴ) or not finite, W then undefined. Against Cholesky, L⁻¹ and
// L⁻ᴴ L⁻¹ (n³/2 multiply-adds in three passes with short loops), complex n = 6 / 12 / 24 / 32 took
// 140 / 410 / 1890 / 3790 ns against 240 / 730 / 3150 / 5880 ns, real n = 6 / 12 / 24 / 32 90 / 300
// / 1140 / 2280 ns against 240 / 620 / 1790 / 3100 ns (the real chain from a copy of A + shift·I;
// at n = 48 they were even; BENCHMARKS.md, session 51).
bool inverse_by_sweeps(const Eigen::MatrixXd& A, double shift, Eigen::MatrixXd& W);
bool inverse_by_sweeps(const Eigen::MatrixXcd& A, double shift, Eigen::MatrixXcd& W);

// W = Gᴴ G for a lower-triangular G (n × n, zeros above the diagonal, as invert_lower_factor
// writes), into W (n × n, both triangles): Z⁻¹ = Lz⁻ᴴ Lz⁻¹ from Lz⁻¹. Real: recursive 2 × 2
// blocking above 32 × 32, about n³/3 multiply-adds instead of n³. Complex: loops up to 12 rows,
// Eigen's rank-k update below 32 (n³/2 multiply-adds on the complex product kernel, faster than
// n³/6 in loops), rank-16 updates by row panels from 32 (n³/6).
void gram_of_lower_factor(const Eigen::MatrixXd& G, Eigen::MatrixXd& W);
void gram_of_lower_factor(const Eigen::MatrixXcd& G, Eigen::MatrixXcd& W);

// visit(i, j) once for every entry below the diagonal of an n × n matrix (i > j), tile by tile
// (16 × 16). The loops that pair A(i, j) with A(j, i) read a column and a row at once; column by
// column, a row's entries lie a column's length apart, and at n = 128 or 256 (1 or 2 KiB real,
// 2 or 4 KiB complex) they all fall into the same few cache sets and evict each other: symmetrize
// took 20 µs at n = 128 and 265 µs at n = 256, 5.4 and 23 µs by tiles, and as long either way at
// the other sizes measured (16 … 200; BENCHMARKS.md, session 29).
constexpr Eigen::Index kMirrorTile = 16;
template <class Visit>
void for_each_entry_below_diagonal(Eigen::Index n, Visit visit) {
  for (Eigen::Index jb = 0; jb < n; jb += kMirrorTile)
    for (Eigen::Index ib = jb; ib < n; ib += kMirrorTile) {
      const Eigen::Index j_end = std::min(jb + kMirrorTile, n), i_end = std::min(ib + kMirrorTile, n);
      for (Eigen::Index j = jb; j < j_end; ++j)
        for (Eigen::Index i = std::max(ib, j + 1); i < i_end; ++i) visit(i, j);
    }
}

// A ← (A + Aᵀ)/2 in place (n × n).
void symmetrize(Eigen::MatrixXd& A);

// out = P · blkdiag(D) for P n × n and D the d × d diagonal blocks stacked (n × d): O(n² d).
// out must already be n × n and must not alias P.
void times_block_diagonal(const Eigen::MatrixXd& P, const Eigen::MatrixXd& D, int d, Eigen::MatrixXd& out);

// The first of α, 0.7α, 0.7²α, … (30 tries) for which passes(α) holds (a Cholesky test of the
// trial point it forms), or 0 when none does: the step lengths' confirmation after a Lanczos
// estimate of the boundary, in StepLength, the complex interior point and dual scaling.
template <class Passes>
double shrink_until_passes(double alpha, Passes passes) {
  for (int tries = 0; tries < 30; ++tries, alpha *= 0.7)
    if (passes(alpha)) return alpha;
  return 0.0;
}

// True when the interior point's step lengths for n × n matrices read L⁻¹ (the Lanczos path's
// products up to kInverseLanczosMaxSize rows); the grid's Cholesky tests do not.
inline bool step_length_reads_inverse(Eigen::Index n) { return n > kGridStepMaxSize && n <= kInverseLanczosMaxSize; }

class StepLength {
 public:
  explicit StepLength(int n);

  // About min(1, τ·α_max) for P + αΔ, Δ a full symmetric n × n matrix. Up to kGridStepMaxSize rows
  // the grid's point (kGridStepMaxSize), never beyond τ·α_max, and 0 when the boundary is closer
  // than the grid's last point (on_grid). Above, a Lanczos estimate, which can lie beyond the
  // boundary (its Ritz value lies above λ_min): the predictor's is taken as it is, the corrector's
  // shrunk by 0.7 until P + αΔ passes a Cholesky test (so α < α_max only; 0 when 30 tries fail).
  // With τ < 1 P + αΔ has passed a Cholesky test (take_tested hands it over), except on the grid
  // with factor_next = false: there P + αΔ ≻ 0 follows from P ≻ 0 and P + (α/τ)Δ ≻ 0 (a convex
  // combination, by a margin of (1 − τ)·λ_min(P)), and only the matrix is formed (take_trial).
  // L is P's Cholesky factor (lower triangle, read above kInverseLanczosMaxSize), inverse its L⁻¹
  // (read when step_length_reads_inverse). 0 for a Δ that is not finite.
  double full(const Eigen::MatrixXd& P, const Eigen::MatrixXd& L, const Eigen::MatrixXd& inverse,
              const Eigen::MatrixXd& delta, double tau, bool factor_next = true);

  // The same for a block-diagonal Δ = blkdiag(D), D the d × d diagonal blocks stacked (n × d),
  // factor_next as full's.
  double block_diagonal(const Eigen::MatrixXd& P, const Eigen::MatrixXd& L, const Eigen::MatrixXd& inverse,
                        const Eigen::MatrixXd& D, int d, double tau, bool factor_next = true);

  // After a call with τ < 1 that returned α > 0: swaps P + αΔ, the matrix its Cholesky test passed,
  // into `next` and that test's factor into the lower triangle of `next_factor` (both n × n). The
  // interior point takes its next iterate and its factor from here instead of factoring it again.
  void take_tested(Eigen::MatrixXd& next, Eigen::MatrixXd& next_factor);
  // The same for the matrix alone (a call with factor_next = false).
  void take_trial(Eigen::MatrixXd& next);

 private:
  // full's and block_diagonal's step for n × n matrices: form_trial(a) writes P + aΔ into trial_,
  // passes_at(a) tests P + aΔ without forming it (sum_passes_cholesky_test or its block form; on
  // the grid), lowest_estimate() returns Lanczos's estimate of λ_min(L⁻¹ΔL⁻ᵀ) (read above
  // kGridStepMaxSize only). Up to kGridStepMaxSize rows on_grid; above, min(1, τ/|estimate|), for
  // τ < 1 shrunk by 0.7 until P + αΔ passes a Cholesky test (shrink_until_passes: at most 30
  // tries, then 0).
  template <class FormTrial, class PassesAt, class LowestEstimate>
  double step(Eigen::Index n, double tau, FormTrial form_trial, PassesAt passes_at, LowestEstimate lowest_estimate,
              bool factor_next = true);
  // The grid's step (kGridStepMaxSize); factor_next as full's.
  template <class FormTrial, class PassesAt>
  double on_grid(double tau, FormTrial form_trial, PassesAt passes_at, bool factor_next);
  bool positive_definite();  // Cholesky test of trial_, its factor into trial_factor_

  Eigen::MatrixXd trial_;         // P + αΔ for the Cholesky test, n × n
  Eigen::MatrixXd trial_factor_;  // its factor in the lower triangle (cholesky_lower, or Eigen's
                                  // blocked kernel above kGridStepMaxSize), n × n
};

}  // namespace fact::sdp::detail
