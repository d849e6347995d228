// Primal–dual interior point for the complex form:  min Re tr(H X)  s.t.  X_ii = 1,  X ⪰ 0,
// X Hermitian N × N (H Hermitian N × N, the scaled C = emb(H)). Its dual is  max Σ y_i  s.t.
// Z = H − diag(y) ⪰ 0, y real. The d = 2 problem on emb(H) has the same optimum at emb(X) with
// Λ_ii = y_i I₂, so this is the same relaxation in N×N complex arithmetic instead of 2N × 2N real
// with 3N constraints: the Schur complement is N × N, against 3N × 3N.
//
// Feasible start (X = I, y = −2·1, Z = H + 2I ≻ 0 since ‖H‖_F = ‖C‖_F/√2 < 1), a warm start
// from a low-rank factor (complex_interior_start) or a handed-off iterate to resume from, HKM direction,
// Mehrotra predictor–corrector. With A(X)_i = Re X_ii and Aᵀ(y) = diag(y), ΔZ = −diag(Δy) is
// diagonal, and the Schur complement of the HKM direction is M_ij = Re(X_ij conj(W_ij)) (N × N
// real symmetric), W = Z⁻¹ (N × N Hermitian). Step lengths come from a Lanczos estimate of the boundary,
// confirmed by a Cholesky test (the real path's exact Sturm bracketing has no complex version).
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "complex_product.h"
#include "internal.h"
#include "step_length.h"

