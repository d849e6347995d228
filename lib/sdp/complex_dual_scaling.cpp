// Dual scaling for the complex form (S. J. Benson, Y. Ye and X. Zhang, "Solving large-scale sparse
// semidefinite programs for combinatorial optimization", SIAM J. Optim. 10(2), 2000; the method
// of DSDP):  min Re tr(H X)  s.t.  X_ii = 1,  X ⪰ 0  (H Hermitian N × N), dual  max Σ y_i  s.t.
// Z = H − diag(y) ⪰ 0.
//
// Each iteration is a Newton step for the dual barrier  max Σ y/μ + ln det Z  from a strictly
// feasible y: with W = Z⁻¹ (N × N Hermitian) and M = |W|∘² (M_ij = |W_ij|², N × N real symmetric,
// the barrier's Hessian), M Δy = 1/μ − diag W, i.e. Δy = Δy₁/μ − Δy₂ with M Δy₁ = 1 and
// M Δy₂ = diag W. The same step gives a primal point for free:
//     X(μ) = μ (W + W diag(Δy) W) = μ W (Z + diag(Δy)) W
// has X_ii = 1 by construction, is ⪰ 0 exactly when Z + diag(Δy) is (one Cholesky test), and its
// objective is Σ y + μ (N + Δyᵀ diag W), an O(N) sum. The primal iterate is never formed: only its
// objective, the upper bound z̄ the next μ = (z̄ − Σ y)/ρ comes from, until X is needed at the end.
//
// Against the primal–dual interior point (complex_interior_point.cpp) an iteration has no N × N
// products (that method's two P·W products were 55 % of a tight_noisy N = 200 solve): the
// inverse and Gram of Z's factor, the N × N real Schur factor, two Cholesky tests and a Lanczos
// estimate. It takes more iterations to the hand-off (13–28 against 11–15 on tight_noisy N = 32 …
// 200) at about a third of the cost each; X is formed once, at the end (BENCHMARKS.md, session 37).
//
// The upper bound matters: started from the staircase's own objective, close to the optimum, μ
// settled near (z̄ − optimum)/2N on 3 of 42 sweep instances while every primal test failed
// (80 iterations); from the objective of the primal–dual warm start's X = 0.35·Y Yᴴ + 0.65·I,
// looser, all 42 handed off within 27 iterations (a review found one that gives up: N = 200,
// noise 0.15, seed 1; solve() then resumes the primal–dual method from this method's pair).
#include <algorithm>
#include <cmath>
#include <string>

#include "complex_product.h"
#include "dual_scaling.h"
#include "internal.h"
#include "spd_solver.h"
#include "step_length.h"

