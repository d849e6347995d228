// Dual scaling for the real problem (S. J. Benson, Y. Ye and X. Zhang, SIAM J. Optim. 10(2), 2000;
// the method of DSDP), the real counterpart of complex_dual_scaling.cpp:
//     min ⟨C, X⟩  s.t.  X_ii = I_d,  X ⪰ 0     dual  max bᵀy  s.t.  Z = C − Aᵀ(y) ⪰ 0
// with the constraints of interior_point.cpp (p = (block i, a ≤ b), Aᵀ(y) = blkdiag(Λ), b_p = 1 on
// a block's diagonal and 0 off it).
//
// Each iteration is a Newton step for the dual barrier  max bᵀy/μ + ln det Z  from a strictly
// feasible y: with W = Z⁻¹ (n × n) the barrier's Hessian is M_pq = ⟨A_p, W A_q W⟩ (m × m, the
// primal–dual Schur complement with X = W), and M Δy = b/μ − A(W), i.e. Δy = Δy₁/μ − Δy₂ with
// M Δy₁ = b and M Δy₂ = A(W). The same step gives a primal point for free:
//     X(μ) = μ W (Z + Aᵀ(Δy)) W
// has A(X) = b by construction, is ⪰ 0 exactly when Z + Aᵀ(Δy) = C − Aᵀ(y − Δy) is (one Cholesky
// test), and ⟨C, X(μ)⟩ = bᵀy + μ (n + Δyᵀ A(W)), an O(m) sum. Only the best primal point's W and
// Δy are kept; X is formed once, at the end.
//
// Against the primal–dual interior point (interior_point.cpp) an iteration has no direction
// products P·W, no primal factor and one step length instead of four (up to n = 48 a few Cholesky
// tests on a grid, step_length.h): Z⁻¹ by its factor, the m × m Hessian and its Cholesky factor (m
// = 3N for d = 2, the largest piece), the primal test and the dual step's test. From the cold start
// it takes 12–18 iterations to a relative gap of 1e-5 on random full-rank C (N = 8 … 100) against
// the primal–dual method's 8–12, at about half the cost each (BENCHMARKS.md, session 38). Where the
// optimum is near 0 (the relative gap's floor of 1e-4 then asks for an absolute gap of 1e-9) it
// needed 26–35 iterations against 13, from the rank-d attempt's warm start or from the cold one.
#include <algorithm>
#include <cmath>
#include <string>

#include "dual_scaling.h"
#include "internal.h"
#include "spd_solver.h"
#include "step_length.h"

