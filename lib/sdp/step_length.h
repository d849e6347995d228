// Step lengths of the interior point: how far P + αΔ stays positive definite, for P = X (the
// primal, n × n) or P = Z (the dual slack, n × n) and a symmetric search direction Δ (n × n).
//
// With P = L Lᵀ, P + αΔ ≻ 0  ⇔  I + α B ≻ 0  for  B = L⁻¹ Δ L⁻ᵀ (n × n, symmetric), so the
// boundary is at α_max = −1/λ_min(B) (no boundary when λ_min(B) ≥ 0). For small n, B is
// reduced to a tridiagonal matrix (Householder) and λ_min is bounded from below by Laguerre's
// iteration; for large n a Lanczos estimate is used. All work matrices live in a StepLength
// object that the interior point allocates once.
#pragma once

#include <algorithm>

#include <Eigen/Dense>

namespace fact::sdp::detail {

// Largest n for which the corrector's step length is computed exactly (tridiagonalisation,
// O(n³)); above it a 12-step Lanczos estimate is verified by Cholesky tests.
constexpr int kExactStepMaxSize = 48;
// From this n on, the predictor's step (τ = 1, it only sets the centring σ) is a Lanczos estimate,
// O(n²) a step (4 steps up to n = 64, 8 above; step_length.cpp). With 8 steps, when introduced:
// the same iterations (or one fewer) on the benchmark's plain and random instances, and 3 / 10 /
// 20 / 12 % fewer instructions per solve at n = 24 / 32 / 64 / 128 (plain_noisy; below n = 24 the
// exact path's plain loops cost less than Eigen's triangular solves then). From 16 since session
// 39, when Lanczos lost its temporaries (lanczos_lowest): 4 seeds of the plain cost (noise 0.01,
// 0.05, 0.1) and random C (rank 3, N + 1, full), summed by kind, N = 8 / 10 (n = 16 / 20) 0.90–1.08
// / 0.81–1.07 of the time, 0.96 / 0.94 on average; at N = 5 … 7 (n = 10 … 14) 0.89–1.11, about even.
constexpr int kPredictorLanczosMinSize = 16;
// Up to this n the Lanczos estimates multiply by an explicit L⁻¹ (two matrix–vector products a
// step) instead of solving with L: at n = 64 a pair of Eigen's triangular solves takes 1.2 µs,
// the two products 0.24 µs; at n = 128 2.5 against 2.0 µs, at n = 200 4.2 against 4.9 µs. Above
// n = 48 the primal's L⁻¹ is computed for it alone (n³/3): random full rank N = 32 / 40 / 48 /
// 64 (n = 64 … 128) took 0.90 / 0.93 / 0.98 / 1.02 of the time with a limit of 128 (BENCHMARKS.md,
// session 26).
constexpr int kInverseLanczosMaxSize = 96;

// A = L Lᵀ for the symmetric A (n × n, lower triangle read) into the lower triangle of L
// (n × n, upper triangle untouched); false when A is not positive definite. Plain loops for
// the small sizes of the exact path, where Eigen's LLT spends most of its time on overhead:
// right-looking below kColumnCholeskyMinSize, left-looking by matrix–vector products from it
// (n = 24 / 32 / 48 / 64: 0.72 / 1.24 / 3.2 / 6.5 µs right-looking, 0.63 / 1.03 / 2.3 / 4.2 µs
// left-looking; n = 16: 0.33 against 0.35; BENCHMARKS.md, session 27).
constexpr Eigen::Index kColumnCholeskyMinSize = 24;
bool cholesky_lower(const Eigen::MatrixXd& A, Eigen::MatrixXd& L);

// The same by the kernel for A's size: cholesky_lower up to kExactStepMaxSize rows, Eigen's
// (cholesky_in_place on a copy into L) above. The interior points' and dual scaling's factors
// of X, Z and their step tests.
bool factor_lower(const Eigen::MatrixXd& A, Eigen::MatrixXd& L);

// L⁻¹ for a lower-triangular L with a real positive diagonal (a Cholesky factor, n × n, upper
// triangle ignored), written into inverse (n × n, lower triangular, upper part zero), by
// recursive 2 × 2 blocking: matrix products above 24 × 24 blocks (8 × 8 complex); below, real
// blocks on padded fixed-size copies (every column at once), complex ones by forward substitution.
void invert_lower_factor(const Eigen::MatrixXd& L, Eigen::MatrixXd& inverse);
void invert_lower_factor(const Eigen::MatrixXcd& L, Eigen::MatrixXcd& inverse);

// W = Gᴴ G for a lower-triangular G (n × n, zeros above the diagonal, as invert_lower_factor
// writes), into W (n × n, both triangles): Z⁻¹ = Lz⁻ᴴ Lz⁻¹ from Lz⁻¹. Recursive 2 × 2 blocking
// above 32 × 32, about n³/3 multiply-adds instead of n³.
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

class StepLength {
 public:
  explicit StepLength(int n);

