// The SDP solve: validate, scale, primal solve (low rank, then interior point if needed),
// certify, and classify. Each step is a named piece in internal.h.
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include "internal.h"

namespace fact::sdp {
namespace {

using detail::Certificate;

// Largest Newton system the polish may factor (its cost is size³/3; detail::newton_unknowns, at
// most N·d(d+1)/2 in Schur form): beyond it the interior point's own result stands.
constexpr int kMaxPolishSize = 2000;

// The early polish (automatic mode): the interior point hands its iterate to Newton once the
// relative gap is below kHandoffGap, and Newton gets kEarlyPolishSteps steps to certify; otherwise
// the interior point resumes. From a gap of 1e-5 Newton certifies in 2–3 steps on most of the
// benchmark's instances, where the interior point needs 4–6 more iterations to converge or to
// find that rounding has stalled it (BENCHMARKS.md, session 9). Until session 24 the polish ran
// only when its system had at most 4 unknowns per row of C (rank ≤ 5 for d = 2), and only up to
// n = 48, where an interior-point iteration had been cheaper than the hand-off's eigensolves and
// the dense Newton system. In Schur form a step costs about one interior-point iteration at any
// rank: polishing every rank took random full-rank C at N = 12 … 24 from 0.67 … 2.0 ms to
// 0.45 … 1.3 ms, and the hand-off at every size took random full-rank C at N = 32 / 48 / 64 to
// 0.69 / 0.70 / 0.69 of the time (N = 100 / 200: 36.6 → 25.9 ms, 217 → 156 ms) and the paper's
// cost with 2N rounds to 0.73 / 0.87 / 0.73, with the same statuses (BENCHMARKS.md, session 24).
constexpr double kHandoffGap = 1e-5;
constexpr int kEarlyPolishSteps = 3;
// The hand-off's factor of X: leading_factor at this cutoff (of X's diagonal, which is 1), whose
// Ritz values polish_size then cuts at 1e-6 of the largest, as it cut X's eigenvalues when the
// factor came from a full eigendecomposition. Sweep (4 seeds, N = 8 … 64, all kinds; fastest of 3,
// two runs): random full rank 0.98 / 0.95 / 0.93 / 0.92 of the time at N = 8 / 16 / 32 / 64, the
// paper's cost with 2N rounds 0.98 / 0.96 / 0.94 / 0.95, no status or iteration-count changes
// (BENCHMARKS.md, session 27).
constexpr double kHandoffFactorCutoff = 1e-6;
// The real interior point starts from the rank-d attempt's factor up to this many rows (below).
constexpr int kWarmStartMaxRows = 48;
// Above kWarmStartMaxRows the rank-d attempt stops when it crawls (from_low_rank). Sweep (4 seeds,
// N = 25 / 32 / 48 / 64, all kinds; fastest of 3, two runs; 0.1 against no stop): random full rank
// 0.99 / 0.93 / 0.96 / 0.94 of the time, the paper's cost with 2N rounds 0.95 / 0.96 / 0.97 / 0.96,
// the other kinds unchanged, no status or objective changes; 0.3 and 0.03 gained less. Random C of
// rank 1 … 50 at N = 25 / 32 / 48 (180 instances): the same methods and statuses. Below, where the
// attempt's factor starts the interior point, stopping it early gained nothing (N = 5 … 24: 0.97 …
// 1.06 by kind, one instance 1.46×; BENCHMARKS.md, session 26).
constexpr double kRankDCrawlDecrease = 0.1;

// The complex staircase in automatic mode climbs while the next rank's Newton system has at most
// this many unknowns (N·(2p − 1)); beyond it the interior point, handed to complex Newton at a gap
// of kHandoffGap, measures faster (BENCHMARKS.md, session 11, tight_noisy: the staircase takes
// 0.09 / 0.11 / 0.27 ms at N = 5 / 6 / 12 against the interior point's 0.13 / 0.18 / 0.79 ms,
// and 17 ms at N = 32, p = 3, against 10–13 ms). Explicit complex_low_rank climbs to kMaxPolishSize.
constexpr int kComplexMaxUnknowns = 80;
// Newton steps for rank 1 when it is the staircase's only level. On paper-noise sweeps (N = 32 …
// 100, noise 0.002 … 0.05, N + 1 rounds, 8–10 seeds each) every rank-1 solve that certified did
// so within 12 steps; the others crawl (f falling by a few % a step, the gradient not converging)
// until the interior point takes over, 25 steps in 3 ms at N = 100 (BENCHMARKS.md, session 15).
constexpr int kOnlyLevelSteps = 15;
// The complex form's polish: Newton in complex arithmetic from the converged interior point's X
// gets kComplexPolishSteps steps when that X does not certify by itself (at p ≥ 2 a step is
// O(N³) in Schur form, whatever the rank).
constexpr int kComplexPolishSteps = 4;
// The complex interior point hands its iterate to Newton at a relative gap of kComplexHandoffGap:
// X's factor down to kComplexHandoffCutoff has the optimum's rank there, and Newton in Schur form
// certifies within kComplexHandoffSteps steps, where the interior point needs 5–7 more
// iterations (tight_noisy N = 32 … 200: 13–14 iterations and 3–9 steps instead of 19–21
// iterations; BENCHMARKS.md, session 16). When Newton does not certify, the interior point
// resumes from the iterate it handed off.
constexpr double kComplexHandoffGap = 1e-3;
constexpr double kComplexHandoffCutoff = 1e-2;
constexpr int kComplexHandoffSteps = 10;
// When Newton from that factor stops at a saddle before its kComplexHandoffSteps, it starts again
// from X's factor down to kHandoffWiderCutoff (pivoted Cholesky until the residual diagonal is
// below it). On the 5 such instances of a tight sweep (N = 27 … 100, 8 seeds, noise 0.02 / 0.05 /
// 0.1: 192 instances) an escape from the saddle instead (the staircase's, along S's lowest
// eigenvector) crawled and certified none within 10 steps; the wider factor certified 4, and the
// interior point resumed on 3 instances instead of 7 (BENCHMARKS.md, session 48).
constexpr double kHandoffWiderCutoff = 1e-3;
// complex_polish's Newton keeps its shift at most kPolishShiftPerGradient·‖grad‖ after the first
// step (complex_newton's shift_per_gradient; at rank ≥ 2, the Schur-form path). The
// lower-10×-a-step rule alone kept the shift above 0.1·‖grad‖ from the second step on:
// tight_noisy N = 100 handed off at ‖grad‖ 5e-5 and took 5 steps at λ = 1e-6, 1e-7, 1e-8, 1e-9,
// 1e-10 while ‖grad‖ went 1.7e-8, 1.2e-8, 1.2e-9, 3.9e-12; with the cap 4 (3 in a build that
// rounds differently). Sweep (the complex form, N + 1 rounds, noise 0.01 / 0.03 / 0.05 / 0.1,
// N = 20 … 100, 6 seeds, two runs each side): 2–3.5 % fewer iterations and steps, none more; time at
// N = 48 … 100 0.87–1.01, mostly 0.94–0.97, at N = 20 / 32 0.97–1.02; 0.3 and 1 saved fewer steps.
// At the staircase's levels, whose Newton descends from a saddle, the cap lost (0.1: tight_noisy
// N = 12 1.17× the time), and on the real Newton (at every call) it moved the iteration totals
// by −2 … +1 % (BENCHMARKS.md, session 44).
constexpr double kPolishShiftPerGradient = 0.1;
// In automatic mode the interior points start from the low-rank path's last factor Y,
// X = (1 − mix) Y Yᴴ + mix·I with mix = kInteriorStartMix, instead of X = I: the complex one from
// the staircase's factor, the real one (not on the complex form) from the rank-d attempt's for
// n ≤ kWarmStartMaxRows. Complex, tight sweeps (8 seeds, interleaved in one process), mix 0.5
// against X = I: −27 % time at N = 32, −2 % at 64, −6 % at 100 (noise 0.05), −10 % and −39 % at
// N = 32 and 64 with noise 0.01; 0.65 against 0.5: +1.5 %, −4 %, −10 % at N = 32, 64, 100
// (BENCHMARKS.md, session 17). Real: 2–4 fewer iterations to the hand-off on plain_noisy
// N = 5 … 16, mix 0.5 … 0.8 alike (session 19).
constexpr double kInteriorStartMix = 0.65;
// When the rank-d attempt that did not certify ended at an objective f (C scaled to ‖C‖_F = 1) in
// [kNearZeroWindowLow, kNearZeroWindowHigh], the real interior point starts from near_zero_start
// (Λ = −10⁻³·I, X centred for it) rather than from the attempt's factor. Such an optimum is small
// against ‖C‖ (the paper's noisy cost: f = 1e-4 … 3e-2), and the attempt's point, off its face,
// mixed with 0.65·I, starts at a μ₀ 20× the near-zero start's (plain_noisy N = 5: 6.7e-2 against
// 3e-3). Below the window the attempt has nearly reached the optimum (the paper's cost with 2N
// rounds at noise 0.01: f ≤ 8e-5, where the near-zero start took up to 2 more iterations); above
// it the optimum is far from 0, and so is Λ = −10⁻³·I (random full-rank C, f = 0.3 … 1.1: as many
// iterations or one more; no instance fell between 3e-2 and 0.3, so the upper end is a choice,
// not a measured edge). Sweep (8 seeds; the plain cost at noise 0.002 … 0.1, with 2N and 3N
// rounds, random C of rank N + 1 and full; N = 5 … 24; two runs each side, fastest of 3 medians):
// the 206 solves whose path changed took 0.95 of the time (geometric mean; 0.65 … 1.23), the
// plain cost 1.5 % and the paper's cost with 2N / 3N rounds at noise 0.1 3.5 % fewer iterations
// and steps (with 3N rounds at noise 0.05: 16 instances fewer, 20 more), no status or objective
// changed; benchmark plain_noisy N = 5 92 → 82 µs, N = 6 … 16 unchanged (BENCHMARKS.md, session 44).
constexpr double kNearZeroWindowLow = 1e-4;
constexpr double kNearZeroWindowHigh = 0.1;
// Automatic mode on a real C with d = 2 and at most this many rows climbs the whole Riemannian
// staircase (rank 2, 3, … to the Pataki bound) before the interior point, instead of rank 2 alone:
// at N = 3 and 4 a Newton step on a factor of rank ≤ 4 costs less than an interior-point
// iteration and the climb certifies the high-rank optima of the plain form and of random C.
// Sweep (12 seeds; the plain cost at noise 0.01 / 0.05 / 0.1, random C of rank 1 … N + 1 and of full
// rank; time summed, staircase against rank 2 then interior point): N = 3 0.59 / 0.52 / 0.59,
// N = 4 0.96 / 0.58 / 0.44 (plain / low rank / full rank); at N = 5 the plain form took 1.9× as
// long (its optimum, of rank 4, needs 45 staircase steps), at N = 6 3.1× (BENCHMARKS.md, session 23).
// All 300 instances (N = 2 … 6) were certified on both paths, with the same statuses.
constexpr Eigen::Index kStaircaseMaxRows = 8;
// Above kStaircaseMaxRows and up to kSteepClimbMaxRows rows (N = 5, 6; d = 2) automatic mode climbs
// past rank 2 only from a critical point (‖S Y‖_F < kSteepClimbEig) whose S has
// λ_min < −kSteepClimbEig (C scaled to ‖C‖_F = 1; a Cholesky test of S + kSteepClimbEig·I), and
// goes to the interior point otherwise.
// The whole staircase measured 0.40–0.87 of the time where λ_min was that low (random C of full
// rank and of rank N + 1: λ_min −0.04 … −0.13 at rank 2, optima of rank 3 and 4; one 1.33×) but
// mostly 1.2–3.1× where it was −5e-4 … −1.1e-2 (the plain form, N + 1 rounds; optima of rank 3 and 4
// reached by crawling levels). Sweep (6 seeds each of the plain form at noise 0.01 / 0.05 / 0.1 and
// at 0.05 with 2N and 3N rounds, random C of rank 3, N + 1 and full; old and new builds alternated):
// random full rank 0.53 / 0.66 of the time at N = 5 / 6, rank N + 1 0.59 / 0.86 (one instance
// 1.32×), the other kinds 0.99–1.02, no status changes. At N = 7 random C of rank N + 1 lost
// (1.2–2.1×), so the limit is 12 rows (BENCHMARKS.md, session 40).
constexpr Eigen::Index kSteepClimbMaxRows = 12;
constexpr double kSteepClimbEig = 1e-2;
// Above kSteepClimbMaxRows (d = 2), when C's null space has no room for a zero optimum of rank 2
// (room_in_null_space), the rank-2 attempt can certify only a positive optimum of rank 2, and gets
// kPositiveRankTwoSteps Newton steps instead of 25: in a sweep of the paper's plain cost (N = 5 …
// 32; N + 1, 2N and 3N rounds; noise 0.002 … 0.1; 6 seeds, 900 instances) every one of the 245 rank-2
// attempts that certified took at most 11 steps (all but one at most 8); past them the attempt
// crawls toward a saddle whose factor only starts the interior point (plain_noisy N = 7: 21 steps,
// 18 % of the solve). Sweep (4 seeds; fastest of 3, interleaved): the plain form at noise 0.01 /
// 0.05 / 0.1, N = 7 / 8 / 12 / 16: 0.92–0.97 / 0.79–0.98 / 0.84–1.00 / 0.95–1.00 of the time; random
// C of full rank 0.92–0.97, of rank N + 1 0.98–1.06; random C of rank 3, and every kind at N = 32
// and 48, with the same iterations (BENCHMARKS.md, session 40). Where a zero optimum of rank 2 may
// lie in the null space (random C of rank 3) the attempt keeps its 25 steps: capped at 10 there
// too, it took 1.09–1.37× as long at N = 8 … 16.
constexpr int kPositiveRankTwoSteps = 12;
// The complex interior point's X is factored (complex_factor, pivoted Cholesky) until what
// remains of its diagonal is below this fraction of the largest entry: at convergence the rest
// is rounding, and dropping it keeps the factor's rank that of the optimum.
constexpr double kComplexFactorCutoff = 1e-10;

struct Candidate {
  Eigen::MatrixXd Y;      // n × r factor of X
  Certificate cert;       // certificate for it (scaled problem)
  double primal = 0;      // ⟨C, Y Yᵀ⟩ (scaled), from primal_objective, set with cert
  Method method = Method::low_rank;
  std::string note;       // why the method stopped, when it did not converge
  bool null_space_empty = false;  // from_null_space: C's null space had room but no feasible X
                                  // (detail::NullSpaceOutcome::empty)
};

// Each method that runs appends its Stage (Result::stages) when it ends (detail::record_stage),
// to the Stages the solve passes down.
using Clock = std::chrono::steady_clock;
using Stages = std::vector<Stage>;
using detail::outcome_of;
using detail::record_stage;

// The relative gap (detail::relative_gap) of a primal objective and a dual bound.
double relative_gap(double primal, double dual) { return detail::relative_gap(primal - dual, primal, dual); }

// ⟨C, Y Yᵀ⟩ for a feasible Y (every block of Y Yᵀ is I), computed as tr Λ + ⟨S, Y Yᵀ⟩.
// The two are equal in exact arithmetic; the second has no cancellation, because S and
// Y Yᵀ are both PSD, so the gap ⟨S, Y Yᵀ⟩ stays accurate when the optimum is small.
double primal_objective(const Eigen::MatrixXd& C, const Eigen::MatrixXd& Y, const Certificate& cert, int d) {
  const Eigen::MatrixXd SY = detail::certificate_matrix(C, cert.lambda, d) * Y;  // n × r
  return cert.trace_lambda + Y.cwiseProduct(SY).sum();
}

// The largest entry of Y_i Y_iᵀ − I over the blocks: how far X = Y Yᵀ is from feasible.
double feasibility_error(const Eigen::MatrixXd& Y, int d) {
  double worst = 0;
  for (Eigen::Index i = 0; i + d <= Y.rows(); i += d)
    for (int a = 0; a < d; ++a)
      for (int b = a; b < d; ++b) {
        const double entry = Y.row(i + a).dot(Y.row(i + b));
        worst = std::max(worst, std::abs(entry - (a == b ? 1.0 : 0.0)));
      }
  return worst;
}
// A candidate's X counts as feasible within this (its objective and certificate assume X_ii = I).
constexpr double kFeasibilityTol = 1e-8;

// The gap closes at a relative gap ≤ gap_tol, or when the absolute gap is within the bound's own
// rounding (bound_error: the eigensolver's error on λ_min(S), n·4nε‖S‖₂, and tr Λ's sum): then
// floating point cannot tell the bound from the objective. That decides only on a small optimum
// (|objective| below about bound_error/gap_tol), where n·|λ_min(S)| at rounding level can exceed
// gap_tol·1e-4: the zero optimum of plain_noisy N = 250 had a relative gap of 1.2e-9.
bool gap_closes(const Candidate& c, const Options& o) {
  return relative_gap(c.primal, c.cert.dual_bound) <= o.gap_tol || c.primal - c.cert.dual_bound <= c.cert.bound_error;
}

// (A candidate without a factor, from a method that found no point, or whose X is not feasible,
// is never certified: an independent review found rank-1 blocks from the closed-form polar factor
// certified with X_ii off I by 0.7.)
bool is_certified(const Candidate& c, const Options& o) {
  return c.Y.size() > 0 && c.cert.min_eig >= -o.psd_tol && gap_closes(c, o) &&
         feasibility_error(c.Y, static_cast<int>(c.cert.lambda.cols() > 0 ? c.cert.lambda.cols() : 1)) <= kFeasibilityTol;
}

// The certificate of a factor Y (n × r, feasible) against its own multipliers Λ(Y), and the
// primal objective, into c. With complex_form (d = 2, C = emb(H)) each block of Λ is replaced by
// half its trace times I₂, the form μ_i I₂ of the Hermitian problem's certificate: for a factor of
// the complex form that only removes rounding.
void certify_factor(const Eigen::MatrixXd& C, int d, Candidate& c, bool complex_form = false) {
  Eigen::MatrixXd lambda = detail::lambda_from_factor(C, c.Y, d);  // n × d, blocks stacked
  if (complex_form)
    for (Eigen::Index i = 0; i < lambda.rows(); i += 2)
      lambda.middleRows<2>(i) = 0.5 * (lambda(i, 0) + lambda(i + 1, 1)) * Eigen::Matrix2d::Identity();
  c.cert = detail::certify(C, lambda, d, false);
  c.primal = primal_objective(C, c.Y, c.cert, d);
}

// A Newton candidate whose S is PSD within psd_tol but whose bound tr Λ + n·λ_min(S) misses the
// gap. Newton stops at ‖grad‖ < 1e-12, where λ_min(S) is of the order of ‖grad‖ and n·|λ_min| can
// exceed the gap tolerance on a small optimum (noise-free plain form, N = 4, seed 9, tested:
// λ_min(S) ≈ −1e-13 and a relative gap of a few 1e-9, and the interior point ran after Newton
// had the optimum; on random_lowrank N = 12 and 32 that cost 11–14× the instructions). One more
// Newton step, quadratic there, lands at rounding; it is taken only for such a candidate, so a
// start that certifies pays nothing.
bool misses_only_the_gap(const Candidate& c, const Options& o) {
  return c.cert.min_eig >= -o.psd_tol && !is_certified(c, o);
}

// The Stage::outcome of a method that produced the candidate c.
std::string outcome_of(const Candidate& c, const Options& o) {
  return is_certified(c, o) ? "certified" : c.note.empty() ? "not certified" : c.note;
}

// c after one more Newton step (grad_tol 0: always taken, unless no damping is accepted) when it
// misses only the gap and the step certifies; c itself otherwise. c's certificate is its own
// factor's (certify_factor, with the same complex_form). The step taken, if any, is added to steps.
Candidate with_one_more_step(const Eigen::MatrixXd& C, int d, Candidate c, const Options& o, int& steps,
                             bool complex_form = false) {
  if (!misses_only_the_gap(c, o)) return c;
  Candidate next = c;
  const int taken = detail::newton_refine(C, d, next.Y, 1, 0.0);
  steps += taken;
  if (taken == 0) return c;  // Y unchanged (no tangent directions, or no step accepted)
  certify_factor(C, d, next, complex_form);
  return is_certified(next, o) ? next : c;
}

// In automatic mode the low-rank path only tries rank d (the tight case, where Newton has
// converged within 10 steps on every benchmark instance) for at most 25 steps; a problem
// that does not certify there goes to the interior point, which measures faster than
// climbing the staircase on high-rank optima. Up to kStaircaseMaxRows rows (d = 2) it climbs
// the whole staircase instead, 25 Newton steps a level, and up to kSteepClimbMaxRows when rank 2
// ends with λ_min(S) < −kSteepClimbEig. Above that, rank 2 gets kPositiveRankTwoSteps steps unless
// zero_optimum_in_reach (room_in_null_space's rank_d). Above kWarmStartMaxRows rows, where the
// interior point starts cold and the attempt serves only if it certifies, it stops once it crawls
// (detail::CrawlWatch, f down by less than kRankDCrawlDecrease of itself in 3 steps).
Candidate from_low_rank(const Eigen::MatrixXd& C, int d, Options o, Stages& stages, bool zero_optimum_in_reach = true) {
  const Clock::time_point start = Clock::now();
  double crawl_decrease = 0, climb_eig = 0;
  if (o.method == Method::automatic) {
    const bool whole_staircase = d == 2 && C.rows() <= kStaircaseMaxRows;
    if (!whole_staircase && d == 2 && C.rows() <= kSteepClimbMaxRows) climb_eig = kSteepClimbEig;
    if (!whole_staircase && climb_eig == 0) o.max_rank = d;
    const bool positive_rank_two = d == 2 && C.rows() > kSteepClimbMaxRows && !zero_optimum_in_reach;
    o.max_newton_iterations = std::min(o.max_newton_iterations, positive_rank_two ? kPositiveRankTwoSteps : 25);
    if (C.rows() > kWarmStartMaxRows) crawl_decrease = kRankDCrawlDecrease;
  }
  // (automatic mode goes on to the interior point when the attempt does not certify, and a
  // certificate without a spectrum never replaces its result)
  detail::LowRankOutcome lr =
      detail::solve_low_rank(C, d, o, crawl_decrease, o.method == Method::automatic, climb_eig);
  Candidate c{std::move(lr.Y), std::move(lr.certificate), 0, Method::low_rank, {}};
  c.primal = primal_objective(C, c.Y, c.cert, d);
  int steps = lr.iterations;
  c = with_one_more_step(C, d, std::move(c), o, steps);
  record_stage(stages, "low_rank", steps, start, outcome_of(c, o));
  return c;
}

// The zero optimum (null_space.cpp), real C only: a factor in C's null space and Λ = 0. Without
// one, a candidate with no factor and the reason in its note.
Candidate from_null_space(const Eigen::MatrixXd& C, int d, const Options& o, Stages& stages) {
  const Clock::time_point start = Clock::now();
  const detail::NullSpace null = detail::null_space_of(C);
  detail::NullSpaceOutcome out;
  Candidate c;
  c.method = Method::null_space;
  const bool found = detail::zero_optimum(C, d, null, out);
  if (found) {
    c.Y = std::move(out.Y);
    c.cert = std::move(out.certificate);
    c.primal = primal_objective(C, c.Y, c.cert, d);
  } else if (!null.positive_semidefinite) {
    c.note = detail::printed("C is not positive semidefinite: λ_min = %g", null.eigenvalues[0]);
  } else if (null.dimension < d) {
    c.note = detail::printed("C's null space (dimension %d) is smaller than d = %d", null.dimension, d);
  } else {
    c.note = detail::printed("C's null space (dimension %d) gave no feasible X in %d Newton steps", null.dimension,
                             out.steps);
    c.null_space_empty = out.empty;
  }
  record_stage(stages, "null_space", out.steps, start, outcome_of(c, o));
  return c;
}

// Automatic mode on a real C: rank-d Newton (from_low_rank; the whole staircase for d = 2 and
// n ≤ kStaircaseMaxRows, or n ≤ kSteepClimbMaxRows after a steep rank 2) and the zero optimum
// (from_null_space), the first that certifies, else the low-rank candidate (the interior point's
// warm start). The null space goes first when it may hold a feasible X but
// generically none of rank d: then a zero optimum, if there is one, is out of rank-d Newton's
// reach (the plain form from N = 7 on, k = N − 1: plain_noisy N = 12 spent 15 of its 17 steps
// there; BENCHMARKS.md, session 22). The order is decided on k estimated by pivoted_rank (C's
// spectrum, which the null space needs, cost a third more than the whole solve of random_lowrank
// N = 100, which rank-d Newton certifies).
//
// When the null space went first and found its set empty (detail::NullSpaceOutcome::empty: a
// Newton step fitted at neither full nor half length; the plain form with N + 1 rounds at
// N = 7 … 14 under noise), the rank-d attempt is skipped for d = 2 above kSteepClimbMaxRows, where
// it could only certify an optimum of rank 2, and the zero candidate (null_space_empty, no factor)
// goes on to the interior point without a warm start: up to kWarmStartMaxRows rows the primal–dual
// method from near_zero_start (from_interior_point), above dual scaling from the cold start. The
// skipped attempt ran its 12 steps toward a saddle whose factor only started the interior point.
// Sweep (6 seeds; fastest of 3, interleaved), the plain form at noise 1e-4 / 0.002 / 0.01 / 0.05 /
// 0.1, N = 7 … 14: 0.87–1.00 of the time (noise 0.01, N = 7 / 10: 1.04 / 1.05, where the polish
// after the cold hand-off did not certify and the interior point resumed); random C of rank N + 1,
// N = 7 … 12: 0.84–0.91; random C of rank 1.5N at N = 32 / 50 / 64: 0.89 / 0.99 / 0.99. Noise-free
// the steps mostly run out (the zero optimum of rank 2 has no interior, and rank-d Newton still
// finds it); the few whose set is found empty take the new path (noise-free sweep, 12 seeds,
// N = 9 / 10 / 13: 1.00 / 0.99 / 0.97). Up to 12 rows, where the attempt climbs and certifies
// optima of rank 3 and 4, skipping it lost (random C of rank 3, N = 5 / 6: 1.11 / 1.07); dual
// scaling in place of the primal–dual method took 0.70–0.91 at noise ≥ 0.03 for N ≤ 9 but
// 1.03–1.22 at noise 0.002 and 1.07–1.28 at N = 12 and 14, where the optimum is near 0; the
// primal–dual method above 48 rows took 1.09 at N = 32 (BENCHMARKS.md, session 42).
//
// When the null space would go first and leaves room for few points (NullSpaceRoom::few_points:
// fewer than N unknowns of P to spare over the constraints), it is not tried above
// kSteepClimbMaxRows (d = 2): the zero candidate is taken as empty (without C's spectrum and
// Newton's step) and goes on to the interior point as above. With so little room a feasible P
// is rarely positive semidefinite: the plain form with N + 1 rounds held a feasible X at N = 7
// (k = 6, 21 unknowns for 21 constraints) in none of 144 instances (noise 1e-4 … 0.1, 24 seeds
// each), random C of rank N + 1 in none of 24, at N = 8 (4 to spare) in 3 of 168, and at N = 9 (9
// to spare) in 17 of 168. Sweep (12 seeds, fastest of 3, two runs each side): the plain form at
// N = 7 and noise 0 / 1e-4 / 0.002 / 0.01 / 0.05 / 0.1 0.84 / 0.91–0.93 / 0.94 / 0.94 / 0.94 /
// 0.93 of the time (noise-free the null space's Newton ran out of steps and the rank-2 attempt
// ran too: 563 iterations and steps against 309), random C of rank N + 1 0.92 (session 44, when
// only N = 7's equal counts were skipped); at N = 8 (24 seeds) the plain form at noise 0 / 1e-4 /
// 0.002 / 0.01 / 0.05 / 0.1 0.84 / 0.83 / 0.86 / 0.88 / 0.88 / 0.89, random C of rank N + 1 0.89,
// after the interior point's step lengths became Cholesky tests (measured 0.92–1.02 before them);
// the few whose null space held a feasible X certify through the interior point instead, at the
// same optimum; no status changed (BENCHMARKS.md, sessions 44 and 45).
Candidate from_rank_d_or_null_space(const Eigen::MatrixXd& C, int d, const Options& o, Stages& stages) {
  const int k = static_cast<int>(C.rows()) - detail::pivoted_rank(C);  // estimated dim null(C)
  const detail::NullSpaceRoom room = detail::room_in_null_space(k, C.rows(), d);
  const bool null_first = room.feasible && !room.rank_d;
  const bool rank_d_only = d == 2 && C.rows() > kSteepClimbMaxRows;
  if (null_first && room.few_points && rank_d_only) {
    Candidate zero;
    zero.method = Method::null_space;
    zero.note = detail::printed("C's null space (dimension %d) leaves room for few points only: not tried",
                                k);
    zero.null_space_empty = true;
    return zero;
  }
  if (null_first) {
    Candidate zero = from_null_space(C, d, o, stages);
    if (is_certified(zero, o) || (zero.null_space_empty && rank_d_only)) return zero;
  }
  Candidate rank_d = from_low_rank(C, d, o, stages, room.rank_d);
  if (is_certified(rank_d, o) || null_first || !room.feasible) return rank_d;
  Candidate zero = from_null_space(C, d, o, stages);
  return is_certified(zero, o) ? zero : rank_d;
}

// A complex outcome on H (C = emb(H), scaled) as a candidate: factor and certificate in d = 2 terms.
Candidate candidate_of(const Eigen::MatrixXd& C, const detail::ComplexOutcome& out, Method method) {
  Candidate c{detail::real_factor(out.Y), detail::complex_certificate(out), 0, method, {}};
  c.primal = primal_objective(C, c.Y, c.cert, 2);
  return c;
}

// The complex staircase on H. In automatic mode each level gets at most 25 Newton steps, as
// the real rank-d path: on the non-unique N = 200 instance rank 1 otherwise spends 60 steps
// (54 ms) before the interior point takes over. When rank 1 is the only level (N > 26, where
// rank 2's system would exceed kComplexMaxUnknowns) it gets kOnlyLevelSteps.
Candidate from_complex_low_rank(const Eigen::MatrixXd& C, Options o, Stages& stages) {
  const Clock::time_point start = Clock::now();
  const bool automatic = o.method == Method::automatic;
  const int max_unknowns = automatic ? kComplexMaxUnknowns : kMaxPolishSize;
  const bool only_level = detail::complex_newton_unknowns(C.rows() / 2, 2) > max_unknowns;  // rank 2 does not fit
  if (automatic) o.max_newton_iterations = std::min(o.max_newton_iterations, only_level ? kOnlyLevelSteps : 25);
  const Eigen::MatrixXcd H = detail::hermitian_of(C);
  // In automatic mode a last level that cannot certify skips its spectrum: the interior point
  // follows and its certificate replaces this one's (0.6 ms at N = 100, 3.2 ms at N = 200).
  detail::ComplexOutcome out = detail::solve_complex_low_rank(H, o, max_unknowns, !automatic);
  Candidate c = candidate_of(C, out, Method::complex_low_rank);
  int steps = out.iterations;
  if (misses_only_the_gap(c, o)) {
    const int more = detail::complex_newton(H, out.Y, 1, 0.0);  // one more step, as with_one_more_step (complex)
    steps += more;
    if (more > 0) {
      Candidate next =
          candidate_of(C, detail::complex_outcome(H, std::move(out.Y), steps, false), Method::complex_low_rank);
      if (is_certified(next, o)) c = std::move(next);
    }
  }
  record_stage(stages, "complex_low_rank", steps, start, outcome_of(c, o));
  return c;
}

// Newton in complex arithmetic from a factor Y (N × p, unit rows) of an interior point's X
// (complex form only, H = hermitian_of(C)) for at most max_steps steps, its shift capped by the
// gradient (kPolishShiftPerGradient); the steps it took into *steps_taken when given.
Candidate complex_polish(const Eigen::MatrixXd& C, const Eigen::MatrixXcd& H, Eigen::MatrixXcd Y, int max_steps,
                         const Options& o, Stages& stages, int* steps_taken = nullptr) {
  const Clock::time_point start = Clock::now();
  const int steps = detail::complex_newton(H, Y, max_steps, 1e-12, false, 0.0, kPolishShiftPerGradient);
  if (steps_taken) *steps_taken = steps;
  Candidate c = candidate_of(C, detail::complex_outcome(H, std::move(Y), steps, false), Method::interior_point);
  record_stage(stages, "complex_newton", steps, start, outcome_of(c, o));
  return c;
}

// The complex interior point on H (complex form, automatic mode), started from the staircase's
// factor staircase_Y (2N × 2p, real form; complex_interior_start with kInteriorStartMix; X = I and
// y = −2 when that finds no dual shift or the warm start stalls), handed to complex Newton at
// kComplexHandoffGap and, when that does not certify, resumed and run to convergence. With a warm
// start, dual scaling (complex_dual_scaling.cpp) takes the first part, to the hand-off, from its
// dual y and with its X's objective as the upper bound; the primal–dual method only when dual
// scaling gives up, and to resume. Dual scaling to the hand-off, against the primal–dual method
// from the same start, summed over 6 sweep instances per N: 0.57 … 0.88 of the solve's time at
// N = 32 … 200 (the benchmark's own N = 32 instance 1.08), neutral below (where the staircase
// mostly certifies), the same statuses and optima (BENCHMARKS.md, session 37). Its dual y
// keeps S = H − diag(y) positive definite and its X (factored down to kComplexFactorCutoff,
// rows renormalised) is feasible, so the pair certifies without a polish; when the interior point
// stops short of the gap, complex Newton from its X gets kComplexPolishSteps steps.
Candidate from_complex_interior_point(const Eigen::MatrixXd& C, const Options& o, const Eigen::MatrixXd& staircase_Y,
                                      Stages& stages) {
  Clock::time_point started = Clock::now();
  const Eigen::MatrixXcd H = detail::hermitian_of(C);
  detail::ComplexInteriorPointOutcome start;
  const Eigen::MatrixXcd Y = staircase_Y.size() > 0 ? detail::complex_of_real_factor(staircase_Y) : Eigen::MatrixXcd();
  const bool warm = Y.size() > 0 && detail::complex_interior_start(H, Y, kInteriorStartMix, start);
  detail::ComplexInteriorPointOutcome ip;
  if (warm) {  // upper bound: the objective of the primal–dual method's warm start X
    ip = detail::solve_complex_dual_scaling(H, o, kComplexHandoffGap, start.y,
                                            (H.array() * start.X.array().conjugate()).real().sum());
    record_stage(stages, "complex_dual_scaling", ip.iterations, started, outcome_of(ip));
  }
  // The primal–dual method to handoff_gap from `from` (X = I and y = −2 without one), into ip.
  const auto primal_dual = [&](double handoff_gap, const detail::ComplexInteriorPointOutcome* from) {
    started = Clock::now();
    ip = detail::solve_complex_interior_point(H, o, handoff_gap, from);
    record_stage(stages, "complex_interior_point", ip.iterations, started, outcome_of(ip));
  };
  // No start, or dual scaling gave up: the primal–dual method, from dual scaling's best primal
  // point and last y when it found one (a strictly feasible pair, closer to the optimum than
  // the start), else from the start.
  if (!ip.handed_off && !ip.converged)
    primal_dual(kComplexHandoffGap, ip.X.size() > 0 ? &ip : (warm ? &start : nullptr));
  // The warm start stalled (4 of 240 sweep instances, N = 27 … 100, near a relative gap of 1): cold.
  if (warm && !ip.handed_off && !ip.converged) primal_dual(kComplexHandoffGap, nullptr);
  if (ip.handed_off) {
    int steps = 0;
    Eigen::MatrixXcd factor = detail::complex_factor(ip.X, kComplexHandoffCutoff);  // N × p
    const Eigen::Index rank = factor.cols();
    Candidate handed = complex_polish(C, H, std::move(factor), kComplexHandoffSteps, o, stages, &steps);
    if (is_certified(handed, o)) return handed;
    // Newton stopped short of its cap at a saddle (S has a negative eigenvalue): the factor's rank
    // was short of the optimum's, the pivoted Cholesky's residual diagonal just under the cutoff
    // (on one instance at N = 48, X's third eigenvalue 7.8e-2 with a unit diagonal). Newton again
    // from X's factor down to kHandoffWiderCutoff, when that has more columns.
    if (steps < kComplexHandoffSteps && handed.cert.min_eig < -o.psd_tol) {
      Eigen::MatrixXcd wider = detail::complex_factor(ip.X, kHandoffWiderCutoff);  // N × p'
      if (wider.cols() > rank) {
        handed = complex_polish(C, H, std::move(wider), kComplexHandoffSteps, o, stages);
        if (is_certified(handed, o)) return handed;
      }
    }
    primal_dual(0.0, &ip);  // resumed where it handed off, to convergence
  }
  Candidate c = candidate_of(
      C, detail::complex_outcome(H, detail::complex_factor(ip.X, kComplexFactorCutoff), ip.y, ip.iterations, false),
      Method::interior_point);
  c.note = ip.reason;
  if (is_certified(c, o)) return c;
  Candidate polished = complex_polish(C, H, detail::complex_factor(ip.X, 1e-6), kComplexPolishSteps, o, stages);
  return is_certified(polished, o) ? polished : c;
}

Candidate candidate_of(const Eigen::MatrixXd& C, int d, const detail::InteriorPointOutcome& ip) {
  Candidate c;
  c.Y = detail::factor_psd(ip.X, 0.0);
  c.cert = detail::certify(C, ip.lambda, d, false);
  c.primal = primal_objective(C, c.Y, c.cert, d);
  c.method = Method::interior_point;
  c.note = ip.reason;
  return c;
}

// The factor rank and Newton-system size the polish uses for Y (n × r, orthogonal columns
// largest first, ‖y_k‖² X's eigenvalues or, from leading_factor at the hand-off, its Ritz
// values): detail::polish_rank, without X's ghost eigenvalues when `ghosts` is set (the hand-off).
struct PolishSize {
  int rank = 0;
  int unknowns = 0;  // of the Newton system newton_refine factors (detail::newton_unknowns)
};
PolishSize polish_size(const Eigen::MatrixXd& Y, int d, bool ghosts) {
  const int blocks = static_cast<int>(Y.rows() / d);
  PolishSize size;
  size.rank = detail::polish_rank(Y.colwise().squaredNorm().transpose(), d, detail::pataki_rank(blocks, d), ghosts);
  size.unknowns = detail::newton_unknowns(blocks, d, size.rank);
  return size;
}

// Riemannian Newton from the interior point's X, at the rank polish_size gives (dropping ghost
// values when `handed_off`: ip.Y is the hand-off's factor), when the Newton system has at most
// max_unknowns unknowns, for at most max_steps steps; nullopt when it does not run. The
// interior point finds the optimal face reliably, but when the optimum is
// small against ‖C‖ its last digits are limited by the conditioning of Z⁻¹; Newton converges
// quadratically from there. A polished point short only of the gap takes one more step
// (with_one_more_step): the benchmark's plain_noisy N = 6 handed off at a relative gap of 1e-5,
// was polished to λ_min(S) = −9e-14 and a gap of 4.1e-9, and the interior point resumed: 27
// iterations and steps in all, 23 with the one step.
std::optional<Candidate> polish(const Eigen::MatrixXd& C, int d, const Candidate& ip, int max_unknowns, int max_steps,
                                bool handed_off, const Options& o, Stages& stages) {
  const Clock::time_point start = Clock::now();
  const PolishSize size = polish_size(ip.Y, d, handed_off);
  if (size.rank < d || size.unknowns > max_unknowns) return std::nullopt;
  Eigen::MatrixXd Y = ip.Y.leftCols(size.rank);
  if (!detail::project_blocks(Y, d)) return std::nullopt;
  Candidate c = ip;
  int steps = detail::newton_refine(C, d, Y, max_steps, 1e-12);
  c.Y = std::move(Y);
  certify_factor(C, d, c);
  c = with_one_more_step(C, d, std::move(c), o, steps);
  record_stage(stages, "newton_polish", steps, start, outcome_of(c, o));
  return c;
}

// The interior point. For n ≤ kWarmStartMaxRows it starts from the rank-d attempt's factor and
// multipliers when `warm` has them (interior_start with kInteriorStartMix; cold, X = I, when that
// finds no dual shift or the warm run stalls), or from near_zero_start when the attempt's
// objective lies in [kNearZeroWindowLow, kNearZeroWindowHigh] (from the attempt's factor when C
// is not PSD there); above kWarmStartMaxRows rows the warm start measured 0 … +20 % slower
// (plain_noisy N = 32, 48; one N = 32 instance, whose optimum is 0, lost positive definiteness
// near the end and restarted cold; with the hand-off at every size, session 24: random full rank
// N = 32 … 64 −1 … +5 %, the paper's cost with 2N rounds −8 … −15 %). In automatic mode it hands
// off at kHandoffGap to a Newton polish of at most kEarlyPolishSteps steps, and resumes where it
// stopped when the polish does not certify. Without a warm start, in automatic mode, dual scaling
// takes the part to the hand-off (dual_scaling_then_interior_point), except after an empty null
// space (Candidate::null_space_empty, from_rank_d_or_null_space) up to kWarmStartMaxRows, where
// the primal–dual method starts from near_zero_start (X = I when that finds C not PSD, or when
// the run from it stalls). Dual scaling takes more
// iterations to the hand-off (random full rank N = 8 … 100: 12–18 against 8–12) at about half the
// cost each: 0.66–0.85 of the solve's time at N = 25 … 100, the same statuses and optima. From
// the rank-d attempt's warm start (n ≤ kWarmStartMaxRows) it gained 10–15 % on random full-rank C
// and plain_noisy N = 5 but lost up to 40 % where the optimum is near 0 (plain and the paper's
// cost at N = 12: 26–32 iterations against 13), so the warm start keeps the primal–dual method
// (BENCHMARKS.md, session 38).
Candidate from_interior_point(const Eigen::MatrixXd& C, int d, const Options& o, bool complex_form, Stages& stages,
                              const Candidate* warm = nullptr) {
  const int n = static_cast<int>(C.rows());
  const double handoff = o.method == Method::automatic ? kHandoffGap : 0.0;
  // The primal–dual method to handoff_gap from `from` (X = I without one), as a stage.
  const auto primal_dual = [&](double handoff_gap, const detail::InteriorPointOutcome* from) {
    const Clock::time_point start = Clock::now();
    detail::InteriorPointOutcome ip = detail::solve_interior_point(C, d, o, handoff_gap, from);
    record_stage(stages, "interior_point", ip.iterations, start, outcome_of(ip));
    return ip;
  };
  detail::InteriorPointOutcome start;
  const bool has_warm = n <= kWarmStartMaxRows && warm && warm->Y.cols() >= d && warm->cert.lambda.size() > 0;
  // A rank-d attempt whose objective lies in the near-zero window starts the interior point from
  // near_zero_start instead of its own factor (kNearZeroWindowLow / High; the factor when C is
  // not PSD, where near_zero_start refuses).
  const bool in_window =
      has_warm && warm->primal >= kNearZeroWindowLow && warm->primal <= kNearZeroWindowHigh;
  // After a null space with room and no feasible X the optimum may be near 0, where dual scaling
  // crawls: up to kWarmStartMaxRows rows the primal–dual method (from_rank_d_or_null_space), from
  // near_zero_start (X = I when C is not PSD). Against X = I (sweep, 6 seeds, the plain form at
  // noise 0.002 … 0.1 and random C of rank N + 1, N = 5 … 24): 2–4 fewer iterations to the
  // hand-off, the plain form at N = 7 0.84–0.93 of the time and at N = 8 … 12 0.86–1.08 (which
  // hand-offs the polish certified changed both ways), rank N + 1 0.94–1.0, the benchmark's
  // plain_noisy N = 7 / 8 0.1666 → 0.1520 / 0.1453 → 0.1254 ms; no status or objective changed
  // (BENCHMARKS.md, session 43). Such a zero candidate has no factor, so it is never has_warm.
  const bool near_zero = warm && warm->null_space_empty && n <= kWarmStartMaxRows;
  bool started = (in_window || near_zero) && detail::near_zero_start(C, d, start);
  if (!started)
    started = has_warm && detail::interior_start(C, d, warm->Y, warm->cert.lambda, kInteriorStartMix, start);
  const bool cold_dual_scaling = !started && o.method == Method::automatic && !near_zero;
  detail::InteriorPointOutcome ip = cold_dual_scaling
                                        ? detail::dual_scaling_then_interior_point(C, d, o, handoff, stages)
                                        : primal_dual(handoff, started ? &start : nullptr);
  if (started && !ip.handed_off && !ip.converged) ip = primal_dual(handoff, nullptr);  // the start stalled
  if (!ip.handed_off) return candidate_of(C, d, ip);
  std::optional<Candidate> polished;
  if (complex_form) {
    polished =
        complex_polish(C, detail::hermitian_of(C), detail::complex_factor_of(ip.X), kComplexPolishSteps, o, stages);
  } else {
    Candidate handed;  // only the factor: polish certifies its own result
    handed.Y = detail::leading_factor(ip.X, kHandoffFactorCutoff);
    handed.method = Method::interior_point;
    polished = polish(C, d, handed, kMaxPolishSize, kEarlyPolishSteps, true, o, stages);
  }
  if (polished && is_certified(*polished, o)) return *polished;
  return candidate_of(C, d, primal_dual(0.0, &ip));  // resumed where it handed off
}

// Whether Y (n × r) is exactly real_factor(Z) of a complex Z (n/2 × r/2): every 2 × 2 block
// [[a, −b], [b, a]]. The complex paths' factors are, entry for entry.
bool is_complex_embedding(const Eigen::MatrixXd& Y) {
  return Y.rows() % 2 == 0 && Y.cols() % 2 == 0 && detail::first_non_complex_block(Y).first < 0;
}

// The singular values of Y (n × r) above 1e-4 of the largest, counted from the eigenvalues of
// the r × r Gram matrix Yᵀ Y (their squares, so above 1e-8 of the largest): a symmetric
// eigensolve of r × r instead of a Jacobi SVD of n × r, which took 8 % of a plain N = 16 solve;
// by eigenvalues_of, not Eigen's solver (4 % of a tight N = 5 solve at r = 4). For Y =
// real_factor(Z) the Gram Yᵀ Y is the embedding of Z's Gram Zᴴ Z (r/2 × r/2), which has its
// eigenvalues, each once where Yᵀ Y has it twice: the count is twice Zᴴ Z's (the 4 × 4 real
// eigensolve was 2.7 % of a tight N = 6 solve at r = 4; BENCHMARKS.md, session 49).
int numerical_rank(const Eigen::MatrixXd& Y) {
  if (Y.cols() == 0) return 0;
  if (is_complex_embedding(Y)) {
    const Eigen::MatrixXcd Z = detail::complex_of_real_factor(Y);  // n/2 × r/2
    const Eigen::MatrixXcd gram = Z.adjoint() * Z;                  // r/2 × r/2
    Eigen::VectorXd w;  // its eigenvalues
    if (gram.rows() == 2) {  // in closed form: the mean ± √(half the difference² + |off-diagonal|²)
      const double mean = 0.5 * (gram(0, 0).real() + gram(1, 1).real());
      const double half = 0.5 * (gram(0, 0).real() - gram(1, 1).real());
      const double radius = std::sqrt(half * half + std::norm(gram(1, 0)));
      w = Eigen::Vector2d(mean - radius, mean + radius);
    } else {
      w = detail::eigenvalues_of(gram);
    }
    return 2 * static_cast<int>((w.array() > 1e-8 * w.maxCoeff()).count());
  }
  const Eigen::MatrixXd gram = Y.transpose() * Y;  // r × r
  const Eigen::VectorXd w = detail::eigenvalues_of(gram);
  return static_cast<int>((w.array() > 1e-8 * w.maxCoeff()).count());
}

// Eigenvalues of the scaled S below null_tol.
int nullity(const Certificate& cert, const Options& o) {
  return static_cast<int>((cert.eigenvalues.array() < o.null_tol).count());
}

// A certificate whose S has nullity exactly d proves the optimum unique and of rank d. Such a
// proof is only path-independent when Λ is the optimum's own multiplier: for a rank-d optimum Y
// (n × d, every d × d block orthogonal) S Y = 0 forces Λ_ii = (C Y)_i Y_iᵀ, so that Λ is the only
// optimal dual, and whether its S has nullity d is a property of the problem. The interior point's
// Λ is only near-optimal; where the optimum is not strictly complementary (noise-free plain form,
// N + 1 rounds: the optimum is 0, the only optimal Λ is 0 and S = C has nullity N − 1) its S still
// shows λ_{d+1} of the order of √μ, above or below null_tol depending on where the iterations
// stopped, and the status then depended on the path and on the machine's rounding (the ARM64
// cross check: x86-64 "unique" through the interior point, arm64 "not unique" through rank-d
// Newton, BENCHMARKS.md, session 20). A staircase level still crawling toward such an optimum
// does the same through its unconverged factor (complex form, N = 4, 2 rounds, seed 32: X of
// rank 4 after 59 steps, λ_3(S) = 1.1e-10). So a result whose certificate claims nullity d, from
// the interior point or with X of numerical rank above d, is taken to rank d (Newton from X's
// top-d eigenvectors) and certified against that factor's own Λ, which then decides the status;
// when that does not certify the result stands as it was. On the complex form Λ keeps the form
// μ_i I₂ (certify_factor's complex_form), so its certificate stays that of the Hermitian problem.
// Automatic mode only (an explicit method returns its own factor and certificate).
Candidate at_unique_rank(const Eigen::MatrixXd& C, int d, Candidate c, const Options& o, bool complex_form,
                         Stages& stages) {
  if (!is_certified(c, o) || nullity(c.cert, o) != d) return c;
  const Clock::time_point start = Clock::now();
  // X's top-d eigenvectors scaled by √eigenvalue, Y V_d with V_d the top-d eigenvectors of the
  // r × r Gram matrix Yᵀ Y (r is up to n for the interior point's factor): n × d.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> gram(c.Y.transpose() * c.Y);
  Eigen::MatrixXd Y = c.Y * gram.eigenvectors().rightCols(d);
  if (!detail::project_blocks(Y, d)) return c;
  Candidate polished = c;
  int steps = detail::newton_refine(C, d, Y, 20, 1e-12);
  polished.Y = std::move(Y);
  certify_factor(C, d, polished, complex_form);
  polished = with_one_more_step(C, d, std::move(polished), o, steps, complex_form);
  record_stage(stages, "unique_rank_newton", steps, start, outcome_of(polished, o));
  return is_certified(polished, o) ? polished : c;
}

void classify(Result& r, const Candidate& c, const Options& o) {
  using detail::printed;
  const Eigen::VectorXd& ev = c.cert.eigenvalues;
  r.nullity = nullity(c.cert, o);
  r.eig_gap = ev.size() > r.d ? ev[r.d] : 0.0;
  const std::string note = c.note.empty() ? "" : " (" + c.note + ")";
  if (c.Y.size() == 0) {
    r.reason = printed("%s found no primal point", to_string(c.method)) + note;
    r.status = Status::not_certified;
  } else if (const double infeasible = feasibility_error(c.Y, r.d); !(infeasible <= kFeasibilityTol)) {
    r.reason = printed("%s gave an infeasible X: a block of Y Yᵀ is off I by %g", to_string(c.method), infeasible) + note;
    r.status = Status::not_certified;
  } else if (!(r.min_eig_S >= -o.psd_tol)) {  // (NaN too)
    r.reason = printed("S = C − Λ has λ_min = %g < −%g after %d %s iterations", r.min_eig_S, o.psd_tol, r.iterations,
                       to_string(c.method)) + note;
    r.status = Status::not_certified;
  } else if (!gap_closes(c, o)) {
    r.reason = printed("relative duality gap %g > %g", r.rel_gap, o.gap_tol) + note;
    r.status = Status::not_certified;
  } else if (r.nullity != r.d) {
    // Nullity above d does not prove other optima exist (the optimum may be unique without being
    // strictly complementary, as on noise-free rounds with few of them; see at_unique_rank): the
    // reason says no more than the certificate.
    r.reason = printed("optimal, but S has nullity %d > d = %d (λ_%d(S) = %g < %g): other optima may exist; X has rank %d",
                       r.nullity, r.d, r.d + 1, r.eig_gap, o.null_tol, r.rank);
    r.status = Status::certified_not_unique;
  } else if (r.rank > r.d) {
    // A unique optimum has rank d; X of higher rank with S of nullity d means S's smallest
    // eigenvalues are at the level of psd_tol, where the count does not decide (review: λ_min(S)
    // = −1.2e-10 and λ_2(S) = 1.3e-10 with X of rank 2 for d = 1, nullity 2 at a tighter gap).
    r.reason = printed("optimal; S has nullity %d = d, but X has rank %d > d = %d (λ_min(S) = %g, λ_%d(S) = %g): "
                       "other optima may exist", r.nullity, r.rank, r.d, r.min_eig_S, r.d + 1, r.eig_gap);
    r.status = Status::certified_not_unique;
  } else {
    r.reason = printed("optimal and unique: λ_min(S) = %g, nullity %d, λ_%d(S) = %g", r.min_eig_S, r.nullity, r.d + 1,
                       r.eig_gap);
    r.status = Status::certified_unique;
  }
  if (r.certified() && r.rel_gap > o.gap_tol)
    r.reason += printed("; relative gap %g > %g, but the gap %g is within the bound's rounding (bound_error %g)",
                        r.rel_gap, o.gap_tol, c.primal - c.cert.dual_bound, c.cert.bound_error);
}

}  // namespace

Result solve(const Eigen::MatrixXd& C, int d, const Options& options) {
  const auto start = std::chrono::steady_clock::now();
  Result r;
  r.d = d;
  r.reason = validate(C, d);
  if (r.reason.empty()) r.reason = validate(options);
  if (!r.reason.empty()) return r;
  r.blocks = static_cast<int>(C.rows() / d);
  // ‖C‖_F without overflow or underflow: C.norm() is inf from entries of 1e154 on and 0 below
  // 1e-162, which left C unscaled against absolute tolerances; outside its safe range the scaled
  // sum (stableNorm) is used. Inside it norm() stays: stableNorm differs in the last bit, and that
  // alone took plain_noisy N = 4 (one sweep seed) from 4 Newton steps to 27 (session 24). The
  // scaled C is made exactly symmetric, since the eigensolvers read one triangle and validate
  // allows 1e-9 of asymmetry.
  double norm = C.norm();
  if (!(norm > 1e-140 && norm < 1e140)) norm = C.stableNorm();
  r.scale = norm > 0 ? norm : 1.0;
  Eigen::MatrixXd Cs = C / r.scale;  // scaled problem, ‖Cs‖_F = 1 (or C = 0)
  Cs = (0.5 * (Cs + Cs.transpose())).eval();

  const bool complex_form = d == 2 && (options.method == Method::automatic || options.method == Method::complex_low_rank) &&
                            detail::complex_embedding_mismatch(Cs).empty();
  if (options.method == Method::complex_low_rank && !complex_form) {
    r.reason = "method complex_low_rank: " +
               (d != 2 ? "d = " + std::to_string(d) + ", needs d = 2" : detail::complex_embedding_mismatch(C));
    return r;
  }
  Candidate best;
  Stages stages;
  stages.reserve(4);
  const bool try_low_rank = options.method != Method::interior_point && options.method != Method::null_space;
  if (complex_form)
    best = from_complex_low_rank(Cs, options, stages);
  else if (options.method == Method::automatic)
    best = from_rank_d_or_null_space(Cs, d, options, stages);
  else if (options.method == Method::null_space)
    best = from_null_space(Cs, d, options, stages);
  else if (try_low_rank)
    best = from_low_rank(Cs, d, options, stages);
  if (options.method == Method::interior_point ||
      (options.method == Method::automatic && !is_certified(best, options))) {
    // Complex form: the N × N complex interior point first, the 2N × 2N real one when it does
    // not certify.
    Candidate ip;
    if (complex_form) ip = from_complex_interior_point(Cs, options, best.Y, stages);
    if (!complex_form || !is_certified(ip, options))
      ip = from_interior_point(Cs, d, options, complex_form, stages, try_low_rank && !complex_form ? &best : nullptr);
    if (options.method == Method::automatic && !is_certified(ip, options)) {
      std::optional<Candidate> polished = polish(Cs, d, ip, kMaxPolishSize, 60, false, options, stages);
      if (polished && is_certified(*polished, options)) ip = std::move(*polished);
    }
    // (a staircase outcome without a spectrum has no bound: the interior point's result replaces it)
    if (!try_low_rank || is_certified(ip, options) || ip.cert.dual_bound > best.cert.dual_bound ||
        best.cert.eigenvalues.size() == 0)
      best = ip;
  }
  int rank = numerical_rank(best.Y);
  // (a low-rank path's rank-d certificate is its own factor's already)
  if (options.method == Method::automatic && (rank > d || (rank == d && best.method == Method::interior_point))) {
    best = at_unique_rank(Cs, d, std::move(best), options, complex_form, stages);
    rank = numerical_rank(best.Y);
  }

  const double primal = best.primal;
  r.method_used = best.method;
  r.Y = best.Y;
  r.Lambda = best.cert.lambda * r.scale;
  r.objective = primal * r.scale;
  r.dual_bound = best.cert.dual_bound * r.scale;
  // (the product with the scale rounds once more)
  r.bound_error = best.cert.bound_error * r.scale + 2 * std::numeric_limits<double>::epsilon() * std::abs(r.dual_bound);
  r.rel_gap = relative_gap(primal, best.cert.dual_bound);
  r.min_eig_S = best.cert.min_eig;
  r.rank = rank;
  r.iterations = 0;
  for (const Stage& stage : stages) r.iterations += stage.iterations;
  r.stages = std::move(stages);
  classify(r, best, options);  // (without a primal point it reads only that)
  if (best.Y.size() == 0) {      // no primal point (an explicit method that found none): no figures either
    const double nan = std::numeric_limits<double>::quiet_NaN();
    r.objective = r.dual_bound = r.bound_error = r.rel_gap = r.min_eig_S = r.eig_gap = nan;
  }
  r.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace fact::sdp