namespace fact::sdp::detail {
namespace {

// ρ = kRealPotentialWeight·n in μ = (z̄ − bᵀy)/ρ (DSDP's potential parameter). Random full rank,
// 3 seeds at N = 25 / 32 / 48 / 64 / 100, time against the primal–dual method: 0.89 / 0.96 / 0.82 /
// 0.89 / 0.71 with 3, 0.85 / 0.85 / 0.76 / 0.83 / 0.66 with 5, 0.82 / 0.86 / 0.76 / 0.85 / 0.66
// with 8; 1.5 and 2 took 1.4–2× the iterations (session 38).
constexpr double kRealPotentialWeight = 5.0;
// The dual step's fraction of the boundary of Z − α Aᵀ(Δy) ⪰ 0 (StepLength confirms it by a
// Cholesky test).
constexpr double kRealStepFraction = 0.95;

// Every matrix of one iteration, allocated once (n = C's size, m = constraints, d = block size).
struct Workspace {
  Workspace(int n, int m, int d)
      : Z(n, n), Lz(n, n), Lz_inv(n, n), W(n, n), best_W(n, n), trial(n, n), trial_factor(n, n), M(m, m), schur(m),
        steps(n), lambda(n, d), dz(n, d), aw(m), dy1(m), dy2(m), dy(m), step(m), best_step(m), y_trial(m) {}
  Eigen::MatrixXd Z, Lz;             // the dual slack C − Aᵀ(y) and its factor (lower triangle), n × n
  Eigen::MatrixXd Lz_inv, W;         // Lz⁻¹ (lower triangular) and W = Z⁻¹, n × n
  Eigen::MatrixXd best_W;            // W at the best primal point so far, n × n
  Eigen::MatrixXd trial, trial_factor;  // the primal test's C − Aᵀ(y − Δy) and its factor, n × n
  Eigen::MatrixXd M;                 // the dual barrier's Hessian, m × m
  SpdSolver schur;                   // M factored
  StepLength steps;                  // the dual step's length (and the factor of the next Z)
  Eigen::MatrixXd lambda, dz;        // Aᵀ(·) as stacked d × d blocks, n × d each
  Eigen::VectorXd aw, dy1, dy2, dy, step, best_step, y_trial;  // A(W), M⁻¹b, M⁻¹A(W), the dual step,
                                                               // Δy(μ), the best point's Δy, a trial y; m each
};

// C − Aᵀ(y) into Z and its factor into the lower triangle of L; false when not positive definite.
bool factor_slack(const Eigen::MatrixXd& C, const Eigen::VectorXd& y, const std::vector<Entry>& entries, int d,
                  Workspace& ws, Eigen::MatrixXd& Z, Eigen::MatrixXd& L) {
  lambda_from_y(y, entries, d, ws.lambda);
  certificate_matrix(C, ws.lambda, d, Z);
  return factor_lower(Z, L);
}

}  // namespace

InteriorPointOutcome solve_dual_scaling(const Eigen::MatrixXd& C, int d, const Options& options, double handoff_gap,
                                        const Eigen::MatrixXd& lambda0, double upper_bound) {
  const int n = static_cast<int>(C.rows());
  const auto entries = constraint_entries(n, d);
  const int m = static_cast<int>(entries.size());
  InteriorPointOutcome out;
  if (n == 0) {
    out.reason = "dual scaling: C is empty";
    return out;
  }
  Eigen::VectorXd b(m), y(m);  // A(X) = b; the dual iterate
  for (int p = 0; p < m; ++p) {
    b[p] = entries[p].u == entries[p].v ? 1.0 : 0.0;
    y[p] = lambda0(entries[p].u, entries[p].v % d);
  }
  Workspace ws(n, m, d);
  if (!factor_slack(C, y, entries, d, ws, ws.Z, ws.Lz)) {
    out.reason = "dual scaling: C − Λ₀ is not positive definite";
    return out;
  }
  // z̄ and the best primal point's μ; with it, best_step and best_W are that point's Δy and W.
  DualScalingBound bound(upper_bound, kRealPotentialWeight * n);
  for (int it = 0; it < options.max_ipm_iterations; ++it, bound.next_iteration()) {
    if (bound.out_of_patience(out)) break;
    out.iterations = it + 1;
    invert_lower_factor(ws.Lz, ws.Lz_inv);
    gram_of_lower_factor(ws.Lz_inv, ws.W);
    schur_complement(ws.W, ws.W, entries, ws.M);
    if (!ws.schur.factor(ws.M)) {
      out.reason = "dual scaling: its Hessian is not positive definite at iteration " + std::to_string(it);
      break;
    }
    for (int p = 0; p < m; ++p) {
      const auto [u, v] = entries[p];
      ws.aw[p] = u == v ? ws.W(u, u) : 2.0 * ws.W(u, v);
    }
    ws.schur.solve(b, ws.dy1);
    ws.schur.solve(ws.aw, ws.dy2);
    const double dual = b.dot(y);
    const double rel_gap = relative_gap(bound.z_bar() - dual, bound.z_bar(), dual);
    if (bound.stops(dual, rel_gap, options.gap_tol, handoff_gap, out)) break;
    // The primal point at μ = (z̄ − bᵀy)/ρ: feasible when C − Aᵀ(y − Δy(μ)) ⪰ 0.
    const double mu = bound.mu(dual);
    ws.step = ws.dy1 / mu - ws.dy2;
    ws.y_trial = y - ws.step;
    if (factor_slack(C, ws.y_trial, entries, d, ws, ws.trial, ws.trial_factor) &&
        bound.lowers(dual + mu * (n + ws.step.dot(ws.aw)), mu)) {
      ws.best_step = ws.step;
      ws.best_W = ws.W;
    }
    // The dual step for the (possibly lowered) z̄: Z(y + αΔy) = Z − α Aᵀ(Δy).
    ws.dy = ws.dy1 / bound.mu(dual) - ws.dy2;
    lambda_from_y(ws.dy, entries, d, ws.dz);
    ws.dz = -ws.dz;
    const double alpha = ws.steps.block_diagonal(ws.Z, ws.Lz, ws.Lz_inv, ws.dz, d, kRealStepFraction);
    if (alpha == 0.0) {
      out.reason = "dual scaling stalled at iteration " + std::to_string(it);
      break;
    }
    y += alpha * ws.dy;
    ws.steps.take_tested(ws.Z, ws.Lz);
  }
  if (!bound.found_primal(out, options.max_ipm_iterations)) return out;
  // X = μ (W + W Aᵀ(Δy) W) at the best primal point, symmetric, every diagonal block I again.
  lambda_from_y(ws.best_step, entries, d, ws.dz);
  times_block_diagonal(ws.best_W, ws.dz, d, ws.trial);  // W Aᵀ(Δy), n × n
  out.X.noalias() = bound.best_mu() * (ws.trial * ws.best_W);
  out.X += bound.best_mu() * ws.best_W;
  symmetrize(out.X);
  unit_diagonal_blocks(out.X, d);
  out.lambda.resize(n, d);
  lambda_from_y(y, entries, d, out.lambda);
  return out;
}

InteriorPointOutcome dual_scaling_then_interior_point(const Eigen::MatrixXd& C, int d, const Options& options,
                                                      double handoff_gap, std::vector<Stage>& stages) {
  auto start = std::chrono::steady_clock::now();
  InteriorPointOutcome ip = solve_dual_scaling(C, d, options, handoff_gap, cold_start_lambda(C, d), C.trace());
  record_stage(stages, "dual_scaling", ip.iterations, start, outcome_of(ip));
  if (ip.handed_off || ip.converged) return ip;
  // solve_interior_point counts only its own iterations; resumed, its budget starts after dual
  // scaling's.
  const int scaling_iterations = ip.iterations;
  start = std::chrono::steady_clock::now();
  ip = solve_interior_point(C, d, options, handoff_gap, ip.X.size() > 0 ? &ip : nullptr);
  record_stage(stages, "interior_point", ip.iterations, start, outcome_of(ip));
  ip.iterations += scaling_iterations;
  return ip;
}

}  // namespace fact::sdp::detail
