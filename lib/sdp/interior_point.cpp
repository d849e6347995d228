// Primal–dual interior point for  min ⟨C,X⟩  s.t.  X_ii = I_d,  X ⪰ 0.
//
// Feasible start (X = I, Λ = −s·I so Z = C + s·I ≻ 0, cold_start_shift; or a handed-off iterate to
// resume from, or interior_start's point near a low-rank factor), HKM search direction, Mehrotra
// predictor–corrector. Because both residuals stay zero, ΔZ = −Aᵀ(Δy)
// is block diagonal, which keeps every product with ΔZ at O(n² d).
//
// Constraints p = (block i, a ≤ b) pick entries (u, v) = (d·i+a, d·i+b):
//   diagonal (u = v):   A_p = e_u e_uᵀ,              b_p = 1
//   off-diagonal:       A_p = e_u e_vᵀ + e_v e_uᵀ,   b_p = 0
// so Aᵀ(y) = blkdiag(Λ) with Λ entries equal to the y_p, and A(W)_p = W_uv (+ W_vu).
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

#include "internal.h"
#include "step_length.h"

namespace fact::sdp::detail {

std::vector<Entry> constraint_entries(int n, int d) {
  std::vector<Entry> entries;
  for (int i = 0; i < n; i += d)
    for (int a = 0; a < d; ++a)
      for (int b = a; b < d; ++b) entries.push_back({i + a, i + b});
  return entries;
}

void lambda_from_y(const Eigen::VectorXd& y, const std::vector<Entry>& entries, int d, Eigen::MatrixXd& lambda) {
  for (std::size_t p = 0; p < entries.size(); ++p) {
    const auto [u, v] = entries[p];
    lambda(u, v % d) = y[p];
    lambda(v, u % d) = y[p];
  }
}

double mehrotra_centring(double mu_aff, double mu, int exponent) {
  const double ratio = mu_aff / mu;
  if (!(ratio > 0)) return 0.0;  // negative by rounding, or NaN
  double sigma = ratio;
  for (int k = 1; k < exponent; ++k) sigma *= ratio;
  return std::min(1.0, sigma);
}

// For A_p = Σ e_α e_βᵀ over its entry pairs: tr(e_α e_βᵀ X e_γ e_δᵀ W) = X_βγ W_δα, X read as X_γβ
// (symmetric): down a column as q runs, like W, rather than along a row, whose entries lie n apart
// (random full rank N = 64 2 % faster; the same iterates).
void schur_complement(const Eigen::MatrixXd& X, const Eigen::MatrixXd& W, const std::vector<Entry>& entries,
                      Eigen::MatrixXd& M) {
  const int m = static_cast<int>(entries.size());
  for (int p = 0; p < m; ++p) {
    const auto [u, v] = entries[p];
    for (int q = p; q < m; ++q) {
      const auto [s, t] = entries[q];
      double value;
      if (u == v && s == t) {
        value = X(s, u) * W(s, u);
      } else if (u == v) {  // A_q has (s,t) and (t,s)
        value = X(s, u) * W(t, u) + X(t, u) * W(s, u);
      } else if (s == t) {  // A_p has (u,v) and (v,u)
        value = X(s, v) * W(s, u) + X(s, u) * W(s, v);
      } else {
        value = X(s, v) * W(t, u) + X(t, v) * W(s, u) + X(s, u) * W(t, v) + X(t, u) * W(s, v);
      }
      M(p, q) = M(q, p) = value;
    }
  }
}

namespace {

// A(P W) for P n × n and W = Z⁻¹ (symmetric): only the d × d diagonal blocks of P W are formed,
// O(n² d), through (P W)_uv = Σ_k P_uk W_vk summed down the columns of P and W. (Along P's rows,
// whose entries lie n apart, it took 24 µs at n = 128 against 11 µs this way: at n = 128 a row's
// entries share cache sets, as in for_each_entry_below_diagonal.) sums (n × d) is scratch: column 0
// gets (P W)_uu, column 1 (d = 2, even u) (P W)_{u,u+1} + (P W)_{u+1,u}.
void apply_A_to_product(const Eigen::MatrixXd& P, const Eigen::MatrixXd& W, const std::vector<Entry>& entries, int d,
                        Eigen::MatrixXd& sums, Eigen::VectorXd& out) {
  const Eigen::Index n = P.rows();
  sums.setZero();
  for (Eigen::Index k = 0; k < n; ++k) {
    const double* p = P.col(k).data();
    const double* w = W.col(k).data();
    double* diagonal = sums.col(0).data();
    for (Eigen::Index u = 0; u < n; ++u) diagonal[u] += p[u] * w[u];
    if (d == 2) {
      double* mates = sums.col(1).data();
      for (Eigen::Index u = 0; u + 1 < n; u += 2) mates[u] += p[u] * w[u + 1] + p[u + 1] * w[u];
    }
  }
  for (std::size_t q = 0; q < entries.size(); ++q) {
    const auto [u, v] = entries[q];
    out[q] = u == v ? sums(u, 0) : sums(u, 1);
  }
}

// Every n × n, m × m and n × d matrix of one interior-point iteration, allocated once.
// n = matrix size, m = number of constraints, d = block size.
struct Workspace {
  Workspace(int n, int m, int d)
      : Lx(n, n), Lz(n, n), chol_m(m), Lz_inv(n, n), W(n, n), M(m, m), P(n, n), dx_aff(n, n),
        dx(n, n), PLt(n, n), dz_aff(n, d), dz(n, d), block_sums(n, d), rhs(m), dy_aff(m), dy(m), primal_steps(n),
        dual_steps(n) {}
  Eigen::MatrixXd Lx, Lz;                      // X = Lx Lxᵀ, Z = Lz Lzᵀ in the lower triangles (n × n;
                                               // Lx only at the first iteration up to kGridStepMaxSize rows)
  SpdSolver chol_m;                            // the Schur complement's factorisation (m × m)
  Eigen::MatrixXd Lx_inv, Lz_inv;              // Lx⁻¹ (sized and formed only when the step lengths
                                               // read it), Lz⁻¹ (n × n, lower triangular)
  Eigen::MatrixXd W;                           // Z⁻¹ = Lz⁻ᵀ Lz⁻¹ (n × n)
  Eigen::MatrixXd M;                           // Schur complement (m × m)
  Eigen::MatrixXd P;                           // scratch n × n product, multiplied by W
  Eigen::MatrixXd dx_aff, dx;                  // predictor / corrector primal directions (n × n)
  Eigen::MatrixXd PLt;                         // P Lz⁻ᵀ for the accurate primal direction (n × n)
  Eigen::MatrixXd dz_aff, dz;                  // dual directions ΔZ = −Aᵀ(Δy), diagonal blocks stacked (n × d)
  Eigen::MatrixXd block_sums;                  // apply_A_to_product's scratch (n × d)
  Eigen::VectorXd rhs, dy_aff, dy;             // Schur right-hand side and dual directions (m)
  StepLength primal_steps, dual_steps;         // step lengths for X and Z; their last Cholesky tests
                                               // factor the next X and Z (take_tested)
};

// The HKM primal direction ΔX = sym(σμW − X − P W) for the P already in ws.P (n × n). With
// `accurate`, P W is formed as (P Lz⁻ᵀ) Lz⁻¹ (one more n × n product): near the optimum W's
// entries grow as 1/μ and P W cancels to O(1), and the product with W loses the digits the last
// iterations need (the gap stalled at 1e-7 on the noise-free plain form, N = 8, whose optimum
// is 0, and at 1e-8 on plain_noisy N = 5 and 8); through the factor the intermediate grows only as 1/√μ.
void primal_direction(const Eigen::MatrixXd& X, double sigma_mu, bool accurate, Workspace& ws, Eigen::MatrixXd& dx) {
  if (accurate) {
    ws.PLt.noalias() = ws.P * ws.Lz_inv.transpose();  // P Lz⁻ᵀ
    dx.noalias() = -ws.PLt * ws.Lz_inv;
  } else {
    dx.noalias() = -ws.P * ws.W;
  }
  dx -= X;
  if (sigma_mu != 0) dx += sigma_mu * ws.W;
  symmetrize(dx);
}

// ⟨X + a ΔX, Z + b ΔZ⟩ with ΔZ = blkdiag(dz): the complementarity after a step.
double complementarity_after(const Eigen::MatrixXd& X, const Eigen::MatrixXd& dx, double a, const Eigen::MatrixXd& Z,
                             const Eigen::MatrixXd& dz, double b, int d) {
  double value = X.cwiseProduct(Z).sum() + a * dx.cwiseProduct(Z).sum();
  for (Eigen::Index i = 0; i < X.rows(); i += d) {
    const auto block = dz.middleRows(i, d).leftCols(d);
    value += b * (X.block(i, i, d, d) + a * dx.block(i, i, d, d)).cwiseProduct(block).sum();
  }
  return value;
}

// The real interior point's centring exponent (mehrotra_centring): 2 up to kSquareCentringMaxSize
// rows (N = 24), the usual 3 above. Sweep (6 seeds, N = 5 … 32, two runs), 2 against 3: plain /
// low rank / random full rank / the paper's cost 0.85–0.97 of the time at N = 5 … 16 and
// 0.95–1.01 at N = 24, no status changes (8 seeds, when taken: 0.90–0.97 at N = 5 … 8); 1, 1.5
// and SDPT3's max(1, 3·min(α_p, α_d)²) did about as well, 2.5 gained less, 4 and 6 lost. Above 48
// rows (N = 40, 56, 64; 10 seeds) 2 measured 0.95–1.14 with single instances to 1.57×, and on the
// complex interior point 0.94–1.05 with outliers to 1.64× (BENCHMARKS.md, session 28).
constexpr int kSquareCentringMaxSize = 48;
int centring_exponent(int n) { return n <= kSquareCentringMaxSize ? 2 : 3; }

// The predictor's step lengths only set the centring σ (through μ_aff). After a run's first
// iteration they are not searched but taken as this fraction of the last corrector's (for X and
// for Z apart): on the grid the predictor's step was mostly 0.7 where the corrector's was 0.95,
// and its search cost two or more Cholesky tests of each of X and Z an iteration (a sixth of an
// iteration at n = 24). Sweep (4 seeds; the plain form and the paper's cost with 2N and 3N rounds
// at noise 0.002 … 0.1, random C of rank 3, N + 1 and full; N = 5 … 24; fastest of two runs each
// side, interleaved): 0.85–0.94 of the time wherever the interior point runs, iterations within
// ±2 % by row (one random full-rank N = 24 instance 23 → 29), the other rows 0.99–1.01, no status
// or objective changed; 0.65 and 0.85 took 0.96–1.03 and 1.00–1.10 of 0.75's time
// (BENCHMARKS.md, session 50).
constexpr double kAffineStepFraction = 0.75;

}  // namespace

InteriorPointOutcome solve_interior_point(const Eigen::MatrixXd& C, int d, const Options& options, double handoff_gap,
                                          const InteriorPointOutcome* resume) {
  const int n = static_cast<int>(C.rows());
  const auto entries = constraint_entries(n, d);
  const int m = static_cast<int>(entries.size());
  Eigen::VectorXd b(m);  // right-hand side of A(X) = b
  for (int p = 0; p < m; ++p) b[p] = entries[p].u == entries[p].v ? 1.0 : 0.0;

  InteriorPointOutcome out;
  Workspace ws(n, m, d);
  const bool invert_x = step_length_reads_inverse(n);  // L⁻¹ of X: only the step lengths use it
  Eigen::MatrixXd X = Eigen::MatrixXd::Identity(n, n);  // primal, n × n
  Eigen::VectorXd y(m);                                  // dual, m
  if (resume) {
    X = resume->X;
    for (int p = 0; p < m; ++p) y[p] = resume->lambda(entries[p].u, entries[p].v % d);
  } else {
    y = -cold_start_shift(C) * b;
  }
  Eigen::MatrixXd lambda(n, d);                          // Aᵀ(y) as stacked d × d blocks, n × d
  lambda_from_y(y, entries, d, lambda);
  Eigen::MatrixXd Z(n, n);                               // dual slack C − Aᵀ(y), n × n
  certificate_matrix(C, lambda, d, Z);
  const double tau = 0.95;

  // The iterate with the smallest gap so far (GapRule): the polish in solve.cpp starts from it.
  GapRule rule(options.gap_tol, handoff_gap);
  Eigen::MatrixXd best_X = X;  // n × n
  Eigen::VectorXd best_y = y;  // m
  const int done = resume ? resume->iterations : 0;  // iterations the resumed run already took
  // X and Z are factored at the first iteration only: after it ws.Lx and ws.Lz are the factors the
  // corrector's step-length tests computed for the step taken (take_tested), or still those of X
  // and Z when a step length is 0: two n × n factorisations fewer per iteration. Up to
  // kGridStepMaxSize rows nothing reads Lx after the first iteration's test of X, and the next X
  // is not factored at all (StepLength::full's factor_next: X + αΔX ≻ 0 follows from the test of
  // X + (α/τ)ΔX), a third of the primal step's Cholesky tests: random C of full rank and the
  // paper's cost at N = 5 … 24 0.955–0.99 of the time, iterations identical (BENCHMARKS.md,
  // session 50).
  const bool keep_lx = n > kGridStepMaxSize;
  // Up to kSweepInverseMaxSize rows W = Z⁻¹ comes from Z itself by inverse_by_sweeps, except for
  // the `accurate` direction, which reads Lz⁻¹: the dual's next Z is then not factored either
  // (Z + αΔZ ≻ 0 follows from the test at α/τ, as for X), and Lz is formed only when an
  // `accurate` iteration needs it (below the hand-off gap: in automatic mode only when the
  // interior point resumes). Sweep (4 seeds, N = 5 … 24, six real kinds, noise 0.002 … 0.1): random
  // full rank 0.94–0.96 of the time at N = 7 … 16 (N = 20 / 24, n > 32, unchanged), 0.98 in all,
  // one iteration more over 540 instances, no status or objective changed; in-process N = 8 / 12
  // 79.6 / 170 → 76.7 / 163 µs (BENCHMARKS.md, session 51).
  const bool sweep_inverse = n <= kSweepInverseMaxSize;
  bool z_factored = false;  // ws.Lz holds Z's factor
  bool factored = false;
  double last_ap = 0, last_ad = 0;  // the last corrector's step lengths (kAffineStepFraction)
  for (int it = done; it < options.max_ipm_iterations; ++it) {
    out.iterations = it + 1 - done;
    const double primal = (C.cwiseProduct(X)).sum(), dual = b.dot(y);
    const double gap = X.cwiseProduct(Z).sum();
    const double rel_gap = relative_gap(gap, primal, dual);
    bool improved = false;
    const GapRule::Verdict verdict = rule.next(gap, rel_gap, improved);
    if (improved) {
      best_X = X;
      best_y = y;
    }
    if (rule.stops(verdict, "interior point", it + 1, out)) break;
    const double mu = gap / n;
    const bool accurate = rel_gap < kAccurateDirectionGap;
    const bool by_sweeps = sweep_inverse && !accurate;  // W from Z, Lz not needed
    if (!factored && !factor_lower(X, ws.Lx)) {
      out.reason = "interior point lost positive definiteness at iteration " + std::to_string(it);
      break;
    }
    factored = true;
    if (by_sweeps ? !inverse_by_sweeps(Z, 0.0, ws.W) : !z_factored && !factor_lower(Z, ws.Lz)) {
      out.reason = "interior point lost positive definiteness at iteration " + std::to_string(it);
      break;
    }
    if (!by_sweeps) {
      z_factored = true;
      invert_lower_factor(ws.Lz, ws.Lz_inv);
      gram_of_lower_factor(ws.Lz_inv, ws.W);             // Z⁻¹ = Lz⁻ᵀ Lz⁻¹
    }
    if (invert_x) invert_lower_factor(ws.Lx, ws.Lx_inv);
    schur_complement(X, ws.W, entries, ws.M);
    if (!ws.chol_m.factor(ws.M)) {
      out.reason = "Schur complement not positive definite at iteration " + std::to_string(it);
      break;
    }
    // Predictor (σ = 0): T = −X, M Δy = A(X) = b; ΔX = −X − X ΔZ W.
    ws.chol_m.solve(b, ws.dy_aff);
    lambda_from_y(ws.dy_aff, entries, d, ws.dz_aff);
    ws.dz_aff = -ws.dz_aff;  // ΔZ = −Aᵀ(Δy), stacked blocks
    times_block_diagonal(X, ws.dz_aff, d, ws.P);  // X ΔZ
    primal_direction(X, 0.0, accurate, ws, ws.dx_aff);
    const bool searched = it == done;  // the run's first iteration (kAffineStepFraction)
    const double ap_aff = searched ? ws.primal_steps.full(X, ws.Lx, ws.Lx_inv, ws.dx_aff, 1.0)
                                   : std::min(1.0, kAffineStepFraction * last_ap);
    const double ad_aff = searched ? ws.dual_steps.block_diagonal(Z, ws.Lz, ws.Lz_inv, ws.dz_aff, d, 1.0)
                                   : std::min(1.0, kAffineStepFraction * last_ad);
    const double mu_aff = complementarity_after(X, ws.dx_aff, ap_aff, Z, ws.dz_aff, ad_aff, d) / n;
    const double sigma = mehrotra_centring(mu_aff, mu, centring_exponent(n));
    // Corrector: T = σμW − X − ΔX_a ΔZ_a W, M Δy = −A(T); ΔX = T − X ΔZ W.
    // A(T) needs only T's diagonal blocks: A(σμW − X) − A((ΔX_a ΔZ_a) W).
    times_block_diagonal(ws.dx_aff, ws.dz_aff, d, ws.P);  // ΔX_a ΔZ_a
    apply_A_to_product(ws.P, ws.W, entries, d, ws.block_sums, ws.rhs);
    for (int p = 0; p < m; ++p) {
      const auto [u, v] = entries[p];
      const double t_uv = sigma * mu * ws.W(u, v) - X(u, v);
      ws.rhs[p] -= u == v ? t_uv : 2.0 * t_uv;  // rhs = −A(T)
    }
    ws.chol_m.solve(ws.rhs, ws.dy);
    lambda_from_y(ws.dy, entries, d, ws.dz);
    ws.dz = -ws.dz;
    // ΔX = σμW − X − (ΔX_a ΔZ_a + X ΔZ) W: one n × n product with W.
    times_block_diagonal(X, ws.dz, d, ws.dx);  // X ΔZ, through dx as scratch
    ws.P += ws.dx;
    primal_direction(X, sigma * mu, accurate, ws, ws.dx);
    const double ap = ws.primal_steps.full(X, ws.Lx, ws.Lx_inv, ws.dx, tau, keep_lx);
    const double ad = ws.dual_steps.block_diagonal(Z, ws.Lz, ws.Lz_inv, ws.dz, d, tau, !sweep_inverse);
    last_ap = ap;
    last_ad = ad;
    if (ap == 0.0 && ad == 0.0) {
      out.reason = "interior point stalled at iteration " + std::to_string(it);
      break;
    }
    // X + αΔX and Z + αΔZ exactly as their tests factored them. Z is updated by its step, not
    // formed again as C − Aᵀ(y): the two differ by rounding, a few ε of Z's diagonal blocks.
    if (ap > 0) keep_lx ? ws.primal_steps.take_tested(X, ws.Lx) : ws.primal_steps.take_trial(X);
    if (ad > 0) {
      y += ad * ws.dy;
      if (sweep_inverse) {
        ws.dual_steps.take_trial(Z);
        z_factored = false;
      } else {
        ws.dual_steps.take_tested(Z, ws.Lz);
      }
    }
  }
  X = best_X;
  lambda_from_y(best_y, entries, d, lambda);
  unit_diagonal_blocks(X, d);  // undo rounding drift
  if (!out.converged && out.reason.empty())
    out.reason = "interior point reached " + std::to_string(options.max_ipm_iterations) + " iterations";
  out.X = X;
  out.lambda = lambda;
  return out;
}

namespace {

// A^{-1/2} for a symmetric positive definite 2 × 2 A = [[a, b], [b, c]] in closed form: with
// s = √det A and t = √(a + c + 2s), A^{1/2} = (A + sI)/t, and since det(A + sI) = s·t²,
// A^{-1/2} = [[c + s, −b], [−b, a + s]] / (s·t). False (R untouched) when A is not positive
// definite or not finite.
bool inverse_sqrt_2x2(double a, double b, double c, Eigen::Matrix2d& R) {
  const double det = a * c - b * b;
  if (!(a > 0 && det > 0 && det <= std::numeric_limits<double>::max() && a + c <= std::numeric_limits<double>::max()))
    return false;
  const double s = std::sqrt(det), t = std::sqrt(a + c + 2 * s), scale = 1.0 / (s * t);
  R << (c + s) * scale, -b * scale, -b * scale, (a + s) * scale;
  return true;
}

}  // namespace

// d = 2 by inverse_sqrt_2x2 on each block, applied to its two rows and columns in place; d = 1
// by 1/√x. Eigen's solver on each block (a dynamic 2 × 2 decomposition and two products with
// temporaries) took 2.8 % of random full rank N = 8 (BENCHMARKS.md, session 51); it stays for a
// block that is not positive definite, where its result (NaN or inf entries) is kept.
void unit_diagonal_blocks(Eigen::MatrixXd& X, int d) {
  const Eigen::Index n = X.rows();
  for (Eigen::Index i = 0; i < n; i += d) {
    if (d == 1) {
      const double root = 1.0 / std::sqrt(X(i, i));
      X.row(i) *= root;
      X.col(i) *= root;
      continue;
    }
    Eigen::Matrix2d R;  // X_ii^{-1/2}
    if (!inverse_sqrt_2x2(X(i, i), X(i + 1, i), X(i + 1, i + 1), R)) {  // (the lower triangle, as Eigen reads)
      R = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(X.block(i, i, d, d)).operatorInverseSqrt();
    }
    for (Eigen::Index j = 0; j < n; ++j) {  // rows i, i + 1 ← R · them
      const double u = X(i, j), v = X(i + 1, j);
      X(i, j) = R(0, 0) * u + R(0, 1) * v;
      X(i + 1, j) = R(1, 0) * u + R(1, 1) * v;
    }
    for (Eigen::Index j = 0; j < n; ++j) {  // columns i, i + 1 ← them · R
      const double u = X(j, i), v = X(j, i + 1);
      X(j, i) = u * R(0, 0) + v * R(1, 0);
      X(j, i + 1) = u * R(0, 1) + v * R(1, 1);
    }
  }
}

// The cold start's dual shift s (Λ = −s·I, Z = C + s·I) for C scaled to ‖C‖_F = 1. C's eigenvalues
// then have root mean square 1/√n, and s = 1/√n starts Z on C's own scale: s = 2 (Z dominated by
// the shift, μ₀ ≈ 2) spent the first iterations bringing μ down to it. Sweep (4 seeds, N = 25 … 64,
// cold start): random full rank 0.91–0.97 of the time, the paper's cost with 2N rounds 0.91–0.95,
// the other kinds 0.98–1.01, no status changes; N = 100 / 200 random full rank 22.2 → 20.9 ms,
// 141 → 128 ms (BENCHMARKS.md, session 27). C need not be PSD: s is taken only when C + (s/2)·I
// passes a Cholesky test, so that λ_min(Z) ≥ s/2 (a Z that only just passed, λ_min(C) at −s, left
// the interior point stalled at a gap of 1e-4 … 1e-2 from a nearly singular start: review, session
// 27); otherwise s = 2, which |λ(C)| ≤ ‖C‖_F = 1 keeps positive definite.
double cold_start_shift(const Eigen::MatrixXd& C) {
  const double shift = 1.0 / std::sqrt(static_cast<double>(C.rows()));
  return positive_definite_when_shifted(C, 0.5 * shift) ? shift : 2.0;
}

namespace {

// Λ = −shift·I as d × d blocks stacked (n × d): the dual of the cold and near-zero starts.
Eigen::MatrixXd shifted_multipliers(Eigen::Index n, int d, double shift) {
  Eigen::MatrixXd lambda = Eigen::MatrixXd::Zero(n, d);
  for (Eigen::Index i = 0; i < n; i += d) lambda.middleRows(i, d).diagonal().setConstant(-shift);
  return lambda;
}

}  // namespace

Eigen::MatrixXd cold_start_lambda(const Eigen::MatrixXd& C, int d) {
  return shifted_multipliers(C.rows(), d, cold_start_shift(C));
}

bool near_zero_start(const Eigen::MatrixXd& C, int d, InteriorPointOutcome& start) {
  const Eigen::Index n = C.rows();
  if (!positive_definite_when_shifted(C, 0.5 * kNearZeroShift)) return false;
  Eigen::MatrixXd Z = C;  // C + s·I (n × n)
  Z.diagonal().array() += kNearZeroShift;
  Eigen::MatrixXd L(n, n), L_inv(n, n);  // Z = L Lᵀ and L⁻¹ (n × n, lower triangular)
  if (!factor_lower(Z, L)) return false;
  invert_lower_factor(L, L_inv);
  gram_of_lower_factor(L_inv, start.X);  // Z⁻¹ = L⁻ᵀ L⁻¹
  unit_diagonal_blocks(start.X, d);      // D Z⁻¹ D, identity blocks
  start.lambda = shifted_multipliers(n, d, kNearZeroShift);
  start.iterations = 0;
  return true;
}

bool interior_start(const Eigen::MatrixXd& C, int d, const Eigen::MatrixXd& Y, const Eigen::MatrixXd& lambda,
                    double mix, InteriorPointOutcome& start) {
  const Eigen::Index n = C.rows();
  const Eigen::MatrixXd S = certificate_matrix(C, lambda, d);  // C − Λ (n × n)
  for (double shift = 1e-3; shift <= 1.0; shift *= 10) {
    if (!positive_definite_when_shifted(S, shift)) continue;
    start.X.noalias() = (1.0 - mix) * (Y * Y.transpose());
    start.X.diagonal().array() += mix;
    start.lambda = lambda;
    for (Eigen::Index i = 0; i < n; i += d) start.lambda.middleRows(i, d).diagonal().array() -= shift;
    start.iterations = 0;
    return true;
  }
  return false;
}

}  // namespace fact::sdp::detail