  // min(1, τ·α_max) for P + αΔ, Δ a full symmetric n × n matrix. L is P's Cholesky factor
  // (lower triangle), inverse its L⁻¹ (only read for n ≤ kInverseLanczosMaxSize). With τ < 1 the result is confirmed by a Cholesky test
  // of P + αΔ (α shrunk by 0.7 until it passes; 0 when 30 tries fail).
  double full(const Eigen::MatrixXd& P, const Eigen::MatrixXd& L, const Eigen::MatrixXd& inverse,
              const Eigen::MatrixXd& delta, double tau);

  // The same for a block-diagonal Δ = blkdiag(D), D the d × d diagonal blocks stacked (n × d).
  double block_diagonal(const Eigen::MatrixXd& P, const Eigen::MatrixXd& L, const Eigen::MatrixXd& inverse,
                        const Eigen::MatrixXd& D, int d, double tau);

  // After a call with τ < 1 that returned α > 0: swaps P + αΔ, the matrix its Cholesky test passed,
  // into `next` and that test's factor into the lower triangle of `next_factor` (both n × n). The
  // interior point takes its next iterate and its factor from here instead of factoring it again.
  void take_tested(Eigen::MatrixXd& next, Eigen::MatrixXd& next_factor);

 private:
  double from_min_eigenvalue_of_B(double tau);  // B_ is set: tridiagonalise, bound λ_min from below
  // True when the step for P (n × n) and τ is a Lanczos estimate rather than the exact bound.
  static bool estimated(Eigen::Index n, double tau) {
    return n > kExactStepMaxSize || (tau >= 1.0 && n >= kPredictorLanczosMinSize);
  }
  // Shrinks α by 0.7 until P + αΔ, which form_trial(α) writes into trial_, has a Cholesky
  // factorisation (at most 30 tries, then 0).
  template <class FormTrial>
  double shrink_until_positive(double alpha, FormTrial form_trial) {
    return shrink_until_passes(alpha, [&](double a) {
      form_trial(a);
      return positive_definite();
    });
  }
  bool positive_definite();  // Cholesky test of trial_

  Eigen::MatrixXd G_;      // L⁻¹ Δ, n × n
  Eigen::MatrixXd B_;      // L⁻¹ Δ L⁻ᵀ, n × n (the in-place tridiagonalisation, n > 64, overwrites it)
  Eigen::MatrixXd trial_;         // P + αΔ for the Cholesky test, n × n
  Eigen::MatrixXd trial_factor_;  // its factor in the lower triangle (cholesky_lower, or Eigen's
                                  // blocked kernel above kExactStepMaxSize), n × n
  Eigen::VectorXd diagonal_, subdiagonal_, work_;  // tridiagonal form of B (n, n − 1) and scratch (2n)
};

}  // namespace fact::sdp::detail