namespace fact::sdp::detail {
namespace {

using Eigen::MatrixXcd;
using Eigen::MatrixXd;
using Eigen::VectorXd;

// A = L Lᴴ for a Hermitian A (N × N), into the lower triangle of L (cholesky_in_place).
struct ComplexCholesky {
  explicit ComplexCholesky(Eigen::Index N) : L(N, N) {}
  // False when A is not positive definite.
  bool compute(const MatrixXcd& A) {
    L = A;
    return cholesky_in_place(L);
  }
  Eigen::TriangularView<const MatrixXcd, Eigen::Lower> lower() const { return L.triangularView<Eigen::Lower>(); }
  MatrixXcd L;  // N × N: the factor in the lower triangle, the upper triangle unused
};

// Every matrix of one iteration, allocated once (N × N complex unless noted).
struct Workspace {
  explicit Workspace(Eigen::Index N)
      : chol_x(N), chol_z(N), next_x(N), next_z(N), Lx_inv(N, N), Lz_inv(N, N), W(N, N), M(N, N), chol_m(N), P(N, N), dx_aff(N, N), dx(N, N),
        trial(N, N), PZ(N, N), u(N), u_x(N), u_y(N), ones(VectorXd::Ones(N)), rhs(N), dy_aff(N), dy(N) {}
  ComplexCholesky chol_x, chol_z;        // X = Lx Lxᴴ, Z = Lz Lzᴴ
  ComplexCholesky next_x, next_z;        // Cholesky tests of the corrector's X + αΔX, Z + αΔZ: the
                                         // next iteration's chol_x, chol_z once the step is taken
  MatrixXcd Lx_inv;                      // Lx⁻¹ (lower triangular), up to kExplicitLxMaxSize
  MatrixXcd Lz_inv;                      // Lz⁻¹ (lower triangular)
  MatrixXcd W;                           // Z⁻¹
  MatrixXd M;                            // Schur complement, N × N real
  SpdSolver chol_m;  // the Schur complement M (N × N real) factored
  MatrixXcd P;                           // scratch product, multiplied by Z⁻¹ (primal_direction)
  MatrixXcd dx_aff, dx;                  // predictor / corrector primal directions
  MatrixXcd trial;                       // X + αΔX or Z + αΔZ for the Cholesky test
  MatrixXcd PZ;                          // P Lz⁻ᴴ (accurate primal_direction)
  Eigen::VectorXcd u, u_x;               // Lanczos scratch vectors, N
  VectorXd u_y;                          // y + αΔy of a dual trial, N
  VectorXd ones, rhs, dy_aff, dy;        // b = A(X) = 1, Schur right-hand side, dual directions (N)
};

// Lanczos steps of the step-length estimate, predictor and corrector alike. The corrector's step
// is confirmed by a Cholesky test, which shrinks it when 8 steps overestimate λ_min; with 24 the
// iterations on tight_noisy N = 32 … 200 were the same and the interior point took 12–30 % longer
// (BENCHMARKS.md, sessions 12 and 13).
constexpr int kLanczosSteps = 8;
// The predictor's step lengths only set σ = (μ_aff/μ)³, and nothing is factored at them: 4
// Lanczos steps are enough (tight_noisy N = 24 … 100: the same iterations, 4–8 % less time
// than with 8; BENCHMARKS.md, session 16).
constexpr int kPredictorLanczosSteps = 4;

// The predictor (τ = 1) and the corrector (τ < 1) take different numbers of Lanczos steps.
int lanczos_steps(double tau) { return tau >= 1.0 ? kPredictorLanczosSteps : kLanczosSteps; }

// min(1, τ·α_max) for P + α Δ ⪰ 0 (P = L Lᴴ): α_max = −1/λ_min(L⁻¹ Δ L⁻ᴴ), where `lowest` is
// Lanczos's estimate of that λ_min. With τ < 1 the step is confirmed by a Cholesky test of
// P + αΔ (form_trial(α) writes it into ws.trial), α shrunk by 0.7 until it passes; `next` then
// holds the factor of P + αΔ.
template <class FormTrial>
double step_length(double lowest, double tau, Workspace& ws, ComplexCholesky& next, FormTrial form_trial) {
  double alpha = lowest >= 0 ? 1.0 : std::min(1.0, -tau / lowest);
  if (tau >= 1.0) return alpha;  // the predictor's step only sets σ
  return shrink_until_passes(alpha, [&](double a) {
    form_trial(a);
    return next.compute(ws.trial);
  });
}

// Up to this N the primal step's Lanczos multiplies by an explicit Lx⁻¹ (inverted once an
// iteration, for the predictor's and the corrector's 4 + 8 steps) instead of solving with Lx: a
// pair of Eigen's complex triangular solves takes 1.2 / 2.7 / 4.6 µs at N = 32 / 64 / 100, the two
// products 0.24 / 1.1 / 2.7 µs, and the inversion 2.3 / ≈ 10 / 37 µs (BENCHMARKS.md, session 26).
constexpr Eigen::Index kExplicitLxMaxSize = 64;

// The step for X + α ΔX; Lanczos on Lx⁻¹ ΔX Lx⁻ᴴ, through ws.Lx_inv up to kExplicitLxMaxSize and
// through triangular solves with X's factor above.
double primal_step(const MatrixXcd& X, const MatrixXcd& dx, Workspace& ws, double tau) {
  const auto L = ws.chol_x.lower();
  const bool explicit_inverse = X.rows() <= kExplicitLxMaxSize;
  const double lowest = lanczos_lowest<Eigen::VectorXcd>(X.rows(), lanczos_steps(tau), [&](const Eigen::VectorXcd& v, Eigen::VectorXcd& w) {
    if (explicit_inverse) {
      ws.u.noalias() = ws.Lx_inv.adjoint() * v;  // Lx⁻ᴴ v
      ws.u_x.noalias() = dx * ws.u;
      w.noalias() = ws.Lx_inv * ws.u_x;          // Lx⁻¹ ΔX Lx⁻ᴴ v
      return;
    }
    ws.u = L.adjoint().solve(v);  // Lx⁻ᴴ v
    w.noalias() = dx * ws.u;
    L.solveInPlace(w);  // Lx⁻¹ ΔX Lx⁻ᴴ v
  });
  return step_length(lowest, tau, ws, ws.next_x, [&](double a) { ws.trial = X + a * dx; });
}

// Z's diagonal from y: Z_ii = H_ii − y_i (the rest of Z is H's). The start, the dual step's trials
// and the update all go through it, so a step taken is bit for bit the trial that was factored.
void set_slack_diagonal(const MatrixXcd& H, const VectorXd& y, MatrixXcd& Z) {
  Z.diagonal() = H.diagonal() - y.cast<std::complex<double>>();
}

// The step for Z + α ΔZ with ΔZ = −diag(Δy), Z = H − diag(y); the trial is H − diag(y + α Δy).
// Lanczos on Lz⁻¹ ΔZ Lz⁻ᴴ through the explicit Lz⁻¹ (dual_step_operator).
double dual_step(const MatrixXcd& Z, const MatrixXcd& H, const VectorXd& y, const VectorXd& dy, Workspace& ws, double tau) {
  const double lowest = lanczos_lowest<Eigen::VectorXcd>(Z.rows(), lanczos_steps(tau), [&](const Eigen::VectorXcd& v, Eigen::VectorXcd& w) {
    dual_step_operator(ws.Lz_inv, dy, v, ws.u, w);
  });
  return step_length(lowest, tau, ws, ws.next_z, [&](double a) {
    ws.trial = Z;
    ws.u_y = y + a * dy;
    set_slack_diagonal(H, ws.u_y, ws.trial);
  });
}

// ΔX = herm(σμW − X − P Z⁻¹) for the P already in ws.P. With `accurate`, P Z⁻¹ is formed as
// (P Lz⁻ᴴ) Lz⁻¹, one product more than P W: near the optimum W's entries grow as 1/μ and the
// product with W loses the digits the last iterations need (with it alone the gap stalls at
// 1e-7 … 1e-8 on tight_noisy); the product is cheaper before that (as in the real interior
// point, interior_point.cpp).
void primal_direction(const MatrixXcd& X, double sigma_mu, bool accurate, Workspace& ws, MatrixXcd& dx) {
  if (accurate) {
    multiply<Shape::dense, Shape::upper>(ws.P, ws.Lz_inv.adjoint(), ws.PZ, 1.0, false);  // P Lz⁻ᴴ
    multiply<Shape::dense, Shape::lower>(ws.PZ, ws.Lz_inv, dx, -1.0, false);             // −P Z⁻¹
  } else {
    multiply(ws.P, ws.W, dx, -1.0, false);
  }
  dx -= X;
  if (sigma_mu != 0) dx += sigma_mu * ws.W;
  hermitian_part(dx);
}

// Re tr((X + a ΔX)(Z + b ΔZ)) with ΔZ = −diag(dy).
double complementarity_after(const MatrixXcd& X, const MatrixXcd& dx, double a, const MatrixXcd& Z, const VectorXd& dy,
                             double b) {
  const MatrixXcd Xa = X + a * dx;
  return (Xa.array() * Z.array().conjugate()).real().sum() - b * Xa.diagonal().real().dot(dy);
}

}  // namespace

void hermitian_part(MatrixXcd& A) {
  A.diagonal() = A.diagonal().real().cast<std::complex<double>>();
  for_each_entry_below_diagonal(A.rows(), [&A](Eigen::Index i, Eigen::Index j) {
    const std::complex<double> v = 0.5 * (A(i, j) + std::conj(A(j, i)));
    A(i, j) = v;
    A(j, i) = std::conj(v);
  });
}

void rescale_to_unit_diagonal(MatrixXcd& X) {
  const VectorXd root = X.diagonal().real().cwiseSqrt().cwiseInverse();
  X = root.asDiagonal() * X * root.asDiagonal();
}

void dual_step_operator(const Eigen::MatrixXcd& Lz_inv, const Eigen::VectorXd& dy, const Eigen::VectorXcd& v,
                        Eigen::VectorXcd& u, Eigen::VectorXcd& w) {
  if (Lz_inv.rows() >= kTriangularProductMinSize) {
    u.noalias() = Lz_inv.triangularView<Eigen::Lower>().adjoint() * v;  // Lz⁻ᴴ v
    u.array() *= -dy.array();                                          // ΔZ Lz⁻ᴴ v
    w.noalias() = Lz_inv.triangularView<Eigen::Lower>() * u;           // Lz⁻¹ ΔZ Lz⁻ᴴ v
    return;
  }
  u.noalias() = Lz_inv.adjoint() * v;
  u.array() *= -dy.array();
  w.noalias() = Lz_inv * u;
}

ComplexInteriorPointOutcome solve_complex_interior_point(const Eigen::MatrixXcd& H, const Options& options,
                                                         double handoff_gap, const ComplexInteriorPointOutcome* resume) {
  const Eigen::Index N = H.rows();
  ComplexInteriorPointOutcome out;
  Workspace ws(N);
  MatrixXcd X = resume ? resume->X : MatrixXcd::Identity(N, N);  // primal, N × N Hermitian
  VectorXd y = resume ? resume->y : VectorXd::Constant(N, -2.0);  // dual, N
  MatrixXcd Z = H;                           // dual slack H − diag(y), N × N
  set_slack_diagonal(H, y, Z);
  const double tau = 0.95;
  // Converged at ⟨X, Z⟩ below gap_tol (relative), not the real interior point's 0.1·gap_tol: the
  // certificate comes from X's factor truncated at 1e-10 (solve.cpp), which drops X's small part,
  // in S's range, that makes up most of ⟨X, Z⟩. Stopped there, the certificates' gaps on
  // tight_noisy N = 32 … 200 were 7e-12 … 2.4e-11; stopped at 10·gap_tol, up to 3.8e-10
  // (BENCHMARKS.md, session 15). A certificate that misses the gap goes to the complex polish.
  GapRule rule(options.gap_tol, handoff_gap, 1.0);  // the iterate with the smallest gap so far is kept
  MatrixXcd best_X = X;
  VectorXd best_y = y;
  // X and Z are factored at the first iteration only: after it chol_x and chol_z are the factors
  // the corrector's step-length tests computed for the step taken (or still those of X and Z
  // when a step length is 0), two N × N factorisations fewer per iteration.
  bool factored = false;
  for (int it = 0; it < options.max_ipm_iterations; ++it) {
    out.iterations = it + 1;
    const double primal = (H.array() * X.array().conjugate()).real().sum(), dual = y.sum();
    const double gap = (X.array() * Z.array().conjugate()).real().sum();
    const double rel_gap = complex_relative_gap(gap, primal, dual);
    bool improved = false;
    const GapRule::Verdict verdict = rule.next(gap, rel_gap, improved);
    if (improved) {
      best_X = X;
      best_y = y;
    }
    if (rule.stops(verdict, "complex interior point", it + 1, out)) break;
    const double mu = gap / static_cast<double>(N);
    const bool accurate = rel_gap < kAccurateDirectionGap;
    if (!factored && (!ws.chol_z.compute(Z) || !ws.chol_x.compute(X))) {
      out.reason = "complex interior point lost positive definiteness at iteration " + std::to_string(it);
      break;
    }
    factored = true;
    invert_lower_factor(ws.chol_z.L, ws.Lz_inv);   // lower triangular, zeros above
    if (N <= kExplicitLxMaxSize) invert_lower_factor(ws.chol_x.L, ws.Lx_inv);
    gram_of_lower_factor(ws.Lz_inv, ws.W);          // Z⁻¹ = Lz⁻ᴴ Lz⁻¹
    ws.M = (X.array() * ws.W.array().conjugate()).real();
    if (!ws.chol_m.factor(ws.M)) {
      out.reason = "complex Schur complement not positive definite at iteration " + std::to_string(it);
      break;
    }
    // Predictor (σ = 0): M Δy = A(X) = 1; ΔX = −X − X ΔZ W with X ΔZ = −X diag(Δy).
    ws.chol_m.solve(ws.ones, ws.dy_aff);
    ws.P.noalias() = -X * ws.dy_aff.asDiagonal();
    primal_direction(X, 0.0, accurate, ws, ws.dx_aff);
    const double ap_aff = primal_step(X, ws.dx_aff, ws, 1.0);
    const double ad_aff = dual_step(Z, H, y, ws.dy_aff, ws, 1.0);
    const double mu_aff = complementarity_after(X, ws.dx_aff, ap_aff, Z, ws.dy_aff, ad_aff) / static_cast<double>(N);
    const double sigma = mehrotra_centring(mu_aff, mu, 3);
    // Corrector: T = σμW − X − ΔX_a ΔZ_a W, M Δy = −A(T); ΔX = T − X ΔZ W.
    ws.P.noalias() = -ws.dx_aff * ws.dy_aff.asDiagonal();  // ΔX_a ΔZ_a
    for (Eigen::Index i = 0; i < N; ++i) {
      const double pw_ii = ws.P.row(i).transpose().cwiseProduct(ws.W.col(i)).sum().real();  // Re (P W)_ii
      ws.rhs[i] = pw_ii - (sigma * mu * ws.W(i, i).real() - X(i, i).real());
    }
    ws.chol_m.solve(ws.rhs, ws.dy);
    ws.P.noalias() -= X * ws.dy.asDiagonal();  // + X ΔZ
    primal_direction(X, sigma * mu, accurate, ws, ws.dx);
    const double ap = primal_step(X, ws.dx, ws, tau);
    const double ad = dual_step(Z, H, y, ws.dy, ws, tau);
    if (ap == 0.0 && ad == 0.0) {
      out.reason = "complex interior point stalled at iteration " + std::to_string(it);
      break;
    }
    // Bit for bit the tests' trials X + αΔX and H − diag(y + αΔy), so the factors are exact.
    if (ap > 0) {
      X += ap * ws.dx;
      std::swap(ws.chol_x, ws.next_x);
    }
    if (ad > 0) {
      y += ad * ws.dy;
      set_slack_diagonal(H, y, Z);
      std::swap(ws.chol_z, ws.next_z);
    }
  }
  X = best_X;
  rescale_to_unit_diagonal(X);  // undo rounding drift
  if (!out.converged && out.reason.empty())
    out.reason = "complex interior point reached " + std::to_string(options.max_ipm_iterations) + " iterations";
  if (resume) out.iterations += resume->iterations;
  out.X = std::move(X);
  out.y = best_y;
  return out;
}

bool complex_interior_start(const Eigen::MatrixXcd& H, const Eigen::MatrixXcd& Y, double mix,
                            ComplexInteriorPointOutcome& start) {
  VectorXd mu;  // the multipliers at Y, N
  complex_multipliers(H * Y, Y, mu);
  for (double shift = 1e-3; shift <= 1.0; shift *= 10) {
    if (!shifted_positive_definite(H, mu, shift)) continue;  // H − diag(μ − shift) = S(Y) + shift·I
    start.X.noalias() = (1.0 - mix) * (Y * Y.adjoint());
    start.X.diagonal().array() += mix;
    start.y = mu.array() - shift;
    start.iterations = 0;
    return true;
  }
  return false;
}

}  // namespace fact::sdp::detail