namespace fact::sdp::detail {
namespace {

using Eigen::MatrixXcd;
using Eigen::MatrixXd;
using Eigen::VectorXcd;
using Eigen::VectorXd;

// ρ = kPotentialWeight·N in μ = (z̄ − Σ y)/ρ: DSDP's potential parameter. tight_noisy N = 100:
// 26 / 22 / 22 / 24 / 30 iterations to a relative gap of 1e-3 with 1.5 / 2 / 3 / 5 / 8 (session 37);
// with the shorter steps below, against 3 (5 seeds, noise 0.02 and 0.05, N = 32 / 64 / 100): 2
// 1.15–1.32× the time, 4 0.97–1.03, 5 0.96–1.33, 6 and 8 up to 1.11× (session 41).
constexpr double kPotentialWeight = 3.0;
// The dual step is kStepFraction of the boundary as Lanczos estimates it (its |λ_min| can be short
// of the true one, so about that fraction); the Cholesky test is what keeps Z positive definite.
// Shorter steps than the primal–dual method's 0.95 keep the iterates centred: tight sweeps (5–6
// seeds, noise 0.02 / 0.03 / 0.05 / 0.1, one process), 0.875 against 0.95: N = 20 / 24 / 48 0.94 /
// 0.81 / 0.81 of the time, N = 32 / 64 / 100 0.78–0.95, N = 200 0.83, 7–15 % fewer iterations;
// 0.85 and 0.9 about as good (single sizes 0.70–1.05), 0.8 and 0.7 less so, 0.99 1.5× slower.
// (At 0.95, 2–4 Lanczos steps, whose estimate overshoots and is then shrunk by 0.7, had gained for
// the same reason.) Lanczos takes kDualLanczosSteps steps, against the primal–dual corrector's 8:
// 6 took 0.95–0.99 of the time (6 seeds, noise 0.02 / 0.05 / 0.1, N = 32 / 64 / 100), iterations
// within ±2 %; 5 and 4 gained less or lost (BENCHMARKS.md, session 41).
constexpr double kStepFraction = 0.875;
constexpr int kDualLanczosSteps = 6;

// Every matrix of one iteration, allocated once.
struct Workspace {
  explicit Workspace(Eigen::Index N)
      : L(N, N), trial(N, N), L_inv(N, N), W(N, N), best_W(N, N), M(N, N), schur(N), u(N), dw(N), dy1(N), dy2(N),
        dy(N), d(N), best_d(N), y_trial(N), ones(VectorXd::Ones(N)) {}
  MatrixXcd L;      // Z = L Lᴴ, lower triangle (N × N)
  MatrixXcd trial;  // a Cholesky test's matrix, then its factor (N × N)
  MatrixXcd L_inv;  // L⁻¹, lower triangular (N × N)
  MatrixXcd W;      // Z⁻¹ (N × N Hermitian)
  MatrixXcd best_W;  // W at the best primal point so far (N × N)
  MatrixXd M;        // |W|∘², the dual barrier's Hessian (N × N real)
  SpdSolver schur;   // M factored
  VectorXcd u;       // Lanczos scratch (N)
  VectorXd dw, dy1, dy2, dy, d, best_d, y_trial;  // diag W, M⁻¹1, M⁻¹ diag W, the dual step, Δy(μ), a trial y; N each
  VectorXd ones;  // the dual objective's gradient 1 (N)
};

// Z = H − diag(y) factored into `factor` (its lower triangle); false when not positive definite.
bool factor_slack(const MatrixXcd& H, const VectorXd& y, MatrixXcd& factor) {
  factor = H;
  factor.diagonal() -= y.cast<std::complex<double>>();
  return cholesky_in_place(factor);
}

}  // namespace

ComplexInteriorPointOutcome solve_complex_dual_scaling(const MatrixXcd& H, const Options& options, double handoff_gap,
                                                       const VectorXd& y0, double upper_bound) {
  const Eigen::Index N = H.rows();
  ComplexInteriorPointOutcome out;
  Workspace ws(N);
  VectorXd y = y0;
  if (N == 0) {
    out.reason = "dual scaling: H is empty";
    return out;
  }
  if (!factor_slack(H, y, ws.L)) {
    out.reason = "dual scaling: H − diag(y₀) is not positive definite";
    return out;
  }
  // z̄ and the best primal point's μ; with it, best_d and best_W are that point's Δy and W.
  DualScalingBound bound(upper_bound, kPotentialWeight * static_cast<double>(N));
  for (int it = 0; it < options.max_ipm_iterations; ++it, bound.next_iteration()) {
    if (bound.out_of_patience(out)) break;
    out.iterations = it + 1;
    invert_lower_factor(ws.L, ws.L_inv);
    gram_of_lower_factor(ws.L_inv, ws.W);
    ws.M = ws.W.cwiseAbs2();
    if (!ws.schur.factor(ws.M)) {
      out.reason = "dual scaling: |Z⁻¹|∘² not positive definite at iteration " + std::to_string(it);
      break;
    }
    ws.dw = ws.W.diagonal().real();
    ws.schur.solve(ws.ones, ws.dy1);
    ws.schur.solve(ws.dw, ws.dy2);
    const double dual = y.sum();
    const double rel_gap = complex_relative_gap(bound.z_bar() - dual, bound.z_bar(), dual);
    if (bound.stops(dual, rel_gap, options.gap_tol, handoff_gap, out)) break;
    // The primal point at μ = (z̄ − Σ y)/ρ: feasible when Z + diag(Δy(μ)) ⪰ 0.
    const double mu = bound.mu(dual);
    ws.d = ws.dy1 / mu - ws.dy2;
    ws.y_trial = y - ws.d;  // Z + diag(Δy(μ)) = H − diag(y − Δy(μ))
    if (factor_slack(H, ws.y_trial, ws.trial) &&
        bound.lowers(dual + mu * (static_cast<double>(N) + ws.d.dot(ws.dw)), mu)) {
      ws.best_d = ws.d;
      ws.best_W = ws.W;
    }
    // The dual step for the (possibly lowered) z̄, to kStepFraction of the boundary of Z − α diag(Δy) ⪰ 0.
    ws.dy = ws.dy1 / bound.mu(dual) - ws.dy2;
    const double lowest = lanczos_lowest<VectorXcd>(N, kDualLanczosSteps, [&](const VectorXcd& v, VectorXcd& w) {
      dual_step_operator(ws.L_inv, ws.dy, v, ws.u, w);
    });
    const double alpha = shrink_until_passes(lowest >= 0 ? 1.0 : std::min(1.0, -kStepFraction / lowest), [&](double a) {
      ws.y_trial = y + a * ws.dy;
      return factor_slack(H, ws.y_trial, ws.trial);
    });
    if (alpha == 0.0) {
      out.reason = "dual scaling stalled at iteration " + std::to_string(it);
      break;
    }
    y = ws.y_trial;
    std::swap(ws.L, ws.trial);
  }
  if (!bound.found_primal(out, options.max_ipm_iterations)) return out;
  // X = μ (W + W diag(Δy) W) at the best primal point, made exactly Hermitian with unit diagonal.
  MatrixXcd WD = ws.best_W * ws.best_d.cast<std::complex<double>>().asDiagonal();  // W diag(Δy), N × N
  multiply(WD, ws.best_W, out.X, bound.best_mu(), false);
  out.X += bound.best_mu() * ws.best_W;
  hermitian_part(out.X);
  rescale_to_unit_diagonal(out.X);
  out.y = y;
  return out;
}

}  // namespace fact::sdp::detail
