// The interior point's handoff and resume (lib/sdp/internal.h): in automatic mode the solver
// stops the interior point at a relative gap of 1e-5, tries a short Newton polish, and resumes
// the interior point from where it stopped when the polish does not certify. These tests check
// that the stop happens below the asked gap and that a resumed run ends where one uninterrupted
// run ends, on the scaled problem (‖C‖_F = 1) the solver passes in. The complex interior point
// (the N × N Hermitian form of a complex-form cost) is checked against the real one. The
// triangular kernels of every iteration (L⁻¹ and Z⁻¹ = L⁻ᴴ L⁻¹ by recursive blocks) are checked
// against dense products, across their blocking thresholds, and Newton's system in Schur form
// against the one in tangent bases. The crawl watch that ends the rank-2 attempt above 48 rows is
// checked on given costs and on random C of full and of low rank.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>


#include "complex_product.h"
#include "internal.h"
#include "sdp_test_costs.h"
#include "step_length.h"

namespace {

using fact::sdp::detail::ComplexInteriorPointOutcome;
using fact::sdp::Options;
using fact::sdp::detail::InteriorPointOutcome;
using fact::sdp::detail::solve_interior_point;

// The paper's plain cost of a noisy swarm of `drones` (2N × 2N), scaled to ‖C‖_F = 1.
Eigen::MatrixXd scaled_plain_cost(int drones, std::uint64_t seed) {
  const Eigen::MatrixXd C = fact::test::noisy_plain_cost(drones, seed);
  return C / C.norm();
}

// The Hermitian form H (N × N) of the complex form of the noisy plain cost, scaled to ‖C‖_F = 1.
Eigen::MatrixXcd complex_test_problem(int drones, std::uint64_t seed) {
  const Eigen::MatrixXd C0 = fact::sdp::complex_form(fact::test::noisy_plain_cost(drones, seed));
  return fact::sdp::detail::hermitian_of(C0 / C0.norm());
}

// Re tr(H X) for an outcome's X.
double complex_objective(const Eigen::MatrixXcd& H, const ComplexInteriorPointOutcome& ip) {
  return (H.array() * ip.X.array().conjugate()).real().sum();
}

// The primal–dual method resumed from `handed` (a handed-off, strictly feasible pair) converges,
// counts the handed-off iterations, and ends at the optimum of `whole`, an uninterrupted run:
// objective and Σ y within 1e-9 relative, to at least 0.5e-4 as the runs' own stopping gap
// (complex_relative_gap's floor): each run stops within that gap of the optimum, and the N = 80
// problem's optimum is 2.7e-5. Returns the resumed outcome.
ComplexInteriorPointOutcome expect_resumes_to(const Eigen::MatrixXcd& H, const ComplexInteriorPointOutcome& handed,
                                              const ComplexInteriorPointOutcome& whole) {
  const ComplexInteriorPointOutcome rest = fact::sdp::detail::solve_complex_interior_point(H, Options{}, 0.0, &handed);
  EXPECT_TRUE(rest.converged) << rest.reason;
  EXPECT_GT(rest.iterations, handed.iterations);
  const double optimum = complex_objective(H, whole);
  const double tolerance = 1e-9 * std::max(0.5e-4, std::abs(optimum));
  EXPECT_NEAR(complex_objective(H, rest), optimum, tolerance);
  EXPECT_NEAR(rest.y.sum(), whole.y.sum(), tolerance);
  return rest;
}

// The options of automatic mode's rank-2 attempt, for solve_low_rank called directly: rank 2
// only, at most 25 Newton steps.
Options rank_two_attempt() {
  Options o;
  o.method = fact::sdp::Method::low_rank;
  o.max_rank = 2;
  o.max_newton_iterations = 25;
  return o;
}

// C = B Bᵀ for a Gaussian B (n × columns, drawn from rng), scaled to ‖C‖_F = 1.
Eigen::MatrixXd scaled_random_psd(Eigen::Index n, Eigen::Index columns, std::mt19937& rng,
                                  std::normal_distribution<double>& gauss) {
  const Eigen::MatrixXd B = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, columns, rng, gauss);
  const Eigen::MatrixXd C = B * B.transpose();
  return C / C.norm();
}

// ⟨C, X⟩ − tr Λ = ⟨X, C − blkdiag(Λ)⟩: the duality gap of a feasible iterate.
double gap_of(const Eigen::MatrixXd& C, const InteriorPointOutcome& ip) {
  const double primal = C.cwiseProduct(ip.X).sum();
  double dual = 0;
  for (Eigen::Index i = 0; i < ip.lambda.rows(); i += 2) dual += ip.lambda(i, 0) + ip.lambda(i + 1, 1);
  return (primal - dual) / std::max({1e-4, std::abs(primal), std::abs(dual)});
}

void expect_feasible(const InteriorPointOutcome& ip) {
  for (Eigen::Index i = 0; i < ip.X.rows(); i += 2)
    EXPECT_LT((ip.X.block(i, i, 2, 2) - Eigen::Matrix2d::Identity()).norm(), 1e-12) << "block " << i / 2;
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(ip.X).eigenvalues().minCoeff(), -1e-12);
}

// A start for the interior point (iterations 0) that is strictly feasible: identity blocks,
// X ≻ 0 and C − Λ ≻ 0.
void expect_strictly_feasible_start(const Eigen::MatrixXd& C, const InteriorPointOutcome& start) {
  EXPECT_EQ(start.iterations, 0);
  expect_feasible(start);
  EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(start.X).info(), Eigen::Success);
  EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(fact::sdp::detail::certificate_matrix(C, start.lambda, 2)).info(),
            Eigen::Success);
}

// The primal–dual method from `start` converges, feasible, within a relative gap of tol, to the
// objective of the run from X = I (within tol). Returns the iterations of the two runs, the
// started one first.
std::pair<int, int> expect_ends_at_the_cold_optimum(const Eigen::MatrixXd& C, const InteriorPointOutcome& start,
                                                    double tol) {
  const Options o;
  const InteriorPointOutcome cold = solve_interior_point(C, 2, o);
  const InteriorPointOutcome started = solve_interior_point(C, 2, o, 0.0, &start);
  EXPECT_TRUE(cold.converged) << cold.reason;
  EXPECT_TRUE(started.converged) << started.reason;
  expect_feasible(started);
  EXPECT_LT(gap_of(C, started), tol);
  EXPECT_NEAR(C.cwiseProduct(started.X).sum(), C.cwiseProduct(cold.X).sum(), tol);
  return {started.iterations, cold.iterations};
}

TEST(SdpInteriorPoint, HandsOffBelowTheGapAndResumesToWhereOneRunEnds) {
  for (int drones : {4, 8}) {
    SCOPED_TRACE("N = " + std::to_string(drones));
    const Eigen::MatrixXd C = scaled_plain_cost(drones, 11 + drones);
    const Options o;
    const InteriorPointOutcome whole = solve_interior_point(C, 2, o);
    const InteriorPointOutcome early = solve_interior_point(C, 2, o, 1e-5);
    ASSERT_TRUE(early.handed_off) << early.reason;
    EXPECT_FALSE(early.converged);
    EXPECT_LT(gap_of(C, early), 1e-5);
    EXPECT_GT(gap_of(C, early), 0.1 * o.gap_tol);  // it stopped before converging
    EXPECT_LT(early.iterations, whole.iterations);
    expect_feasible(early);

    const InteriorPointOutcome rest = solve_interior_point(C, 2, o, 0.0, &early);
    EXPECT_FALSE(rest.handed_off);
    expect_feasible(rest);
    EXPECT_LT(gap_of(C, rest), 1e-7) << rest.reason;
    // The same optimum as one uninterrupted run, within the gaps both reached.
    EXPECT_NEAR(C.cwiseProduct(rest.X).sum(), C.cwiseProduct(whole.X).sum(), 1e-7);
    EXPECT_LE(early.iterations + rest.iterations, whole.iterations + 3);
  }
}

TEST(SdpInteriorPoint, NoHandoffGapNeverHandsOff) {
  const Eigen::MatrixXd C = scaled_plain_cost(6, 5);
  const InteriorPointOutcome ip = solve_interior_point(C, 2, Options{});
  EXPECT_FALSE(ip.handed_off);
  EXPECT_LT(gap_of(C, ip), 1e-7) << ip.reason;
}

// The cold start shifts Z = C + s·I by s = 1/√n, on C's scale, and by s = 2 when C + s·I is not
// positive definite (C need not be PSD). Every feasible X has tr X = n, so C and C + κ·I have the
// same optimal X and objectives κ·n apart: the run on an indefinite C (λ_min = −1 ≪ −1/√n, the
// fallback's start) and the run on the PSD C + I (scaled again, 1/√n's start) must agree.
TEST(SdpInteriorPoint, ColdStartOnAnIndefiniteCostEndsAtTheShiftedCostsOptimum) {
  std::mt19937 rng(31);
  std::normal_distribution<double> gauss;
  const Eigen::Index n = 16;
  const Eigen::VectorXd v = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, 1, rng, gauss);
  const Eigen::MatrixXd B = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, 4, rng, gauss);
  Eigen::MatrixXd C = 0.2 * B * B.transpose() / B.squaredNorm() - v * v.transpose() / v.squaredNorm();
  C /= C.norm();  // ‖C‖_F = 1, as the solver passes it
  ASSERT_LT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(C).eigenvalues().minCoeff(), -0.9);
  const Eigen::MatrixXd shifted_unscaled = C + Eigen::MatrixXd::Identity(n, n);  // PSD
  const double shifted_norm = shifted_unscaled.norm();
  const Eigen::MatrixXd shifted = shifted_unscaled / shifted_norm;

  const InteriorPointOutcome indefinite = solve_interior_point(C, 2, Options{});
  const InteriorPointOutcome psd = solve_interior_point(shifted, 2, Options{});
  ASSERT_TRUE(indefinite.converged) << indefinite.reason;
  ASSERT_TRUE(psd.converged) << psd.reason;
  expect_feasible(indefinite);
  EXPECT_LT(gap_of(C, indefinite), 1e-7);
  const double objective = C.cwiseProduct(indefinite.X).sum();
  const double shifted_objective = shifted_norm * shifted.cwiseProduct(psd.X).sum() - static_cast<double>(n);
  EXPECT_NEAR(objective, shifted_objective, 1e-7 * static_cast<double>(n));
}

// A cost whose λ_min is −1/√n after scaling (a rotated reflection R = Q diag(−1, 1, …, 1) Qᵀ,
// n = 8): C + I/√n is singular, and when rounding let it pass the Cholesky test the interior
// point started from a nearly singular Z and stalled at a relative gap of 3e-4 (d = 1) and 3e-2
// (d = 2), not certified (review, session 27). The shift is now taken only when C + (s/2)·I passes,
// so these start from s = 2 and certify, as before the change, through the explicit interior
// point and through automatic mode.
TEST(SdpInteriorPoint, ColdStartNextToTheShiftsEdgeStillCertifies) {
  const int n = 8;
  std::mt19937 rng(3008);
  std::normal_distribution<double> gauss;
  Eigen::MatrixXd G(n, n);  // Gaussian, drawn row by row (the review's reproducer)
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) G(i, j) = gauss(rng);
  const Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(G).householderQ();  // orthogonal, n × n
  Eigen::VectorXd signs = Eigen::VectorXd::Ones(n);
  signs[0] = -1.0;
  Eigen::MatrixXd R = Q * signs.asDiagonal() * Q.transpose();
  R = (0.5 * (R + R.transpose())).eval();
  ASSERT_NEAR(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(R / R.norm()).eigenvalues()[0], -1.0 / std::sqrt(n), 1e-14);
  for (int d : {1, 2}) {
    SCOPED_TRACE("d = " + std::to_string(d));
    Options interior;
    interior.method = fact::sdp::Method::interior_point;
    for (const Options& o : {interior, Options{}}) {
      const fact::sdp::Result r = fact::sdp::solve(R, d, o);
      EXPECT_TRUE(r.certified()) << fact::sdp::to_string(r.status) << ": " << r.reason;
      EXPECT_LT(r.rel_gap, 1e-9);
    }
  }
}

// The real interior point from the rank-2 factor of the automatic solve's first attempt (noisy
// plain form, N = 8, whose optimum has rank > 2, so the attempt does not certify): the start is
// strictly feasible (identity blocks, X ≻ 0, C − Λ ≻ 0) and the run from it ends at the optimum
// of the run from X = I. Multipliers that no shift up to 1 makes dual feasible give no start.
TEST(SdpInteriorPoint, WarmStartFromARankTwoFactorEndsAtTheColdOptimum) {
  const Eigen::MatrixXd C = scaled_plain_cost(8, 19);
  const Options rank_two = rank_two_attempt();
  const fact::sdp::detail::LowRankOutcome attempt = fact::sdp::detail::solve_low_rank(C, 2, rank_two);
  ASSERT_FALSE(attempt.certified);
  ASSERT_EQ(attempt.Y.cols(), 2);

  InteriorPointOutcome start;
  ASSERT_TRUE(fact::sdp::detail::interior_start(C, 2, attempt.Y, attempt.certificate.lambda, 0.65, start));
  const Eigen::MatrixXd expected_X =
      0.35 * attempt.Y * attempt.Y.transpose() + 0.65 * Eigen::MatrixXd::Identity(C.rows(), C.rows());
  EXPECT_LT((start.X - expected_X).cwiseAbs().maxCoeff(), 1e-14);  // the factor, mixed with I
  expect_strictly_feasible_start(C, start);
  expect_ends_at_the_cold_optimum(C, start, 1e-7);

  InteriorPointOutcome untouched;
  // Λ_ii = 10·I₂: C − Λ + s·I has λ_max(C) − 10 + s < 0 for s ≤ 1 (λ_max(C) ≤ ‖C‖_F = 1)
  const Eigen::MatrixXd too_large = 10.0 * Eigen::Matrix2d::Identity().replicate(C.rows() / 2, 1);
  EXPECT_FALSE(fact::sdp::detail::interior_start(C, 2, attempt.Y, too_large, 0.65, untouched));
  EXPECT_EQ(untouched.X.size(), 0);
}

// The near-zero start on the plain form with N + 1 rounds under noise (N = 7 and 8, the
// benchmark's plain_noisy), whose optimum is about 1e-4 of ‖C‖ and whose null space holds no
// feasible X: strictly feasible (identity blocks, X ≻ 0, Λ = −s·I with C − Λ ≻ 0), a
// complementarity μ₀ = ⟨X, C − Λ⟩/n under a tenth of the cold start's, and fewer iterations to
// the optimum of the run from X = I. Automatic mode takes it (interior_point first: at N = 7 and
// 8 the null space leaves room for few points only and is not tried):
// its interior point reaches the hand-off (a relative gap of 1e-5, solve.cpp's kHandoffGap) in
// as many iterations as the run from this start, fewer than from X = I. A C with a negative
// eigenvalue beyond s/2 gives no start.
TEST(SdpInteriorPoint, NearZeroStartIsCloserAndEndsAtTheColdOptimum) {
  using fact::sdp::detail::kNearZeroShift;
  const Options o;
  for (int drones : {7, 8}) {
    SCOPED_TRACE("N = " + std::to_string(drones));
    const Eigen::MatrixXd C0 = fact::test::plain_cost(drones, drones + 1, 0.05, 2000 + drones);
    const Eigen::MatrixXd C = C0 / C0.norm();
    const Eigen::Index n = C.rows();
    InteriorPointOutcome start;
    ASSERT_TRUE(fact::sdp::detail::near_zero_start(C, 2, start));
    expect_strictly_feasible_start(C, start);
    const Eigen::MatrixXd expected_lambda = -kNearZeroShift * Eigen::Matrix2d::Identity().replicate(n / 2, 1);
    EXPECT_EQ(start.lambda, expected_lambda);
    const Eigen::MatrixXd Z = fact::sdp::detail::certificate_matrix(C, start.lambda, 2);  // C − Λ
    const double mu0 = start.X.cwiseProduct(Z).sum() / static_cast<double>(n);
    const double cold_shift = fact::sdp::detail::cold_start_shift(C);
    const double cold_mu0 = (C.trace() + static_cast<double>(n) * cold_shift) / static_cast<double>(n);
    EXPECT_LT(mu0, 0.1 * cold_mu0);
    const auto [near_iterations, cold_iterations] = expect_ends_at_the_cold_optimum(C, start, 1e-9);
    EXPECT_LT(near_iterations, cold_iterations);

    const fact::sdp::Result automatic = fact::sdp::solve(C0, 2);
    ASSERT_GE(automatic.stages.size(), 1u);
    ASSERT_EQ(automatic.stages[0].method, "interior_point");
    const InteriorPointOutcome handed = solve_interior_point(C, 2, o, 1e-5, &start);
    const InteriorPointOutcome cold_handed = solve_interior_point(C, 2, o, 1e-5);
    EXPECT_TRUE(handed.handed_off) << handed.reason;
    EXPECT_EQ(automatic.stages[0].iterations, handed.iterations);
    EXPECT_LT(handed.iterations, cold_handed.iterations);
  }
  const Eigen::MatrixXd C = scaled_plain_cost(8, 19);
  Eigen::MatrixXd indefinite = C;  // λ_min(C) moved to −s
  indefinite.diagonal().array() -= Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(C).eigenvalues()[0] + kNearZeroShift;
  InteriorPointOutcome untouched;
  EXPECT_FALSE(fact::sdp::detail::near_zero_start(indefinite, 2, untouched));
  EXPECT_EQ(untouched.X.size(), 0);
}

// solve.cpp's near-zero window: when the rank-2 attempt ends, uncertified, at an objective in
// [1e-4, 0.1] of ‖C‖ (the paper's noisy cost, N + 1 rounds, noise 0.05; the benchmark's
// plain_noisy N = 5 and 6), automatic mode's interior point runs from near_zero_start: its stage
// takes as many iterations as the run from that start to the hand-off (a relative gap of 1e-5).
// Below the window (2N rounds at noise 0.01, where the attempt ends within 3e-5 of ‖C‖ of the
// optimum) it runs from the attempt's factor, not from the near-zero start: the stage takes
// another number of iterations than the run from that start (N = 16, seed 8601: 14 against 12).
// (The factor took 10–12 iterations there, 0–2 fewer than the near-zero start, until session 45;
// with the grid's step lengths it takes 11–14, 0–2 more, but moving the window's lower edge to 0
// measured 1.00 of the time on a sweep, so the window stayed.)
TEST(SdpInteriorPoint, AttemptsEndingInTheNearZeroWindowStartFromNearZero) {
  const Options o;
  const auto interior_point_stage = [](const fact::sdp::Result& r) {
    for (const fact::sdp::Stage& stage : r.stages)
      if (stage.method == "interior_point") return stage.iterations;
    return -1;
  };
  for (int drones : {5, 6}) {
    SCOPED_TRACE("N = " + std::to_string(drones));
    const Eigen::MatrixXd C0 = fact::test::plain_cost(drones, drones + 1, 0.05, 2000 + drones);
    const Eigen::MatrixXd C = C0 / C0.norm();
    const fact::sdp::Result automatic = fact::sdp::solve(C0, 2);
    ASSERT_TRUE(automatic.certified()) << automatic.reason;
    ASSERT_GE(automatic.stages.size(), 2u);
    EXPECT_EQ(automatic.stages[0].method, "low_rank");
    EXPECT_EQ(automatic.stages[0].outcome, "not certified");
    InteriorPointOutcome start;
    ASSERT_TRUE(fact::sdp::detail::near_zero_start(C, 2, start));
    const InteriorPointOutcome handed = solve_interior_point(C, 2, o, 1e-5, &start);
    ASSERT_TRUE(handed.handed_off) << handed.reason;
    EXPECT_EQ(interior_point_stage(automatic), handed.iterations);
  }
  const Eigen::MatrixXd C0 = fact::test::plain_cost(16, 32, 0.01, 8601);
  const Eigen::MatrixXd C = C0 / C0.norm();
  const fact::sdp::Result automatic = fact::sdp::solve(C0, 2);
  ASSERT_TRUE(automatic.certified()) << automatic.reason;
  InteriorPointOutcome start;
  ASSERT_TRUE(fact::sdp::detail::near_zero_start(C, 2, start));
  const InteriorPointOutcome handed = solve_interior_point(C, 2, o, 1e-5, &start);
  ASSERT_TRUE(handed.handed_off) << handed.reason;
  const int stage = interior_point_stage(automatic);
  ASSERT_GT(stage, 0);
  EXPECT_NE(stage, handed.iterations);
}

// The polish's rank: every value above 1e-6 of the largest, up to the bound; at the hand-off
// (drop_ghosts) not past a ghost, a value past the d-th both below kGhostBelow of the largest
// and kGhostDrop times below the one before it. The first spectrum is a hand-off's (plain form,
// N = 8, noise 0.002, sweep seed 5, whose optimum has rank 4); in the second the small values
// fall off gradually, as genuine ones of a high-rank optimum can, and are kept.
TEST(SdpPolishRank, DropsGhostsOnlyBehindASteepFall) {
  using fact::sdp::detail::polish_rank;
  const auto values = [](std::initializer_list<double> v) {
    Eigen::VectorXd out(static_cast<Eigen::Index>(v.size()));
    std::copy(v.begin(), v.end(), out.data());
    return out;
  };
  const Eigen::VectorXd handed = values({7.9, 7.7, 0.25, 0.17, 6.0e-4, 2.8e-5, 8.5e-6});
  EXPECT_EQ(polish_rank(handed, 2, 10, false), 7);  // all above 7.9e-6
  EXPECT_EQ(polish_rank(handed, 2, 10, true), 4);
  EXPECT_EQ(polish_rank(handed, 2, 5, false), 5);   // the bound
  const Eigen::VectorXd gradual = values({8.0, 7.0, 1e-2, 3e-3, 6e-4, 2e-4});
  EXPECT_EQ(polish_rank(gradual, 2, 10, true), 6);
  const Eigen::VectorXd steep = values({8.0, 7.0, 1e-2, 3e-3, 6e-5, 2e-5});
  EXPECT_EQ(polish_rank(steep, 2, 10, true), 4);
  EXPECT_EQ(polish_rank(values({8.0, 2e-5}), 2, 10, true), 2);  // never below d
  EXPECT_EQ(polish_rank(values({8.0, 7.0, 1e-6}), 2, 10, false), 2);  // the cutoff alone
}

// The complex interior point on H (the Hermitian form of complex_form(noisy plain cost), scaled):
// its X is Hermitian PSD with unit diagonal, S = H − diag(y) is PSD, the gap is below the
// tolerance, and 2·Re tr(H X) is the real interior point's ⟨C, X⟩ on emb(H). N = 80 takes the
// large-N paths: triangular products in Lz⁻¹, its Gram and the accurate direction (blocks of
// kTriangularShapeMinSize = 40 rows and more), the triangular dual-step operator
// (kTriangularProductMinSize = 64) and the primal step through triangular solves (N > 64).
TEST(SdpComplexInteriorPoint, ConvergesToTheRealInteriorPointsOptimumWithAFeasibleDual) {
  static_assert(fact::sdp::detail::kTriangularShapeMinSize <= 40 && fact::sdp::detail::kTriangularProductMinSize < 80);
  for (int drones : {6, 12, 24, 80}) {
    SCOPED_TRACE("N = " + std::to_string(drones));
    const Eigen::MatrixXd C0 = fact::sdp::complex_form(fact::test::noisy_plain_cost(drones, 3));
    const Eigen::MatrixXd C = C0 / C0.norm();
    const Eigen::MatrixXcd H = fact::sdp::detail::hermitian_of(C);
    const Options o;
    const ComplexInteriorPointOutcome ip = fact::sdp::detail::solve_complex_interior_point(H, o, 0.0);
    EXPECT_FALSE(ip.handed_off);
    EXPECT_LT((ip.X - ip.X.adjoint()).norm(), 1e-12);
    EXPECT_LT((ip.X.diagonal().real() - Eigen::VectorXd::Ones(drones)).norm(), 1e-12);
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>(ip.X).eigenvalues().minCoeff(), -1e-12);
    Eigen::MatrixXcd S = H;  // H − diag(y), N × N
    S.diagonal() -= ip.y.cast<std::complex<double>>();
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>(S).eigenvalues().minCoeff(), -1e-12);
    const double primal = (H.array() * ip.X.array().conjugate()).real().sum(), dual = ip.y.sum();
    EXPECT_LT((primal - dual) / std::max({0.5e-4, std::abs(primal), std::abs(dual)}), o.gap_tol) << ip.reason;
    const InteriorPointOutcome real = solve_interior_point(C, 2, o);
    EXPECT_NEAR(2 * primal, C.cwiseProduct(real.X).sum(), 1e-8);

    const ComplexInteriorPointOutcome early = fact::sdp::detail::solve_complex_interior_point(H, o, 1e-5);
    EXPECT_TRUE(early.handed_off) << early.reason;
    EXPECT_LT(early.iterations, ip.iterations);
  }
}

// The complex interior point handed off at the automatic mode's gap (1e-3) and resumed from its
// iterate ends where one uninterrupted run ends, with the handed-off iterations counted.
TEST(SdpComplexInteriorPoint, HandsOffAndResumesToWhereOneRunEnds) {
  for (int drones : {12, 32}) {
    SCOPED_TRACE("N = " + std::to_string(drones));
    const Eigen::MatrixXcd H = complex_test_problem(drones, 7);
    const Options o;
    const ComplexInteriorPointOutcome whole = fact::sdp::detail::solve_complex_interior_point(H, o, 0.0);
    const ComplexInteriorPointOutcome early = fact::sdp::detail::solve_complex_interior_point(H, o, 1e-3);
    ASSERT_TRUE(early.handed_off) << early.reason;
    EXPECT_FALSE(early.converged);
    const double early_gap = (complex_objective(H, early) - early.y.sum()) / std::abs(complex_objective(H, early));
    EXPECT_LT(early_gap, 1e-3);
    EXPECT_GT(early_gap, o.gap_tol);

    const ComplexInteriorPointOutcome rest = expect_resumes_to(H, early, whole);
    EXPECT_LE(rest.iterations, whole.iterations + 3);
    EXPECT_LT((rest.X.diagonal().real() - Eigen::VectorXd::Ones(drones)).norm(), 1e-12);
  }
}

// The polish after the complex interior point's hand-off (solve.cpp: gap 1e-3, factor cutoff 1e-2):
// Newton with its shift capped at 0.1·‖grad‖ (kPolishShiftPerGradient) reaches ‖grad‖ < 1e-12 at
// the objective the uncapped rule reaches, never in more steps, and in fewer over the four instances
// (N = 12 / 20 / 32 / 48: 4 / 3 / 3 / 4 steps against 5 / 4 / 4 / 5 when written).
TEST(SdpComplexInteriorPoint, PolishWithTheShiftCappedByTheGradientTakesFewerSteps) {
  int total[2] = {0, 0};  // steps over the instances, uncapped and capped
  for (const auto& [drones, seed] : {std::pair{12, 10u}, std::pair{20, 9u}, std::pair{32, 7u}, std::pair{48, 9u}}) {
    SCOPED_TRACE("N = " + std::to_string(drones));
    const Eigen::MatrixXcd H = complex_test_problem(drones, seed);
    const ComplexInteriorPointOutcome ip = fact::sdp::detail::solve_complex_interior_point(H, Options{}, 1e-3);
    ASSERT_TRUE(ip.handed_off) << ip.reason;
    const Eigen::MatrixXcd handed = fact::sdp::detail::complex_factor(ip.X, 1e-2);  // N × p
    ASSERT_GE(handed.cols(), 2);  // the Schur-form path, where the cap applies
    int steps[2];
    double cost[2];
    for (int capped = 0; capped < 2; ++capped) {
      Eigen::MatrixXcd Y = handed;
      steps[capped] = fact::sdp::detail::complex_newton(H, Y, 10, 1e-12, false, 0.0, capped ? 0.1 : 0.0);
      const Eigen::MatrixXcd HY = H * Y;  // N × p
      Eigen::VectorXd mu;                 // the multipliers at Y (N)
      fact::sdp::detail::complex_multipliers(HY, Y, mu);
      EXPECT_LT(2.0 * (HY - mu.asDiagonal() * Y).norm(), 1e-12) << "capped = " << capped;
      cost[capped] = (Y.adjoint() * HY).trace().real();
      total[capped] += steps[capped];
    }
    EXPECT_NEAR(cost[1], cost[0], 1e-10 * std::max(0.5e-4, std::abs(cost[0])));
    EXPECT_LE(steps[1], steps[0]);
  }
  EXPECT_LT(total[1], total[0]);
}

// solve() passes the cap to the polish after complex dual scaling (N ≥ 27): over eight instances
// whose polish the cap shortened when written (N = 28 seeds 1, 2, 4, 7; N = 32 seeds 2, 4, 5, 7),
// automatic mode's first complex_newton stages (the hand-off's polish; a second one starts from
// a wider factor after a saddle, N = 32 seed 2 in sessions 48 … 51) took 26 steps in all, against
// 35 without the cap; the bound sits between the two.
TEST(SdpComplexInteriorPoint, AutomaticModeCapsThePolishShift) {
  int steps = 0;
  for (const auto& [drones, seed] : {std::pair{28, 1u}, std::pair{28, 2u}, std::pair{28, 4u}, std::pair{28, 7u},
                                     std::pair{32, 2u}, std::pair{32, 4u}, std::pair{32, 5u}, std::pair{32, 7u}}) {
    SCOPED_TRACE("N = " + std::to_string(drones) + ", seed " + std::to_string(seed));
    const Eigen::MatrixXd C = fact::sdp::complex_form(fact::test::noisy_plain_cost(drones, seed));
    const fact::sdp::Result r = fact::sdp::solve(C, 2);
    ASSERT_TRUE(r.certified()) << r.reason;
    int polish = 0;
    for (const fact::sdp::Stage& stage : r.stages)
      if (stage.method == "complex_newton") {
        polish = stage.iterations;
        break;
      }
    EXPECT_GT(polish, 0);
    steps += polish;
  }
  EXPECT_LE(steps, 30);
}

// The Schur-form Newton's skip of a first shift that failed last step: only at or below the failed
// shift, only while ‖grad‖ is above 10× it, never in the polish (shift capped by the gradient), and
// nothing to skip after a step without a failure.
TEST(SdpComplexNewton, SkipsAFirstShiftThatFailedLastStepOnlyFarFromTheOptimum) {
  using fact::sdp::detail::skipped_shift;
  EXPECT_EQ(skipped_shift(1e-5, 1e-5, 1e-3, 0.0), 1e-5);   // failed at this shift, gradient 100× above it
  EXPECT_EQ(skipped_shift(1e-6, 1e-5, 1e-3, 0.0), 1e-5);   // below a failed shift
  EXPECT_EQ(skipped_shift(1e-4, 1e-5, 1e-3, 0.0), 0.0);    // above it: tried as usual
  EXPECT_EQ(skipped_shift(1e-5, 1e-5, 5e-5, 0.0), 0.0);    // gradient within 10× of it: near the optimum
  EXPECT_EQ(skipped_shift(1e-5, 1e-5, 1e-3, 0.1), 0.0);    // the polish
  EXPECT_EQ(skipped_shift(1e-5, 0.0, 1e-3, 0.0), 0.0);     // no failure last step
}

// N = 28 seed 8: the Newton polish from the hand-off's factor (X down to 1e-2) ends at a saddle,
// λ_min(S) < 0, after 4 steps, before its kComplexHandoffSteps. Newton from X's factor down to 1e-3
// certifies an optimum of rank 4, where the interior point used to resume; the optimum is the one
// the interior point alone reaches. Which instances end at such a saddle depends on the kernels'
// rounding: until session 52 this was N = 32 seed 2, whose first polish certifies since the
// padded factor became LDLᵀ; N = 28 seed 8 reached the saddle with both factors.
TEST(SdpComplexInteriorPoint, HandoffPolishAtASaddleStartsAgainFromAWiderFactor) {
  const Eigen::MatrixXd C = fact::sdp::complex_form(fact::test::noisy_plain_cost(28, 8));
  const fact::sdp::Result r = fact::sdp::solve(C, 2);
  ASSERT_TRUE(r.certified()) << r.reason;
  std::vector<std::string> methods;
  for (const fact::sdp::Stage& stage : r.stages) methods.push_back(stage.method);
  ASSERT_EQ(methods, (std::vector<std::string>{"complex_low_rank", "complex_dual_scaling", "complex_newton",
                                               "complex_newton"}));
  EXPECT_EQ(r.stages[2].outcome, "not certified");
  EXPECT_EQ(r.stages[3].outcome, "certified");
  EXPECT_GE(r.rank, 3);
  Options ip;
  ip.method = fact::sdp::Method::interior_point;
  const fact::sdp::Result reference = fact::sdp::solve(C, 2, ip);
  ASSERT_TRUE(reference.certified()) << reference.reason;
  EXPECT_NEAR(r.objective, reference.objective, 1e-9 * std::abs(reference.objective));
  EXPECT_LE(r.rel_gap, 1e-9);
}

// The warm start from the staircase's rank-1 factor (the path solve() takes at N ≥ 27): strictly
// feasible (unit diagonal, X ≻ 0, H − diag(y) ≻ 0), and the interior point from it ends at the
// optimum of a cold run.
TEST(SdpComplexInteriorPoint, WarmStartFromARankOneFactorEndsAtTheColdOptimum) {
  const int drones = 32;
  const Eigen::MatrixXcd H = complex_test_problem(drones, 7);
  const Options o;
  Eigen::MatrixXcd Y = fact::sdp::detail::bottom_eigenvectors(H, 1, 64);  // N × 1
  Y.rowwise().normalize();
  fact::sdp::detail::complex_newton(H, Y, 15, 1e-12);

  ComplexInteriorPointOutcome start;
  ASSERT_TRUE(fact::sdp::detail::complex_interior_start(H, Y, 0.65, start));
  EXPECT_EQ(start.iterations, 0);
  EXPECT_LT((start.X.diagonal().real() - Eigen::VectorXd::Ones(drones)).norm(), 1e-12);
  EXPECT_EQ(Eigen::LLT<Eigen::MatrixXcd>(start.X).info(), Eigen::Success);
  Eigen::MatrixXcd Z = H;
  Z.diagonal() -= start.y.cast<std::complex<double>>();
  EXPECT_EQ(Eigen::LLT<Eigen::MatrixXcd>(Z).info(), Eigen::Success);

  const ComplexInteriorPointOutcome cold = fact::sdp::detail::solve_complex_interior_point(H, o, 0.0);
  const ComplexInteriorPointOutcome warm = fact::sdp::detail::solve_complex_interior_point(H, o, 0.0, &start);
  ASSERT_TRUE(cold.converged) << cold.reason;
  ASSERT_TRUE(warm.converged) << warm.reason;
  EXPECT_NEAR(complex_objective(H, warm), complex_objective(H, cold), 1e-9 * std::abs(complex_objective(H, cold)));
  EXPECT_NEAR(warm.y.sum(), cold.y.sum(), 1e-9 * std::abs(complex_objective(H, cold)));
}

// Dual scaling from y = −2·1 with X = I's objective as the upper bound, handed off at a relative
// gap of 1e-3: X Hermitian positive definite with unit diagonal, H − diag(y) positive definite,
// the gap between Re tr(H X) and Σ y positive and below 1e-3 (relative), and the primal–dual
// method resumed from the pair ends at the optimum of a cold primal–dual run, also from the pair of
// a run stopped after 4 iterations. N = 80 takes the triangular paths of the inverse, the Gram and
// the dual step's operator.
TEST(SdpComplexDualScaling, HandsOffAFeasiblePairThePrimalDualMethodFinishes) {
  for (int drones : {5, 32, 80}) {
    SCOPED_TRACE("N = " + std::to_string(drones));
    const Eigen::MatrixXcd H = complex_test_problem(drones, 7);
    const Options o;
    const Eigen::VectorXd y0 = Eigen::VectorXd::Constant(drones, -2.0);
    const ComplexInteriorPointOutcome scaled =
        fact::sdp::detail::solve_complex_dual_scaling(H, o, 1e-3, y0, H.diagonal().real().sum());
    ASSERT_TRUE(scaled.handed_off) << scaled.reason;
    EXPECT_FALSE(scaled.converged);
    EXPECT_GT(scaled.iterations, 1);
    EXPECT_LE(scaled.iterations, 30);  // 13 / 23 / 24 when written; slower steps take more
    EXPECT_LT((scaled.X - scaled.X.adjoint()).norm(), 1e-12);
    EXPECT_LT((scaled.X.diagonal().real() - Eigen::VectorXd::Ones(drones)).norm(), 1e-12);
    EXPECT_EQ(Eigen::LLT<Eigen::MatrixXcd>(scaled.X).info(), Eigen::Success);
    Eigen::MatrixXcd Z = H;  // H − diag(y), N × N
    Z.diagonal() -= scaled.y.cast<std::complex<double>>();
    EXPECT_EQ(Eigen::LLT<Eigen::MatrixXcd>(Z).info(), Eigen::Success);
    const double gap = complex_objective(H, scaled) - scaled.y.sum();
    EXPECT_GT(gap, 0.0);
    EXPECT_LT(gap / std::max(0.5e-4, std::abs(complex_objective(H, scaled))), 1e-3);

    const ComplexInteriorPointOutcome cold = fact::sdp::detail::solve_complex_interior_point(H, o, 0.0);
    ASSERT_TRUE(cold.converged) << cold.reason;
    expect_resumes_to(H, scaled, cold);

    // Stopped early (as when it gives up) it still returns its pair, which solve() resumes from.
    Options four = o;
    four.max_ipm_iterations = 4;
    const ComplexInteriorPointOutcome early =
        fact::sdp::detail::solve_complex_dual_scaling(H, four, 1e-3, y0, H.diagonal().real().sum());
    EXPECT_FALSE(early.handed_off || early.converged);
    ASSERT_EQ(early.X.rows(), drones) << early.reason;
    expect_resumes_to(H, early, cold);
  }
}

// Dual scaling refuses an infeasible start and an upper bound that is not above Σ y₀ (or NaN),
// and gives up, with no X and neither flag, when no primal point can beat its upper bound (here
// the optimum itself).
TEST(SdpComplexDualScaling, GivesUpWhenNoPrimalPointBeatsTheBound) {
  const int drones = 24;
  const Eigen::MatrixXcd H = complex_test_problem(drones, 7);
  const Options o;
  const Eigen::VectorXd y0 = Eigen::VectorXd::Constant(drones, -2.0);

  const ComplexInteriorPointOutcome infeasible =
      fact::sdp::detail::solve_complex_dual_scaling(H, o, 1e-3, Eigen::VectorXd::Constant(drones, 2.0), 1.0);
  EXPECT_FALSE(infeasible.handed_off || infeasible.converged);
  EXPECT_EQ(infeasible.X.size(), 0);
  EXPECT_NE(infeasible.reason.find("not positive definite"), std::string::npos) << infeasible.reason;

  for (const double bound : {y0.sum() - 1.0, y0.sum(), std::numeric_limits<double>::quiet_NaN()}) {
    SCOPED_TRACE(testing::Message() << "upper bound " << bound);
    const ComplexInteriorPointOutcome below = fact::sdp::detail::solve_complex_dual_scaling(H, o, 1e-3, y0, bound);
    EXPECT_FALSE(below.handed_off || below.converged);
    EXPECT_EQ(below.X.size(), 0);
    EXPECT_EQ(below.iterations, 1);
    EXPECT_NE(below.reason.find("is not above the dual objective"), std::string::npos) << below.reason;
  }

  const ComplexInteriorPointOutcome cold = fact::sdp::detail::solve_complex_interior_point(H, o, 0.0);
  ASSERT_TRUE(cold.converged) << cold.reason;
  const double optimum = complex_objective(H, cold);
  const ComplexInteriorPointOutcome stuck = fact::sdp::detail::solve_complex_dual_scaling(H, o, 1e-3, y0, optimum);
  EXPECT_FALSE(stuck.handed_off || stuck.converged);
  EXPECT_EQ(stuck.X.size(), 0);
  EXPECT_LT(stuck.iterations, o.max_ipm_iterations);
  EXPECT_NE(stuck.reason.find("no better primal point"), std::string::npos) << stuck.reason;
}

// The primal–dual method resumed from `handed` converges to the optimum of the uninterrupted
// run `whole`, within the gaps both reached.
void expect_real_resumes_to(const Eigen::MatrixXd& C, const InteriorPointOutcome& handed,
                            const InteriorPointOutcome& whole) {
  const InteriorPointOutcome rest = solve_interior_point(C, 2, Options{}, 0.0, &handed);
  EXPECT_TRUE(rest.converged) << rest.reason;
  expect_feasible(rest);
  EXPECT_LT(gap_of(C, rest), 1e-9);
  EXPECT_NEAR(C.cwiseProduct(rest.X).sum(), C.cwiseProduct(whole.X).sum(), 1e-9);
  EXPECT_NEAR(fact::sdp::detail::block_trace(rest.lambda, 2), fact::sdp::detail::block_trace(whole.lambda, 2), 1e-9);
}

// Random full-rank C (optimum of high rank) of 16, 64 and 128 rows and the paper's plain cost at
// N = 30, scaled, each with a name.
std::vector<std::pair<const char*, Eigen::MatrixXd>> dual_scaling_test_costs() {
  std::mt19937 rng(43);
  std::normal_distribution<double> gauss;
  std::vector<std::pair<const char*, Eigen::MatrixXd>> costs;
  costs.emplace_back("random full rank n = 16", scaled_random_psd(16, 16, rng, gauss));
  costs.emplace_back("random full rank n = 64", scaled_random_psd(64, 64, rng, gauss));
  costs.emplace_back("random full rank n = 128", scaled_random_psd(128, 128, rng, gauss));
  costs.emplace_back("plain N = 30", scaled_plain_cost(30, 9));
  return costs;
}

// Real dual scaling from the cold start, with tr C = ⟨C, I⟩ as its upper bound (as solve() runs it
// without a warm start), on random full-rank C (optimum of high rank) and on the paper's plain
// cost: a strictly feasible pair within the hand-off gap, which the primal–dual method finishes at
// the optimum of its own uninterrupted run; stopped early it still returns its pair.
TEST(SdpDualScaling, HandsOffAFeasiblePairThePrimalDualMethodFinishes) {
  const auto costs = dual_scaling_test_costs();
  for (const auto& [name, C] : costs) {
    SCOPED_TRACE(name);
    const Options o;
    const Eigen::MatrixXd lambda0 = fact::sdp::detail::cold_start_lambda(C, 2);
    const InteriorPointOutcome scaled = fact::sdp::detail::solve_dual_scaling(C, 2, o, 1e-5, lambda0, C.trace());
    ASSERT_TRUE(scaled.handed_off) << scaled.reason;
    EXPECT_FALSE(scaled.converged);
    EXPECT_GT(scaled.iterations, 1);
    EXPECT_LE(scaled.iterations, 30);  // 13–19 when written
    expect_feasible(scaled);
    EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(scaled.X).info(), Eigen::Success);
    EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(fact::sdp::detail::certificate_matrix(C, scaled.lambda, 2)).info(),
              Eigen::Success);
    EXPECT_GT(gap_of(C, scaled), 0.0);
    EXPECT_LT(gap_of(C, scaled), 1e-5);

    const InteriorPointOutcome whole = solve_interior_point(C, 2, o);
    ASSERT_TRUE(whole.converged) << whole.reason;
    expect_real_resumes_to(C, scaled, whole);

    Options four = o;
    four.max_ipm_iterations = 4;
    const InteriorPointOutcome early = fact::sdp::detail::solve_dual_scaling(C, 2, four, 1e-5, lambda0, C.trace());
    EXPECT_FALSE(early.handed_off || early.converged);
    ASSERT_EQ(early.X.rows(), C.rows()) << early.reason;
    EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(early.X).info(), Eigen::Success);
    expect_real_resumes_to(C, early, whole);
  }
}

// Dual scaling hands off at the first iterate whose true relative gap (⟨C, X⟩ of the X it returns
// against tr Λ) is below the hand-off gap h: run with one iteration fewer than it took it returns
// the same pair, and with two fewer a pair whose gap is still at least h. This checks the O(m)
// objective of its primal points, which decides when to hand off, against ⟨C, X⟩ formed in full.
TEST(SdpDualScaling, HandsOffAtTheFirstPairWhoseTrueGapIsBelowTheHandOffGap) {
  const auto costs = dual_scaling_test_costs();
  using fact::sdp::detail::solve_dual_scaling;
  for (const auto& [name, C] : costs) {
    const Eigen::MatrixXd lambda0 = fact::sdp::detail::cold_start_lambda(C, 2);
    for (const double h : {1e-1, 1e-2, 1e-3, 1e-4, 1e-5}) {
      SCOPED_TRACE(testing::Message() << name << ", h = " << h);
      const InteriorPointOutcome handed = solve_dual_scaling(C, 2, Options{}, h, lambda0, C.trace());
      ASSERT_TRUE(handed.handed_off) << handed.reason;
      ASSERT_GE(handed.iterations, 3);
      Options capped;
      capped.max_ipm_iterations = handed.iterations - 1;
      const InteriorPointOutcome last = solve_dual_scaling(C, 2, capped, h, lambda0, C.trace());
      EXPECT_EQ((last.X - handed.X).cwiseAbs().maxCoeff(), 0.0);
      EXPECT_EQ((last.lambda - handed.lambda).cwiseAbs().maxCoeff(), 0.0);
      EXPECT_LT(gap_of(C, handed), h * (1 + 1e-6));
      capped.max_ipm_iterations = handed.iterations - 2;
      const InteriorPointOutcome before = solve_dual_scaling(C, 2, capped, h, lambda0, C.trace());
      ASSERT_EQ(before.X.rows(), C.rows()) << before.reason;
      EXPECT_GE(gap_of(C, before), h * (1 - 1e-6));
    }
  }
}

// The interior point without a warm start: dual scaling alone when it hands off; when it gives up
// after finding a primal point (the paper's noise-free cost at N = 12, optimum near 0, seed 2) the
// primal–dual method resumed from its pair, and without one (N = 1: X = I is the only feasible
// point, which its upper bound already is) the primal–dual method from X = I; the iterations of
// both count, and each run is a stage of its own.
TEST(SdpDualScaling, ThenTheInteriorPointWhenItGivesUp) {
  using fact::sdp::Stage;
  using fact::sdp::detail::dual_scaling_then_interior_point;
  using fact::sdp::detail::solve_dual_scaling;
  const Options o;
  std::mt19937 rng(59);
  std::normal_distribution<double> gauss;

  const Eigen::MatrixXd full = scaled_random_psd(64, 64, rng, gauss);
  const InteriorPointOutcome alone =
      solve_dual_scaling(full, 2, o, 1e-5, fact::sdp::detail::cold_start_lambda(full, 2), full.trace());
  ASSERT_TRUE(alone.handed_off) << alone.reason;
  std::vector<Stage> stages;
  const InteriorPointOutcome handed = dual_scaling_then_interior_point(full, 2, o, 1e-5, stages);
  EXPECT_TRUE(handed.handed_off);
  EXPECT_EQ(handed.iterations, alone.iterations);
  EXPECT_EQ((handed.X - alone.X).cwiseAbs().maxCoeff(), 0.0);
  ASSERT_EQ(stages.size(), 1u);
  EXPECT_EQ(stages[0].method, "dual_scaling");
  EXPECT_EQ(stages[0].iterations, alone.iterations);
  EXPECT_EQ(stages[0].outcome, "handed off");

  Eigen::MatrixXd C = fact::test::plain_cost(12, 13, 0.0, 2);
  C /= C.norm();
  const InteriorPointOutcome gave_up =
      solve_dual_scaling(C, 2, o, 1e-5, fact::sdp::detail::cold_start_lambda(C, 2), C.trace());
  ASSERT_FALSE(gave_up.handed_off || gave_up.converged);
  ASSERT_EQ(gave_up.X.rows(), C.rows()) << gave_up.reason;
  const InteriorPointOutcome resumed = solve_interior_point(C, 2, o, 1e-5, &gave_up);
  stages.clear();
  const InteriorPointOutcome both = dual_scaling_then_interior_point(C, 2, o, 1e-5, stages);
  EXPECT_TRUE(both.handed_off || both.converged) << both.reason;
  EXPECT_EQ(both.iterations, gave_up.iterations + resumed.iterations);
  ASSERT_EQ(stages.size(), 2u);
  EXPECT_EQ(stages[0].method, "dual_scaling");
  EXPECT_EQ(stages[0].iterations, gave_up.iterations);
  EXPECT_EQ(stages[0].outcome, gave_up.reason);
  EXPECT_EQ(stages[1].method, "interior_point");
  EXPECT_EQ(stages[1].iterations, resumed.iterations);
  EXPECT_EQ((both.X - resumed.X).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LT(gap_of(C, both), 1e-5);

  const Eigen::MatrixXd one = scaled_random_psd(2, 2, rng, gauss);
  const InteriorPointOutcome none =
      solve_dual_scaling(one, 2, o, 1e-5, fact::sdp::detail::cold_start_lambda(one, 2), one.trace());
  ASSERT_EQ(none.X.size(), 0);
  const InteriorPointOutcome cold = solve_interior_point(one, 2, o, 1e-5);
  stages.clear();
  const InteriorPointOutcome fallback = dual_scaling_then_interior_point(one, 2, o, 1e-5, stages);
  EXPECT_EQ(fallback.iterations, none.iterations + cold.iterations);
  ASSERT_EQ(stages.size(), 2u);
  EXPECT_EQ(stages[0].iterations, none.iterations);
  EXPECT_EQ(stages[1].iterations, cold.iterations);
  EXPECT_EQ((fallback.X - cold.X).cwiseAbs().maxCoeff(), 0.0);
}

// Real dual scaling refuses an empty C, an infeasible start and an upper bound that is not above
// tr Λ₀ (or NaN), and gives up, with no X and neither flag, when no primal point can beat its
// upper bound (the optimum itself).
TEST(SdpDualScaling, RefusesWhatItCannotStartFromAndGivesUpBelowTheOptimum) {
  std::mt19937 rng(47);
  std::normal_distribution<double> gauss;
  const Eigen::MatrixXd C = scaled_random_psd(24, 24, rng, gauss);
  const Options o;
  const Eigen::MatrixXd lambda0 = fact::sdp::detail::cold_start_lambda(C, 2);
  using fact::sdp::detail::solve_dual_scaling;

  const InteriorPointOutcome empty = solve_dual_scaling(Eigen::MatrixXd(), 2, o, 1e-5, Eigen::MatrixXd(), 1.0);
  EXPECT_EQ(empty.X.size(), 0);
  EXPECT_NE(empty.reason.find("C is empty"), std::string::npos) << empty.reason;

  const InteriorPointOutcome infeasible =
      solve_dual_scaling(C, 2, o, 1e-5, Eigen::MatrixXd::Constant(24, 2, 2.0), C.trace());
  EXPECT_FALSE(infeasible.handed_off || infeasible.converged);
  EXPECT_EQ(infeasible.X.size(), 0);
  EXPECT_NE(infeasible.reason.find("not positive definite"), std::string::npos) << infeasible.reason;

  const double dual = fact::sdp::detail::block_trace(lambda0, 2);
  for (const double bound : {dual - 1.0, dual, std::numeric_limits<double>::quiet_NaN()}) {
    SCOPED_TRACE(testing::Message() << "upper bound " << bound);
    const InteriorPointOutcome below = solve_dual_scaling(C, 2, o, 1e-5, lambda0, bound);
    EXPECT_FALSE(below.handed_off || below.converged);
    EXPECT_EQ(below.X.size(), 0);
    EXPECT_EQ(below.iterations, 1);
    EXPECT_NE(below.reason.find("is not above the dual objective"), std::string::npos) << below.reason;
  }

  const InteriorPointOutcome whole = solve_interior_point(C, 2, o);
  ASSERT_TRUE(whole.converged) << whole.reason;
  const InteriorPointOutcome stuck = solve_dual_scaling(C, 2, o, 1e-5, lambda0, C.cwiseProduct(whole.X).sum());
  EXPECT_FALSE(stuck.handed_off || stuck.converged);
  EXPECT_EQ(stuck.X.size(), 0);
  EXPECT_LT(stuck.iterations, o.max_ipm_iterations);
  EXPECT_NE(stuck.reason.find("no better primal point"), std::string::npos) << stuck.reason;
}

// solve() in automatic mode takes dual scaling to the hand-off when the interior point has no warm
// start (n > 48): random full-rank C of 64 and 100 rows, d = 2 and d = 1, certify at the explicit
// primal–dual method's optimum.
TEST(SdpDualScaling, AutomaticModeWithoutAWarmStartCertifiesTheInteriorPointsOptimum) {
  std::mt19937 rng(53);
  std::normal_distribution<double> gauss;
  for (const auto& [n, d] : {std::pair{64, 2}, std::pair{100, 2}, std::pair{64, 1}}) {
    SCOPED_TRACE("n = " + std::to_string(n) + ", d = " + std::to_string(d));
    const Eigen::MatrixXd C = scaled_random_psd(n, n, rng, gauss);
    const fact::sdp::Result automatic = fact::sdp::solve(C, d);
    ASSERT_TRUE(automatic.certified()) << automatic.reason;
    EXPECT_EQ(automatic.method_used, fact::sdp::Method::interior_point);
    Options explicit_ip;
    explicit_ip.method = fact::sdp::Method::interior_point;
    const fact::sdp::Result reference = fact::sdp::solve(C, d, explicit_ip);
    ASSERT_TRUE(reference.certified()) << reference.reason;
    EXPECT_NEAR(automatic.objective, reference.objective, 1e-9 * std::abs(reference.objective));
    EXPECT_LE(automatic.rel_gap, 1e-9);
  }
}

// Z (n × n, Hermitian positive definite: B Bᴴ + n I for a Gaussian B), its factor L, L⁻¹ by
// invert_lower_factor and W by gram_of_lower_factor: L⁻¹ lower triangular with L⁻¹ L = I, and
// W = L⁻ᴴ L⁻¹ = Z⁻¹, Hermitian and equal to the dense product to rounding.
template <class Matrix>
void expect_triangular_kernels(int n, std::mt19937& rng) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Matrix B = fact::test::gaussian_matrix<Matrix>(n, n, rng, gauss);
  const Matrix Z = B * B.adjoint() + n * Matrix::Identity(n, n);
  Matrix L = Z;
  ASSERT_TRUE(fact::sdp::detail::cholesky_in_place(L));
  // NaN above L's diagonal and in L⁻¹'s and W's storage beforehand: the inverse must read only
  // L's lower triangle and write zeros above its own diagonal (the interior point's factors keep
  // leftovers above theirs), and the Gram must not add to what W held (the complex rank-k update
  // accumulates into W's lower triangle).
  const double nan = std::numeric_limits<double>::quiet_NaN();
  L.template triangularView<Eigen::StrictlyUpper>().setConstant(nan);
  Matrix L_inv = Matrix::Constant(n, n, nan), W = Matrix::Constant(n, n, nan);
  fact::sdp::detail::invert_lower_factor(L, L_inv);
  L = Matrix(L.template triangularView<Eigen::Lower>());
  fact::sdp::detail::gram_of_lower_factor(L_inv, W);
  const Matrix I = Matrix::Identity(n, n);
  EXPECT_LT((L_inv * L - I).cwiseAbs().maxCoeff(), 1e-13);
  EXPECT_EQ(Matrix(L_inv.template triangularView<Eigen::StrictlyUpper>()).cwiseAbs().maxCoeff(), 0.0);
  const Matrix dense = L_inv.adjoint() * L_inv;
  EXPECT_TRUE(W.allFinite());  // (maxCoeff below skips NaN entries)
  EXPECT_LT((W - dense).cwiseAbs().maxCoeff(), 1e-14 * dense.cwiseAbs().maxCoeff());
  EXPECT_LT((W * Z - I).cwiseAbs().maxCoeff(), 1e-12);
  if constexpr (Eigen::NumTraits<typename Matrix::Scalar>::IsComplex) {
    // exactly Hermitian (the three-product leaves are not by themselves: 1e-15 of max|W| apart)
    EXPECT_TRUE((W.array() == Matrix(W.adjoint()).array()).all());
  } else {
    EXPECT_LT((W - Matrix(W.adjoint())).cwiseAbs().maxCoeff(), 1e-15 * dense.cwiseAbs().maxCoeff());
  }
}

TEST(SdpTriangularKernels, InverseAndGramOfTheFactorMatchDenseProducts) {
  std::mt19937 rng(13);
  // (complex L⁻¹: padded sizes 4, 8, … 32 and panels of 24 from 33 rows; both sides of each step)
  for (int n : {1, 2, 3, 4, 5, 8, 9, 12, 13, 16, 17, 20, 21, 24, 25, 28, 29, 31, 32, 33, 48, 49, 56, 57, 64, 65, 72, 73, 79,
                80, 100, 129}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    expect_triangular_kernels<Eigen::MatrixXd>(n, rng);
    expect_triangular_kernels<Eigen::MatrixXcd>(n, rng);
  }
}

// The step length's last Cholesky test hands over what it factored (StepLength::take_tested), on
// the grid (n ≤ 48) and the Lanczos path, for a full and a block-diagonal Δ: the matrix is
// P + αΔ with the returned α, the factor's L Lᵀ is that matrix, and α stops short of the boundary
// by about τ = 0.95 and at most one coarse grid step more (P + 1.01·α/(0.7·τ)·Δ is not definite;
// GridStepLengthsStopWithinOneGridPointOfTheBoundary checks the grid's bounds); without the
// factor (factor_next = false) the same α and matrix.
TEST(SdpKernels, StepLengthHandsOverTheMatrixAndFactorItTested) {
  using fact::sdp::detail::StepLength;
  std::mt19937 rng(29);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int n : {10, 48, 64}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    const Eigen::MatrixXd B = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, n, rng, gauss);
    const Eigen::MatrixXd P = B * B.transpose() / n + 0.1 * Eigen::MatrixXd::Identity(n, n);  // n × n, ≻ 0
    const Eigen::MatrixXd G = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, n, rng, gauss);
    const Eigen::MatrixXd full = -(G + G.transpose());                                           // n × n symmetric
    Eigen::MatrixXd blocks = -fact::test::gaussian_matrix<Eigen::MatrixXd>(n, 2, rng, gauss).cwiseAbs();  // n × 2
    for (int i = 0; i < n; i += 2) blocks(i + 1, 0) = blocks(i, 1);  // symmetric 2 × 2 blocks, stacked
    Eigen::MatrixXd L = P, L_inv(n, n);
    ASSERT_TRUE(fact::sdp::detail::cholesky_in_place(L));
    fact::sdp::detail::invert_lower_factor(L, L_inv);
    for (bool block_diagonal : {false, true}) {
      SCOPED_TRACE(block_diagonal ? "block-diagonal Δ" : "full Δ");
      Eigen::MatrixXd delta = full;  // n × n
      if (block_diagonal) {
        delta.setZero();
        for (int i = 0; i < n; i += 2) delta.block(i, i, 2, 2) = blocks.middleRows(i, 2);
      }
      StepLength steps(n);
      // A predictor's call first (τ = 1: its tests, on the grid, are of other trial points), as the
      // interior point makes: it must not leave anything the corrector's hand-over would pick up.
      const double predicted = block_diagonal ? steps.block_diagonal(P, L, L_inv, blocks, 2, 1.0)
                                              : steps.full(P, L, L_inv, 1.7 * delta, 1.0);
      ASSERT_GT(predicted, 0.0);
      const double alpha = block_diagonal ? steps.block_diagonal(P, L, L_inv, blocks, 2, 0.95)
                                          : steps.full(P, L, L_inv, delta, 0.95);
      ASSERT_GT(alpha, 0.0);
      ASSERT_LT(alpha, 1.0);  // Δ has eigenvalues far below −1 against P's ≥ 0.1: the boundary is near
      Eigen::MatrixXd next, factor;
      steps.take_tested(next, factor);
      const Eigen::MatrixXd expected = P + alpha * delta;
      EXPECT_LT((next - expected).cwiseAbs().maxCoeff(), 1e-14);
      const Eigen::MatrixXd lower = factor.triangularView<Eigen::Lower>();
      EXPECT_LT((lower * lower.transpose() - next).cwiseAbs().maxCoeff(), 1e-12);
      const Eigen::LLT<Eigen::MatrixXd> beyond(P + 1.01 * alpha / (0.7 * 0.95) * delta);
      EXPECT_NE(beyond.info(), Eigen::Success);
      if (block_diagonal) continue;
      // Without the factor (factor_next = false, the interior point's X up to 48 rows): the same
      // α on the grid, and take_trial hands over P + αΔ, positive definite; on the Lanczos path
      // the flag changes nothing.
      StepLength untested(n);
      const double same = untested.full(P, L, L_inv, delta, 0.95, false);
      EXPECT_EQ(same, alpha);
      Eigen::MatrixXd trial;
      untested.take_trial(trial);
      EXPECT_LT((trial - expected).cwiseAbs().maxCoeff(), 1e-14);
      EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(trial).info(), Eigen::Success);
    }
  }
}

// The grid's step lengths (n ≤ 48) against α_max = −1/λ_min of the pencil (Δ, P) from Eigen's
// generalised eigensolver (independent of the Cholesky tests): never beyond τ·α_max, and short of
// it by at most one grid point, α ≥ r·τ·α_max with r = kPredictorStepRatio (0.7) for the
// predictor (τ = 1) and kCorrectorStepRatio (0.95) for the corrector while τ·α_max ≥ ½ (0.7
// below, where its grid coarsens); for a full Δ, a block-diagonal one, and Δ = −3P, whose
// B = −3I has one eigenvalue n times. A Δ ⪰ 0 has no boundary (α = 1); a boundary closer than the
// grid's last point (Δ = −1e5·P, α_max = 1e-5) and a Δ with a NaN get 0.
TEST(SdpKernels, GridStepLengthsStopWithinOneGridPointOfTheBoundary) {
  using fact::sdp::detail::StepLength;
  std::mt19937 rng(31);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int n : {2, 4, 10, 16, 24, 34, 48}) {
    const Eigen::MatrixXd B = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, n, rng, gauss);
    const Eigen::MatrixXd P = B * B.transpose() / n + 0.1 * Eigen::MatrixXd::Identity(n, n);  // n × n, ≻ 0
    const Eigen::MatrixXd G = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, n, rng, gauss);
    Eigen::MatrixXd L = P, L_inv(n, n);
    ASSERT_TRUE(fact::sdp::detail::cholesky_in_place(L));
    fact::sdp::detail::invert_lower_factor(L, L_inv);
    Eigen::MatrixXd blocks = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, 2, rng, gauss);  // n × 2
    for (int i = 0; i < n; i += 2) blocks(i + 1, 0) = blocks(i, 1);  // symmetric 2 × 2 blocks, stacked
    // Δ₀₀ = −2 P₀₀ − 1 puts a Rayleigh quotient of (Δ, P) below −2: the boundary is inside the full step.
    blocks(0, 0) = -2.0 * P(0, 0) - 1.0;
    StepLength steps(n);
    for (int kind = 0; kind < 3; ++kind) {
      SCOPED_TRACE("n = " + std::to_string(n) + ", Δ kind " + std::to_string(kind));
      Eigen::MatrixXd delta = kind == 0 ? Eigen::MatrixXd(G + G.transpose()) : Eigen::MatrixXd(-3.0 * P);  // n × n
      if (kind == 0) delta(0, 0) = -2.0 * P(0, 0) - 1.0;
      if (kind == 1) {
        delta.setZero();
        for (int i = 0; i < n; i += 2) delta.block(i, i, 2, 2) = blocks.middleRows(i, 2);
      }
      const double lowest =
          Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd>(delta, P, Eigen::EigenvaluesOnly).eigenvalues()[0];
      ASSERT_LT(lowest, -1.0);
      // As drawn (α_max < 1, mostly far below ½) and scaled so that α_max = 0.8, where the
      // corrector's τ·α_max is on its fine grid.
      for (double scale : {1.0, 0.8 * -lowest}) {
        const double alpha_max = -1.0 / (lowest / scale);
        for (double tau : {1.0, 0.95}) {
          const double alpha = kind == 1 ? steps.block_diagonal(P, L, L_inv, blocks / scale, 2, tau)
                                         : steps.full(P, L, L_inv, delta / scale, tau);
          const double ratio = tau == 1.0 || tau * alpha_max < 0.5 ? 0.7 : 0.95;
          EXPECT_LE(alpha, tau * alpha_max * (1 + 1e-12)) << "τ = " << tau << ", α_max = " << alpha_max;
          EXPECT_GE(alpha, ratio * tau * alpha_max * (1 - 1e-12)) << "τ = " << tau << ", α_max = " << alpha_max;
        }
      }
    }
    for (double tau : {1.0, 0.95}) {
      SCOPED_TRACE("n = " + std::to_string(n) + ", τ = " + std::to_string(tau));
      EXPECT_EQ(steps.full(P, L, L_inv, 0.5 * P, tau), 1.0);
      EXPECT_EQ(steps.full(P, L, L_inv, -1e5 * P, tau), 0.0);
      Eigen::MatrixXd nan_delta = G + G.transpose();
      nan_delta(n - 1, 0) = std::nan("");
      EXPECT_EQ(steps.full(P, L, L_inv, nan_delta, tau), 0.0);
      Eigen::MatrixXd nan_blocks = blocks;
      nan_blocks(0, 1) = std::nan("");
      EXPECT_EQ(steps.block_diagonal(P, L, L_inv, nan_blocks, 2, tau), 0.0);
    }
  }
}

// Mehrotra's centring σ = min(1, (μ_aff/μ)^e): the square and the cube, the clamp at 1 when the
// predictor's step made the complementarity grow, and 0 for a ratio below zero (a rounding
// overshoot of ⟨X + αΔX, Z + βΔZ⟩) or NaN, where the power would give a negative or NaN σ.
TEST(SdpKernels, CentringIsThePowerOfTheRatioClampedToTheUnitInterval) {
  using fact::sdp::detail::mehrotra_centring;
  EXPECT_DOUBLE_EQ(mehrotra_centring(0.5, 1.0, 2), 0.25);
  EXPECT_DOUBLE_EQ(mehrotra_centring(0.5, 1.0, 3), 0.125);
  EXPECT_DOUBLE_EQ(mehrotra_centring(3e-6, 1e-5, 3), 0.027);
  EXPECT_EQ(mehrotra_centring(2.0, 1.0, 2), 1.0);
  EXPECT_EQ(mehrotra_centring(1.0, 1.0, 3), 1.0);
  EXPECT_EQ(mehrotra_centring(0.0, 1.0, 2), 0.0);
  EXPECT_EQ(mehrotra_centring(-1e-18, 1.0, 2), 0.0);
  EXPECT_EQ(mehrotra_centring(-0.5, 1.0, 3), 0.0);
  EXPECT_EQ(mehrotra_centring(std::nan(""), 1.0, 2), 0.0);
  EXPECT_EQ(mehrotra_centring(1.0, std::nan(""), 3), 0.0);
}

// SpdSolver on each of its paths (L D Lᵀ to 12 rows, padded to 4, 8 or 12; cholesky_lower to 64
// rows: the padded L D Lᵀ kernels to 48 (right-looking padded to 16, 24 and 32, left-looking to 40
// and 48) and by columns above; Eigen's blocked kernel in place above; and
// back, so that a smaller L D Lᵀ system follows a larger one in the same padding and in another):
// x = A⁻¹ b for A = B Bᵀ + n I, with x aliasing b, and the same x with A's strict upper triangle
// NaN (only the lower one is read); false and a NaN solution for an indefinite A, one whose every
// pivot is negative and one with a single eigenvalue just below zero.
TEST(SdpKernels, SpdSolverSolvesOnEachPathAndRefusesIndefiniteMatrices) {
  std::mt19937 rng(17);
  std::normal_distribution<double> gauss(0.0, 1.0);
  fact::sdp::detail::SpdSolver solver(3);
  for (int n : {1, 2, 4, 5, 8, 9, 12, 13, 23, 24, 28, 32, 36, 40, 47, 48, 49, 64, 65, 100, 7, 3, 11, 10, 8, 6}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    const Eigen::MatrixXd B = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, n, rng, gauss);
    const Eigen::MatrixXd A = B * B.transpose() + n * Eigen::MatrixXd::Identity(n, n);
    const Eigen::VectorXd b = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, 1, rng, gauss);
    ASSERT_TRUE(solver.factor(A));
    Eigen::VectorXd x = b;
    solver.solve(x, x);  // aliased
    EXPECT_LT((A * x - b).cwiseAbs().maxCoeff(), 1e-12 * b.cwiseAbs().maxCoeff() * n);
    Eigen::MatrixXd lower_only = A;  // n × n
    lower_only.triangularView<Eigen::StrictlyUpper>().setConstant(std::numeric_limits<double>::quiet_NaN());
    ASSERT_TRUE(solver.factor(lower_only));
    Eigen::VectorXd from_lower;  // n
    solver.solve(b, from_lower);
    EXPECT_LT((A * from_lower - b).cwiseAbs().maxCoeff(), 1e-12 * b.cwiseAbs().maxCoeff() * n);
    const Eigen::MatrixXd indefinite = A - 2.0 * A.diagonal().maxCoeff() * Eigen::MatrixXd::Identity(n, n);
    EXPECT_FALSE(solver.factor(indefinite));
    solver.solve(b, x);
    EXPECT_TRUE(x.array().isNaN().all());
    const double lowest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A).eigenvalues()[0];
    EXPECT_FALSE(solver.factor(A - 1.01 * lowest * Eigen::MatrixXd::Identity(n, n)));
    ASSERT_TRUE(solver.factor(A - 0.99 * lowest * Eigen::MatrixXd::Identity(n, n)));
    solver.solve(b, x);
    EXPECT_TRUE(x.allFinite());
    // A NaN entry on the diagonal or below it fails the factorisation on every path, and on the
    // L D Lᵀ path an infinite pivot too.
    for (const auto& [i, j] : {std::pair{n - 1, n - 1}, std::pair{0, 0}, std::pair{n - 1, 0}}) {
      Eigen::MatrixXd bad = A;  // n × n
      bad(i, j) = std::numeric_limits<double>::quiet_NaN();
      EXPECT_FALSE(solver.factor(bad)) << "NaN at (" << i << ", " << j << ")";
      if (n <= fact::sdp::detail::kLdlMaxSize && i == j) {
        bad(i, j) = std::numeric_limits<double>::infinity();
        EXPECT_FALSE(solver.factor(bad)) << "inf at (" << i << ", " << j << ")";
      }
    }
  }
}

// cholesky_in_place on every path (real: Eigen's unblocked kernel below 49 rows, the padded
// kernel from 49 (odd sizes and sizes between its paddings among them: 49, 57, 63, 100, 121, 127),
// Eigen's blocked one from 128; complex: complex_cholesky_by_loops below 40 rows, complex_cholesky_by_panels of 24
// columns below 256 (a last panel of 16, 24 and 1 column at n = 40, 48 and 49), Eigen's blocked
// kernel from 256): L Lᴴ = A for a positive definite A, the upper triangle left as it
// was; false for an indefinite A (a negative eigenvalue that only the last pivot sees, and a
// negative first pivot), for a singular one (a last pivot of exactly 0) and for a NaN or infinite
// entry on the diagonal or below it.
template <class Matrix>
void expect_cholesky_on_every_path(std::mt19937& rng) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int n : {1, 2, 5, 31, 32, 39, 40, 48, 49, 57, 63, 64, 100, 121, 127, 128, 140, 255, 256}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    const Matrix B = fact::test::gaussian_matrix<Matrix>(n, n, rng, gauss);
    const Matrix A = B * B.adjoint() + Matrix::Identity(n, n);
    Matrix L = A;
    L.template triangularView<Eigen::StrictlyUpper>().setConstant(7.0);  // must stay untouched
    ASSERT_TRUE(fact::sdp::detail::cholesky_in_place(L));
    EXPECT_TRUE((L.template triangularView<Eigen::StrictlyUpper>().toDenseMatrix().array() ==
                 Matrix(Matrix::Constant(n, n, 7.0).template triangularView<Eigen::StrictlyUpper>()).array()).all());
    const Matrix lower = L.template triangularView<Eigen::Lower>();
    EXPECT_LT((lower * lower.adjoint() - A).cwiseAbs().maxCoeff(), 1e-13 * A.cwiseAbs().maxCoeff() * n);
    EXPECT_TRUE((lower.diagonal().imag().array() == 0).all());
    // λ_min(A) ≥ 1: A − (λ_min + 0.5)·I has one eigenvalue −0.5
    const double lowest = Eigen::SelfAdjointEigenSolver<Matrix>(A).eigenvalues()[0];
    Matrix indefinite = A - (lowest + 0.5) * Matrix::Identity(n, n);
    EXPECT_FALSE(fact::sdp::detail::cholesky_in_place(indefinite));
    Matrix negative_first = A;
    negative_first(0, 0) = -1.0;
    EXPECT_FALSE(fact::sdp::detail::cholesky_in_place(negative_first));
    Matrix zero_last = A;  // singular: the last pivot is exactly 0 (a pivot test of < 0 would pass it)
    zero_last.row(n - 1).setZero();
    zero_last.col(n - 1).setZero();
    EXPECT_FALSE(fact::sdp::detail::cholesky_in_place(zero_last));
    for (const double bad : {std::nan(""), std::numeric_limits<double>::infinity()})
      for (const auto& [i, j] : {std::pair<int, int>{n - 1, n - 1}, {0, 0}, {n - 1, 0}}) {
        Matrix with_bad = A;
        with_bad(i, j) = bad;
        EXPECT_FALSE(fact::sdp::detail::cholesky_in_place(with_bad)) << bad << " at (" << i << ", " << j << ")";
      }
  }
}

// positive_definite_when_shifted on its paths (real: cholesky_lower's padded kernels up to 48 rows,
// cholesky_in_place above; complex: cholesky_in_place): S + t·I passes just above t = −λ_min(S)
// and fails just below it, for an indefinite S; an infinite or NaN diagonal entry fails.
TEST(SdpKernels, PositiveDefiniteWhenShiftedDecidesAtTheLowestEigenvalue) {
  std::mt19937 rng(53);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int n : {6, 30, 48, 49, 64}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    const Eigen::MatrixXd G = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, n, rng, gauss);
    const Eigen::MatrixXd S = G + G.transpose();  // indefinite
    const double lowest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(S).eigenvalues()[0];
    ASSERT_LT(lowest, 0.0);
    EXPECT_TRUE(fact::sdp::detail::positive_definite_when_shifted(S, -lowest * 1.001));
    EXPECT_FALSE(fact::sdp::detail::positive_definite_when_shifted(S, -lowest * 0.999));
    for (const double bad : {std::numeric_limits<double>::infinity(), std::nan("")}) {
      Eigen::MatrixXd with_bad = S;
      with_bad(n - 1, n - 1) = bad;
      EXPECT_FALSE(fact::sdp::detail::positive_definite_when_shifted(with_bad, -lowest * 2.0)) << bad;
    }
  }
  const Eigen::MatrixXcd G = fact::test::gaussian_matrix<Eigen::MatrixXcd>(6, 6, rng, gauss);
  const Eigen::MatrixXcd H = G + G.adjoint();
  const double lowest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>(H).eigenvalues()[0];
  EXPECT_TRUE(fact::sdp::detail::positive_definite_when_shifted(H, -lowest * 1.001));
  EXPECT_FALSE(fact::sdp::detail::positive_definite_when_shifted(H, -lowest * 0.999));
}

// The grid's tests of P + aΔ (sum_passes_cholesky_test, and block_sum_passes_cholesky_test for
// Δ = blkdiag(D), d = 1 and 2) decide as a Cholesky factorisation does, on both sides of the
// boundary: P + aΔ = B + sI with s just above and just below −λ_min(B) (B symmetric indefinite),
// for n = 1 … 48 (every padded size of the right-looking and the left-looking kernel); NaN in the
// upper triangles of P, Δ and D's blocks changes nothing; a NaN entry below the diagonal or an
// infinite pivot fails.
TEST(SdpKernels, SumPassesCholeskyTestDecidesAtTheLowestEigenvalue) {
  using fact::sdp::detail::block_sum_passes_cholesky_test;
  using fact::sdp::detail::sum_passes_cholesky_test;
  std::mt19937 rng(37);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const double a = 0.7, garbage = std::numeric_limits<double>::quiet_NaN();
  for (Eigen::Index n = 1; n <= fact::sdp::detail::kGridStepMaxSize; ++n) {
    SCOPED_TRACE(testing::Message() << "n = " << n);
    const Eigen::MatrixXd G = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, n, rng, gauss);
    const Eigen::MatrixXd H = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, n, rng, gauss);
    const Eigen::MatrixXd B = G + G.transpose();
    Eigen::MatrixXd delta = H + H.transpose();
    const double lowest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(B, Eigen::EigenvaluesOnly).eigenvalues()[0];
    const double margin = 1e-3 * std::max(1.0, std::abs(lowest));
    for (const bool above : {true, false}) {
      SCOPED_TRACE(above ? "above the boundary" : "below the boundary");
      const double shift = -lowest + (above ? margin : -margin);
      const Eigen::MatrixXd target = B + shift * Eigen::MatrixXd::Identity(n, n);  // P + aΔ
      Eigen::MatrixXd P = target - a * delta;
      Eigen::MatrixXd full_delta = delta;
      P.triangularView<Eigen::StrictlyUpper>().setConstant(garbage);
      full_delta.triangularView<Eigen::StrictlyUpper>().setConstant(garbage);
      EXPECT_EQ(sum_passes_cholesky_test(P, a, full_delta), above);
      for (const int d : {1, 2}) {
        if (n % d != 0) continue;
        SCOPED_TRACE(testing::Message() << "d = " << d);
        Eigen::MatrixXd D = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, d, rng, gauss);  // blocks stacked
        Eigen::MatrixXd blocks = Eigen::MatrixXd::Zero(n, n);                               // blkdiag(D)
        for (Eigen::Index i = 0; i < n; i += d) {
          if (d == 2) D(i, 1) = D(i + 1, 0);
          blocks.block(i, i, d, d) = D.middleRows(i, d);
        }
        Eigen::MatrixXd Pb = target - a * blocks;
        Pb.triangularView<Eigen::StrictlyUpper>().setConstant(garbage);
        if (d == 2)
          for (Eigen::Index i = 0; i < n; i += 2) D(i, 1) = garbage;  // each block's upper entry
        EXPECT_EQ(block_sum_passes_cholesky_test(Pb, a, D, d), above);
        if (!above) continue;
        Pb(n - 1, 0) = std::numeric_limits<double>::quiet_NaN();
        EXPECT_FALSE(block_sum_passes_cholesky_test(Pb, a, D, d));
      }
      if (!above) continue;
      Eigen::MatrixXd broken = P;
      broken(n - 1, 0) = std::numeric_limits<double>::quiet_NaN();
      EXPECT_FALSE(sum_passes_cholesky_test(broken, a, full_delta));
      broken = P;
      broken(0, 0) = std::numeric_limits<double>::infinity();
      EXPECT_FALSE(sum_passes_cholesky_test(broken, a, full_delta));
    }
  }
}

TEST(SdpKernels, CholeskyInPlaceFactorsOnEveryPathAndRefusesIndefiniteMatrices) {
  std::mt19937 rng(23);
  expect_cholesky_on_every_path<Eigen::MatrixXd>(rng);
  expect_cholesky_on_every_path<Eigen::MatrixXcd>(rng);
}

// multiply against Eigen's complex product: blocks and adjoints of blocks of larger matrices
// (an outer stride) on either side, assigned and accumulated, with α = 1, −1 and −0.75, on shapes
// below, at and above kThreeProductMinSize in each dimension (m × k times k × n). The
// three-product form's error is normwise of the usual product's order: within 1e-14 of
// ‖L‖·‖R‖ in the Frobenius norm. The entries of C outside the block stay as they were.
TEST(SdpKernels, MultiplyComplexMatchesEigensProduct) {
  using Eigen::MatrixXcd;
  constexpr Eigen::Index t = fact::sdp::detail::kThreeProductMinSize;
  std::mt19937 rng(31);
  std::normal_distribution<double> gauss(0.0, 1.0);
  // L, R: the operands as multiply gets them; C_store holds the m × n block C.
  auto check = [&](const auto& L, const auto& R, double alpha, bool accumulate) {
    const Eigen::Index m = L.rows(), n = R.cols();
    const MatrixXcd l = L, r = R;
    MatrixXcd C_store = fact::test::gaussian_matrix<MatrixXcd>(m + 4, n + 4, rng, gauss);
    MatrixXcd expected = C_store;
    if (accumulate) {
      expected.block(2, 3, m, n) += alpha * l * r;
    } else {
      expected.block(2, 3, m, n) = alpha * l * r;
    }
    fact::sdp::detail::multiply(L, R, C_store.block(2, 3, m, n), alpha, accumulate);
    EXPECT_LT((C_store - expected).norm(), 1e-14 * l.norm() * r.norm());
    C_store.block(2, 3, m, n) = expected.block(2, 3, m, n);
    EXPECT_TRUE((C_store.array() == expected.array()).all()) << "an entry outside the block changed";
  };
  const Eigen::Index shapes[][3] = {{3, 5, 4}, {t - 1, t, t}, {t, t, t}, {t, t - 1, t}, {t, t, t - 1}, {40, 17, 23}, {64, 64, 64},
                                    {101, 37, 90}};
  for (const auto& [m, k, n] : shapes)
    for (const double alpha : {1.0, -1.0, -0.75})
      for (const bool accumulate : {false, true}) {
        SCOPED_TRACE(testing::Message() << m << " x " << k << " x " << n << ", alpha " << alpha << ", accumulate "
                                        << accumulate);
        const MatrixXcd A = fact::test::gaussian_matrix<MatrixXcd>(m + k + 3, m + k + 3, rng, gauss);
        const MatrixXcd B = fact::test::gaussian_matrix<MatrixXcd>(k + n + 3, k + n + 3, rng, gauss);
        check(A.block(1, 2, m, k), B.block(2, 1, k, n), alpha, accumulate);
        check(A.block(1, 2, m, k), B.block(2, 1, n, k).adjoint(), alpha, accumulate);
        check(A.block(1, 2, k, m).adjoint(), B.block(2, 1, k, n), alpha, accumulate);
        check(A.block(1, 2, k, m).adjoint(), B.block(2, 1, n, k).adjoint(), alpha, accumulate);
      }
}

// multiply with a triangular operand (Shape::lower or Shape::upper, zeros outside the triangle)
// against Eigen's product of the dense matrices, real and complex: lower and upper on either side,
// a block of a lower-triangular matrix and its adjoint (the inverse and Gram kernels' operands),
// into a matrix and (lower · dense) into a block of a larger one (their destinations), below, at and above kThreeProductMinSize and kTriangularShapeMinSize, assigned and accumulated, α = 1, −1 and −0.75. With
// the wrong triangle the product misses half of the operand's entries.
template <class Matrix>
void expect_triangular_products_match(std::mt19937& rng) {
  using fact::sdp::detail::multiply;
  using fact::sdp::detail::Shape;
  constexpr Eigen::Index t = fact::sdp::detail::kThreeProductMinSize;
  std::normal_distribution<double> gauss(0.0, 1.0);
  constexpr Eigen::Index s = fact::sdp::detail::kTriangularShapeMinSize;
  for (const Eigen::Index k : {Eigen::Index{5}, t - 1, t, s - 1, s, Eigen::Index{101}})
    for (const Eigen::Index other : {t, s - 1, s + 24})
      for (const double alpha : {1.0, -1.0, -0.75})
        for (const bool accumulate : {false, true}) {
          SCOPED_TRACE(testing::Message() << "k " << k << ", other " << other << ", alpha " << alpha << ", accumulate "
                                          << accumulate);
          // T_store's block (1, 1) is a k × k lower-triangular matrix, zeros above its diagonal.
          Matrix T_store = fact::test::gaussian_matrix<Matrix>(k + 3, k + 3, rng, gauss);
          T_store.block(1, 1, k, k) = Matrix(T_store.block(1, 1, k, k).template triangularView<Eigen::Lower>());
          const auto T = T_store.block(1, 1, k, k);
          const Matrix t_lower = T, t_upper = T.adjoint();
          const Matrix R = fact::test::gaussian_matrix<Matrix>(k, other, rng, gauss);
          const Matrix L = fact::test::gaussian_matrix<Matrix>(other, k, rng, gauss);
          const Matrix start = fact::test::gaussian_matrix<Matrix>(k, other, rng, gauss);
          const Matrix start_t = start.transpose();
          const double tol = 1e-14 * t_lower.norm() * R.norm();
          auto expected = [&](const Matrix& product, const Matrix& before) -> Matrix {
            return accumulate ? Matrix(before + alpha * product) : Matrix(alpha * product);
          };
          Matrix C = start;
          multiply<Shape::lower>(T, R, C, alpha, accumulate);
          EXPECT_LT((C - expected(t_lower * R, start)).norm(), tol) << "lower · dense";
          // into a block of a larger matrix (the inverse and Gram kernels' destinations): the
          // entries around it stay as they were
          Matrix C_store = fact::test::gaussian_matrix<Matrix>(k + 4, other + 3, rng, gauss);
          C_store.block(2, 1, k, other) = start;
          const Matrix store_before = C_store;
          multiply<Shape::lower>(T, R, C_store.block(2, 1, k, other), alpha, accumulate);
          EXPECT_LT((C_store.block(2, 1, k, other) - expected(t_lower * R, start)).norm(), tol) << "lower · dense, block";
          C_store.block(2, 1, k, other) = start;
          EXPECT_EQ(C_store, store_before) << "lower · dense wrote outside its block";
          C = start;
          multiply<Shape::upper>(T.adjoint(), R, C, alpha, accumulate);
          EXPECT_LT((C - expected(t_upper * R, start)).norm(), tol) << "upper · dense";
          C = start_t;
          multiply<Shape::dense, Shape::lower>(L, T, C, alpha, accumulate);
          EXPECT_LT((C - expected(L * t_lower, start_t)).norm(), tol) << "dense · lower";
          C = start_t;
          multiply<Shape::dense, Shape::upper>(L, T.adjoint(), C, alpha, accumulate);
          EXPECT_LT((C - expected(L * t_upper, start_t)).norm(), tol) << "dense · upper";
        }
}

// inverse_by_sweeps's W = (A + sI)⁻¹ against Eigen's LLT inverse, real and complex, for n = 1 … 32
// (every padded size, full and partly filled) and a shift that moves A's diagonal: W symmetric
// or Hermitian exactly (its upper triangle the lower one's conjugate), into an output of the wrong
// size with stale entries; false for an indefinite A + sI (λ_min = −0.1 after the shift), for a
// NaN entry and for an infinite diagonal entry (whose pivot would give a finite-looking W).
template <class Matrix>
void check_inverse_by_sweeps(std::mt19937& rng) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (Eigen::Index n = 1; n <= fact::sdp::detail::kSweepInverseMaxSize; ++n) {
    SCOPED_TRACE(testing::Message() << "n = " << n << (Eigen::NumTraits<typename Matrix::Scalar>::IsComplex ? ", complex" : ", real"));
    const Matrix G = fact::test::gaussian_matrix<Matrix>(n, n, rng, gauss);
    const Matrix A = G * G.adjoint() + 0.5 * Matrix::Identity(n, n);  // λ_min ≥ 0.5
    const double shift = 0.25;
    const Matrix shifted = A + shift * Matrix::Identity(n, n);
    const Matrix expected = shifted.llt().solve(Matrix::Identity(n, n));
    Matrix W = Matrix::Constant(n + 3, 2, 7.0);
    ASSERT_TRUE(fact::sdp::detail::inverse_by_sweeps(A, shift, W));
    ASSERT_EQ(W.rows(), n);
    ASSERT_EQ(W.cols(), n);
    EXPECT_LT((W - expected).norm(), 1e-12 * expected.norm());
    EXPECT_LT((shifted * W - Matrix::Identity(n, n)).norm(), 1e-11);
    EXPECT_TRUE(W == W.adjoint());
    const Eigen::SelfAdjointEigenSolver<Matrix> eig(A, Eigen::EigenvaluesOnly);
    EXPECT_FALSE(fact::sdp::detail::inverse_by_sweeps(A, -eig.eigenvalues()[0] - 0.1, W));
    Matrix broken = A;
    broken(n - 1, 0) = std::numeric_limits<double>::quiet_NaN();
    broken(0, n - 1) = broken(n - 1, 0);
    if (n > 1) {
      EXPECT_FALSE(fact::sdp::detail::inverse_by_sweeps(broken, shift, W));
    }
    Matrix infinite = A;
    infinite(n - 1, n - 1) = std::numeric_limits<double>::infinity();
    EXPECT_FALSE(fact::sdp::detail::inverse_by_sweeps(infinite, shift, W));
  }
}

TEST(SdpKernels, InverseBySweepsMatchesTheCholeskyInverse) {
  std::mt19937 rng(31);
  check_inverse_by_sweeps<Eigen::MatrixXd>(rng);
  check_inverse_by_sweeps<Eigen::MatrixXcd>(rng);
}

// The complex staircase's loops against Eigen's products: factor_gram's X = Y Yᴴ, both triangles
// (the escape reads the upper one), and times_thin's A B, for ranks 0 … 3 and N = 1, 5, 33,
// into outputs of the wrong size and with stale entries.
TEST(SdpKernels, FactorGramAndTimesThinMatchEigensProducts) {
  using Eigen::MatrixXcd;
  std::mt19937 rng(37);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (const Eigen::Index N : {1, 5, 33})
    for (const Eigen::Index p : {0, 1, 2, 3}) {
      SCOPED_TRACE(testing::Message() << "N = " << N << ", p = " << p);
      const MatrixXcd Y = fact::test::gaussian_matrix<MatrixXcd>(N, p, rng, gauss);
      const MatrixXcd A = fact::test::gaussian_matrix<MatrixXcd>(N, N, rng, gauss);
      // wrong size and stale entries; at p = 0 the right size, so that only setting X to zero clears them
      MatrixXcd X = MatrixXcd::Constant(p == 0 ? N : N + 1, N, {7.0, -7.0});
      fact::sdp::detail::factor_gram(Y, X);
      ASSERT_EQ(X.rows(), N);
      ASSERT_EQ(X.cols(), N);
      if (p == 0) {  // (stale entries overwritten)
        EXPECT_TRUE((X.array() == std::complex<double>(0.0, 0.0)).all());
        continue;
      }
      const MatrixXcd expected_gram = Y * Y.adjoint();
      EXPECT_LT((X - expected_gram).cwiseAbs().maxCoeff(), 1e-14 * Y.squaredNorm());
      MatrixXcd C = MatrixXcd::Constant(N, p + 2, {3.0, 1.0});  // wrong size, stale entries
      fact::sdp::detail::times_thin(A, Y, C);
      ASSERT_EQ(C.rows(), N);
      ASSERT_EQ(C.cols(), p);
      const MatrixXcd expected_product = A * Y;
      EXPECT_LT((C - expected_product).cwiseAbs().maxCoeff(), 1e-14 * A.norm() * Y.norm());
    }
}

// bottom_vector_by_inverse (the complex spectral start from N = 4 to 32, on W² up to 8 rows):
// H's bottom eigenvector to an angle of about 1e-7 on positive semidefinite H (a random one, and
// one with a null vector as on noise-free data), an empty result for an indefinite H.
TEST(SdpKernels, BottomVectorByInverseFindsTheLowestEigenvector) {
  using Eigen::MatrixXcd;
  std::mt19937 rng(43);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (const Eigen::Index N : {4, 6, 8, 9, 20, 32})
    for (const bool singular : {false, true}) {
      SCOPED_TRACE(testing::Message() << "N = " << N << (singular ? ", one null vector" : ""));
      const MatrixXcd G = fact::test::gaussian_matrix<MatrixXcd>(N, singular ? N - 1 : N, rng, gauss);
      const MatrixXcd H = G * G.adjoint() / static_cast<double>(N);  // N × N, positive semidefinite
      const Eigen::SelfAdjointEigenSolver<MatrixXcd> reference(H);
      const MatrixXcd v = fact::sdp::detail::bottom_vector_by_inverse(H);
      ASSERT_EQ(v.rows(), N);
      ASSERT_EQ(v.cols(), 1);
      EXPECT_NEAR(v.norm(), 1.0, 1e-14);
      EXPECT_GT(std::abs(reference.eigenvectors().col(0).dot(v.col(0))), 1.0 - 1e-12);
      const MatrixXcd indefinite = H - 2.0 * reference.eigenvalues()[1] * MatrixXcd::Identity(N, N);
      EXPECT_EQ(fact::sdp::detail::bottom_vector_by_inverse(indefinite).size(), 0);
    }
}

// bottom_vectors_by_inverse (the real staircase's spectral start from 16 to 64 rows): C's bottom two
// eigenvectors, orthonormal, spanning the reference's subspace to within the iteration's rate
// (projectors within 10·ρ^steps + 1e-10, ρ = (λ₂ + δ)/(λ₅ + δ) each step: 3e-4 at worst for the
// random C here, rounding (1e-10) for the singular ones) on positive semidefinite C (a random one of full
// rank, and one with a two-dimensional null space, as the paper's cost on noise-free data has); an
// empty result for an indefinite C.
TEST(SdpKernels, BottomVectorsByInverseSpanTheLowestEigenvectors) {
  std::mt19937 rng(47);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (const Eigen::Index n : {16, 24, 33, 48, 64})
    for (const bool singular : {false, true}) {
      SCOPED_TRACE(testing::Message() << "n = " << n << (singular ? ", null space of dimension 2" : ""));
      const Eigen::MatrixXd G = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, singular ? n - 2 : n, rng, gauss);
      Eigen::MatrixXd C = G * G.transpose();  // n × n, positive semidefinite
      C /= C.norm();
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> reference(C);
      const Eigen::MatrixXd V = fact::sdp::detail::bottom_vectors_by_inverse(C, 2);
      ASSERT_EQ(V.rows(), n);
      ASSERT_EQ(V.cols(), 2);
      EXPECT_LT((V.transpose() * V - Eigen::Matrix2d::Identity()).cwiseAbs().maxCoeff(), 1e-13);
      const Eigen::MatrixXd U = reference.eigenvectors().leftCols(2);  // n × 2
      const double delta = fact::sdp::detail::inverse_iteration_shift(C);
      const double rate = (reference.eigenvalues()[1] + delta) / (reference.eigenvalues()[4] + delta);
      EXPECT_LT((V * V.transpose() - U * U.transpose()).norm(),
                10 * std::pow(rate, fact::sdp::detail::kInverseStartSteps) + 1e-10);
      const Eigen::MatrixXd indefinite = C - 2.0 * reference.eigenvalues()[2] * Eigen::MatrixXd::Identity(n, n);
      EXPECT_EQ(fact::sdp::detail::bottom_vectors_by_inverse(indefinite, 2).size(), 0);
    }
}

TEST(SdpKernels, MultiplyWithATriangularOperandMatchesEigensProduct) {
  std::mt19937 rng(41);
  expect_triangular_products_match<Eigen::MatrixXd>(rng);
  expect_triangular_products_match<Eigen::MatrixXcd>(rng);
}

// From kTriangularShapeMinSize rows a triangular operand goes through Eigen's triangular product,
// which never reads the other triangle: with NaN there the product is still exact (real, and
// complex through its three real products). Below it the operand is multiplied as a dense one,
// and the NaN comes through; a path that fell back to the dense product would too.
template <class Matrix>
void expect_other_triangle_unread(std::mt19937& rng) {
  using fact::sdp::detail::multiply;
  using fact::sdp::detail::Shape;
  std::normal_distribution<double> gauss(0.0, 1.0);
  constexpr Eigen::Index s = fact::sdp::detail::kTriangularShapeMinSize;
  for (const Eigen::Index k : {s - 1, s, Eigen::Index{101}}) {
    SCOPED_TRACE(testing::Message() << "k " << k);
    const Matrix lower = Matrix(fact::test::gaussian_matrix<Matrix>(k, k, rng, gauss).template triangularView<Eigen::Lower>());
    Matrix poisoned = lower;  // lower, with NaN above the diagonal
    poisoned.template triangularView<Eigen::StrictlyUpper>().setConstant(std::numeric_limits<double>::quiet_NaN());
    const Matrix R = fact::test::gaussian_matrix<Matrix>(k, k + 2, rng, gauss);
    const Matrix L = fact::test::gaussian_matrix<Matrix>(k + 2, k, rng, gauss);
    Matrix C, D;
    multiply<Shape::lower>(poisoned, R, C, 1.0, false);
    multiply<Shape::dense, Shape::upper>(L, poisoned.adjoint(), D, -1.0, false);
    if (k < s) {
      EXPECT_FALSE(C.allFinite());
      EXPECT_FALSE(D.allFinite());
      continue;
    }
    const double tol = 1e-14 * lower.norm() * R.norm();
    EXPECT_LT((C - lower * R).norm(), tol);
    EXPECT_LT((D + L * lower.adjoint()).norm(), tol);
  }
}

TEST(SdpKernels, FromTheThresholdATriangularOperandsOtherTriangleIsNotRead) {
  std::mt19937 rng(43);
  expect_other_triangle_unread<Eigen::MatrixXd>(rng);
  expect_other_triangle_unread<Eigen::MatrixXcd>(rng);
}

// The dual step-length operator w = Lz⁻¹ ΔZ Lz⁻ᴴ v (ΔZ = −diag(dy)) against the dense formula, on
// both of its paths (dense below kTriangularProductMinSize rows, triangular from it); with the
// wrong triangle or without the adjoint the interior point's steps went wrong without a test
// noticing (review, helper-38). A resized destination of multiply is covered here too.
TEST(SdpKernels, DualStepOperatorIsLzInverseTimesDeltaZTimesItsAdjoint) {
  std::mt19937 rng(37);
  std::normal_distribution<double> gauss(0.0, 1.0);
  constexpr Eigen::Index t = fact::sdp::detail::kTriangularProductMinSize;
  for (const Eigen::Index n : {Eigen::Index{5}, t - 1, t, t + 17}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    const Eigen::MatrixXcd B = fact::test::gaussian_matrix<Eigen::MatrixXcd>(n, n, rng, gauss);
    Eigen::MatrixXcd L = B * B.adjoint() + static_cast<double>(n) * Eigen::MatrixXcd::Identity(n, n);
    ASSERT_TRUE(fact::sdp::detail::cholesky_in_place(L));
    Eigen::MatrixXcd Lz_inv;
    fact::sdp::detail::invert_lower_factor(L, Lz_inv);
    const Eigen::VectorXd dy = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, 1, rng, gauss);
    const Eigen::VectorXcd v = fact::test::gaussian_matrix<Eigen::MatrixXcd>(n, 1, rng, gauss);
    Eigen::VectorXcd u(n), w(n);
    fact::sdp::detail::dual_step_operator(Lz_inv, dy, v, u, w);
    const Eigen::MatrixXcd lower = Lz_inv.triangularView<Eigen::Lower>();
    const Eigen::VectorXcd expected = lower * (-dy).asDiagonal() * lower.adjoint() * v;
    EXPECT_LT((w - expected).norm(), 1e-13 * expected.norm());
    Eigen::MatrixXcd product;  // empty: multiply sizes it
    fact::sdp::detail::multiply(lower, lower.adjoint(), product, 1.0, false);
    ASSERT_EQ(product.rows(), n);
    ASSERT_EQ(product.cols(), n);
    EXPECT_LT((product - lower * lower.adjoint()).norm(), 1e-14 * lower.norm() * lower.norm());
  }
}

// The 16 × 16 tiles of for_each_entry_below_diagonal visit every entry below the diagonal exactly
// once, at sizes below, at and across a tile's edge; symmetrize through them gives (A + Aᵀ)/2 to the
// last bit.
TEST(SdpKernels, TiledLoopsVisitEveryEntryBelowTheDiagonalOnce) {
  std::mt19937 rng(29);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int n : {1, 2, 15, 16, 17, 33, 128, 130}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    Eigen::MatrixXi visits = Eigen::MatrixXi::Zero(n, n);
    fact::sdp::detail::for_each_entry_below_diagonal(n, [&](Eigen::Index i, Eigen::Index j) { ++visits(i, j); });
    const Eigen::MatrixXi expected = Eigen::MatrixXi::Ones(n, n).triangularView<Eigen::StrictlyLower>();
    EXPECT_TRUE((visits.array() == expected.array()).all());
    const Eigen::MatrixXd A = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, n, rng, gauss);
    Eigen::MatrixXd symmetric = A;
    fact::sdp::detail::symmetrize(symmetric);
    const Eigen::MatrixXd average = 0.5 * (A + A.transpose());
    EXPECT_TRUE((symmetric.array() == average.array()).all());
  }
}

// pivoted_rank: the rank of a PSD C = B Bᵀ (B n × r), and n (no null space) for an indefinite C,
// including one whose diagonal is 0 (blocks [[0, 1], [1, 0]]), which stops the pivoting at once.
TEST(SdpKernels, PivotedRankCountsPsdRankAndSeesIndefiniteMatrices) {
  std::mt19937 rng(19);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int r : {0, 1, 3, 9}) {
    const Eigen::MatrixXd B = fact::test::gaussian_matrix<Eigen::MatrixXd>(12, std::max(r, 1), rng, gauss);
    const Eigen::MatrixXd C = r == 0 ? Eigen::MatrixXd::Zero(12, 12) : Eigen::MatrixXd(B * B.transpose());
    EXPECT_EQ(fact::sdp::detail::pivoted_rank(C), r);
  }
  Eigen::MatrixXd swap = Eigen::MatrixXd::Zero(8, 8);
  for (int i = 0; i < 8; i += 2) swap(i, i + 1) = swap(i + 1, i) = 1.0;
  EXPECT_EQ(fact::sdp::detail::pivoted_rank(swap), 8);
  Eigen::MatrixXd mixed = Eigen::MatrixXd::Identity(8, 8);
  mixed(7, 7) = -1.0;
  EXPECT_EQ(fact::sdp::detail::pivoted_rank(mixed), 8);
}

// The hand-off's factors: pivoted_cholesky reproduces a PSD X of exact rank r with r columns, and
// leading_factor of X = (rank-r part with eigenvalues 1 … 8) + (a part of eigenvalues ≤ 1e-9)
// keeps r columns, orthogonal, largest first, whose squared norms are the r large eigenvalues
// and whose Y Yᵀ is the rank-r part to within the dropped one; factor_psd at the same cutoff
// agrees with it.
TEST(SdpKernels, PivotedAndLeadingFactorsKeepTheLeadingPartOfX) {
  std::mt19937 rng(23);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Eigen::Index n = 20;
  const int r = 5;
  const Eigen::MatrixXd G = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, n, rng, gauss);
  const Eigen::MatrixXd V = Eigen::HouseholderQR<Eigen::MatrixXd>(G).householderQ();  // orthogonal, n × n
  Eigen::VectorXd values(n);
  for (Eigen::Index k = 0; k < n; ++k) values[k] = k < r ? 8.0 - 1.75 * static_cast<double>(k) : 1e-9 / (1.0 + k);
  const Eigen::MatrixXd large = V.leftCols(r) * values.head(r).asDiagonal() * V.leftCols(r).transpose();
  const Eigen::MatrixXd X = large + V.rightCols(n - r) * values.tail(n - r).asDiagonal() * V.rightCols(n - r).transpose();

  const Eigen::MatrixXd P = fact::sdp::detail::pivoted_cholesky(large, 1e-12);
  EXPECT_EQ(P.cols(), r);
  EXPECT_LT((P * P.transpose() - large).cwiseAbs().maxCoeff(), 1e-12);

  const Eigen::MatrixXd Y = fact::sdp::detail::leading_factor(X, 1e-6);
  ASSERT_EQ(Y.cols(), r);
  const Eigen::MatrixXd gram = Y.transpose() * Y;  // r × r: diag(values) for orthogonal columns
  for (int k = 0; k < r; ++k) {
    EXPECT_NEAR(gram(k, k), values[k], 1e-10) << "column " << k;
    for (int l = 0; l < k; ++l) EXPECT_NEAR(gram(k, l), 0.0, 1e-10) << "columns " << k << ", " << l;
  }
  EXPECT_LT((Y * Y.transpose() - large).cwiseAbs().maxCoeff(), 1e-9);
  const Eigen::MatrixXd E = fact::sdp::detail::factor_psd(X, 1e-6);
  ASSERT_EQ(E.cols(), r);
  EXPECT_LT((E * E.transpose() - Y * Y.transpose()).cwiseAbs().maxCoeff(), 1e-9);
}

// unit_diagonal_blocks maps X to D^{-1/2} X D^{-1/2}, D = blkdiag(X_ii): against Eigen's inverse
// square root of each block (d = 2, the closed form; d = 1), on a random positive definite X whose
// blocks are far from I and on one whose blocks are I up to a drift of 1e-9; the result's blocks
// are I and it stays positive definite. A block that is not positive definite gives non-finite
// entries, as Eigen's decomposition did.
TEST(SdpKernels, UnitDiagonalBlocksScaleByEachBlocksInverseSquareRoot) {
  std::mt19937 rng(29);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Eigen::Index n = 10;
  const Eigen::MatrixXd G = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, n, rng, gauss);
  const Eigen::MatrixXd far = G * G.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
  Eigen::MatrixXd near = Eigen::MatrixXd::Identity(n, n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j <= i; ++j) near(i, j) = near(j, i) = near(i, j) + 1e-9 * gauss(rng) + (i != j ? 0.05 : 0.0);
  const Eigen::MatrixXd* cases[] = {&far, &near};
  for (const Eigen::MatrixXd* X0 : cases)
    for (int d : {1, 2}) {
      Eigen::MatrixXd D = Eigen::MatrixXd::Zero(n, n);  // blkdiag(X_ii)^{-1/2} by Eigen
      for (Eigen::Index i = 0; i < n; i += d)
        D.block(i, i, d, d) = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(X0->block(i, i, d, d)).operatorInverseSqrt();
      const Eigen::MatrixXd expected = D * *X0 * D;
      Eigen::MatrixXd X = *X0;
      fact::sdp::detail::unit_diagonal_blocks(X, d);
      const double scale = expected.cwiseAbs().maxCoeff();
      EXPECT_LT((X - expected).cwiseAbs().maxCoeff(), 1e-13 * scale) << "d = " << d << (X0 == &far ? ", far" : ", near");
      for (Eigen::Index i = 0; i < n; i += d)
        EXPECT_LT((X.block(i, i, d, d) - Eigen::MatrixXd::Identity(d, d)).cwiseAbs().maxCoeff(), 1e-13) << "block " << i;
      EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(X).info(), Eigen::Success);
    }
  Eigen::MatrixXd indefinite = far;
  indefinite.block(2, 2, 2, 2) << 1.0, 2.0, 2.0, 1.0;  // eigenvalues 3 and −1
  fact::sdp::detail::unit_diagonal_blocks(indefinite, 2);
  EXPECT_FALSE(indefinite.block(2, 0, 2, n).allFinite());
}

// Newton's system in Schur form against the one in tangent bases (newton_refine's NewtonSystem):
// the damped system Proj(S V) + λV = −S Y is the same, so from a point near a rank-r optimum one
// step of each lands at the same factor, and from farther out both converge to the same optimum.
// Plain costs of N = 5 and 8 (optima of rank 4 and 5, where automatic mode takes the Schur form)
// and a random C with d = 1 at rank 3. The near start is 1e-8 off the optimum, so that S there has
// no eigenvalue below −0.5e-8, the Schur form's first shift: both then take their first damping
// (μ = 2λ = 1e-8). At 1e-7 off, λ_min(S) was −1e-8 on the d = 1 case, the Schur form raised its
// shift and the dense one did not, and the steps differed by 3e-6 (session 45, when the interior
// point's optimum moved by 1e-11).
TEST(SdpNewton, SchurFormTakesTheTangentBasisStep) {
  using fact::sdp::detail::NewtonSystem;
  std::mt19937 rng(23);
  std::normal_distribution<double> gauss(0.0, 1.0);
  struct Case { Eigen::MatrixXd C; int d; };
  Eigen::MatrixXd B = fact::test::gaussian_matrix<Eigen::MatrixXd>(12, 12, rng, gauss);
  const Eigen::MatrixXd random_psd = B * B.transpose();
  for (const Case& c : {Case{scaled_plain_cost(5, 3), 2}, Case{scaled_plain_cost(8, 4), 2},
                        Case{random_psd / random_psd.norm(), 1}}) {
    fact::sdp::Options o;
    o.method = fact::sdp::Method::interior_point;
    const fact::sdp::Result r = fact::sdp::solve(c.C, c.d, o);
    ASSERT_TRUE(r.certified()) << r.reason;
    // The optimum's factor at its numerical rank, then a perturbation of size `size`, projected.
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(r.X());
    const Eigen::Index rank = r.rank;
    ASSERT_GT(c.d * rank - c.d * (c.d + 1) / 2, c.d * (c.d + 1) / 2) << "rank " << rank << ": not the Schur form";
    const Eigen::MatrixXd optimum = eig.eigenvectors().rightCols(rank) *
                                    eig.eigenvalues().tail(rank).cwiseSqrt().asDiagonal();  // n × rank
    for (double size : {1e-8, 1e-2}) {
      SCOPED_TRACE("d = " + std::to_string(c.d) + ", rank " + std::to_string(rank) + ", perturbation " +
                   std::to_string(size));
      Eigen::MatrixXd start = optimum + size * fact::test::gaussian_matrix<Eigen::MatrixXd>(optimum.rows(), rank, rng, gauss);
      ASSERT_TRUE(fact::sdp::detail::project_blocks(start, c.d));
      if (size < 1e-4) {  // the premise of the same step: S(start) + 0.5e-8·I ≻ 0
        const Eigen::MatrixXd S = fact::sdp::detail::certificate_matrix(
            c.C, fact::sdp::detail::lambda_from_factor(c.C, start, c.d), c.d);  // C − blkdiag(Λ(Y)), n × n
        ASSERT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(S).eigenvalues()[0], -0.5e-8);
      }
      Eigen::MatrixXd dense = start, schur = start;
      const int steps = size < 1e-4 ? 1 : 60;
      const int dense_steps = fact::sdp::detail::newton_refine(c.C, c.d, dense, steps, 1e-12, NewtonSystem::tangent_basis);
      const int schur_steps = fact::sdp::detail::newton_refine(c.C, c.d, schur, steps, 1e-12, NewtonSystem::schur);
      const double f_dense = (dense.transpose() * c.C * dense).trace(), f_schur = (schur.transpose() * c.C * schur).trace();
      if (size < 1e-4) {  // one step each, from the same point: the same step
        EXPECT_EQ(dense_steps, 1);
        EXPECT_EQ(schur_steps, 1);
        EXPECT_LT((dense - schur).norm(), 1e-8 * (dense - start).norm() + 1e-14);  // (rounding of a 5e-8 step)
      } else {  // both converge (‖grad‖ < 1e-12 before the step limit) to the optimum
        EXPECT_LT(dense_steps, steps);
        EXPECT_LT(schur_steps, steps);
        EXPECT_NEAR(f_schur, f_dense, 1e-12 * std::max(1.0, std::abs(f_dense)));
      }
      EXPECT_NEAR(f_schur, r.objective / r.scale, 1e-9 * std::max(1e-4, std::abs(f_schur)) + 2 * size * size);
    }
  }
}

}  // namespace

namespace {

// CrawlWatch on given costs: it stops from step 6 on, once f has fallen by less than the asked
// fraction of itself over 3 steps while the gradient is above 1e-4; never with decrease 0.
TEST(SdpNewton, CrawlWatchStopsOnlyASlowRunWithALargeGradient) {
  using fact::sdp::detail::CrawlWatch;
  const auto first_stop = [](double decrease, double rate, double grad) {
    CrawlWatch watch(decrease);
    double f = 1.0;
    for (int step = 0; step < 40; ++step, f *= rate)
      if (watch.crawls(step, f, grad)) return step;
    return -1;
  };
  EXPECT_EQ(first_stop(0.1, 0.98, 1e-2), 6);   // 6 % in 3 steps: crawls at the first step it may stop
  EXPECT_EQ(first_stop(0.1, 0.9, 1e-2), -1);   // 27 % in 3 steps: converging
  EXPECT_EQ(first_stop(0.1, 0.98, 1e-5), -1);  // small gradient: near a critical point, let it converge
  EXPECT_EQ(first_stop(0.0, 1.0, 1e-2), -1);   // no watch
  EXPECT_EQ(first_stop(0.1, 0.95, 1e-2), -1);  // 14 % in 3 steps, 17 % of the current f
  // The look-back is exactly 3 steps: 0.96³ falls 13 % of the current f (2 steps would be 8.5 %),
  // 0.972³ 8.9 % (4 steps would be 12 %).
  EXPECT_EQ(first_stop(0.1, 0.96, 1e-2), -1);
  EXPECT_EQ(first_stop(0.1, 0.972, 1e-2), 6);
  EXPECT_EQ(first_stop(0.3, 0.95, 1e-2), 6);   // a larger fraction stops it
}

// The automatic mode's rank-2 attempt above 48 rows (random C, N = 32, scaled to ‖C‖_F = 1):
// on C of full rank, whose optimum has a higher rank, it crawls and the watch ends it well before
// its 25 steps without changing what it certifies (nothing); on C of rank 3, whose zero optimum
// has rank 2, it is not stopped and certifies in the same steps.
TEST(SdpNewton, RankTwoAttemptStopsCrawlingOnFullRankButNotOnLowRank) {
  std::mt19937 rng(31);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Options rank_two = rank_two_attempt();
  for (int columns : {64, 3}) {
    SCOPED_TRACE("C = B Bᵀ, B 64 × " + std::to_string(columns));
    const Eigen::MatrixXd C = scaled_random_psd(64, columns, rng, gauss);
    const auto unwatched = fact::sdp::detail::solve_low_rank(C, 2, rank_two);
    const auto watched = fact::sdp::detail::solve_low_rank(C, 2, rank_two, 0.1);
    EXPECT_EQ(watched.certified, unwatched.certified);
    if (columns == 64) {
      EXPECT_FALSE(unwatched.certified);
      EXPECT_GE(unwatched.iterations, 15) << "watched: " << watched.iterations;
      EXPECT_LE(watched.iterations, 10);
    } else {
      EXPECT_TRUE(unwatched.certified);
      EXPECT_EQ(watched.iterations, unwatched.iterations);
      EXPECT_LT(unwatched.iterations, 25);
    }
  }
}

// The rank-2 attempt that automatic mode hands to the interior point skips S's spectrum when its
// gradient proves λ_min(S) < −psd_tol (or a Cholesky test does: the next test): on random C of
// full rank (N = 64) the crawl watch stops it far from a critical point, and its certificate
// comes without eigenvalues, NaN for λ_min and the bound, and the Λ of the same factor, whose S
// (computed here) has λ_min below −psd_tol indeed; on C of rank 3 (zero optimum of rank 2) it
// converges, certifies and keeps its spectrum.
TEST(SdpNewton, RankTwoAttemptFarFromACriticalPointSkipsTheSpectrumByItsGradient) {
  std::mt19937 rng(37);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Options rank_two = rank_two_attempt();
  for (int columns : {128, 3}) {
    SCOPED_TRACE("C = B Bᵀ, B 128 × " + std::to_string(columns));
    const Eigen::MatrixXd C = scaled_random_psd(128, columns, rng, gauss);
    const auto full = fact::sdp::detail::solve_low_rank(C, 2, rank_two, 0.1);
    const auto skipping = fact::sdp::detail::solve_low_rank(C, 2, rank_two, 0.1, true);
    EXPECT_EQ(skipping.certified, full.certified);
    EXPECT_EQ(skipping.iterations, full.iterations);
    EXPECT_EQ((skipping.Y - full.Y).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ((skipping.certificate.lambda - full.certificate.lambda).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_NEAR(skipping.certificate.trace_lambda, full.certificate.trace_lambda, 1e-15);
    if (columns == 128) {
      ASSERT_FALSE(full.certified);
      EXPECT_EQ(skipping.certificate.eigenvalues.size(), 0);
      EXPECT_TRUE(std::isnan(skipping.certificate.min_eig) && std::isnan(skipping.certificate.dual_bound) &&
                  std::isnan(skipping.certificate.bound_error));
      const Eigen::MatrixXd S = fact::sdp::detail::certificate_matrix(C, skipping.certificate.lambda, 2);
      EXPECT_LT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(S).eigenvalues().minCoeff(), -rank_two.psd_tol);
    } else {
      EXPECT_TRUE(skipping.certified);
      EXPECT_EQ(skipping.certificate.eigenvalues.size(), 128);
      EXPECT_EQ(skipping.certificate.min_eig, full.certificate.min_eig);
    }
  }
}

// Where the rank-2 attempt converges to a saddle (random C of full rank, n = 24 and 32: the
// optimum has a higher rank), S Y is at rounding level and the gradient proves nothing; S's
// spectrum is still skipped, since S + psd_tol·I fails a Cholesky test. The same run with the
// spectrum finds λ_min(S) below −psd_tol, with the same factor and Λ.
TEST(SdpNewton, RankTwoAttemptAtASaddleSkipsTheSpectrumByACholeskyTest) {
  std::mt19937 rng(41);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Options rank_two = rank_two_attempt();
  for (int n : {24, 32}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    const Eigen::MatrixXd C = scaled_random_psd(n, n, rng, gauss);
    const auto full = fact::sdp::detail::solve_low_rank(C, 2, rank_two);
    const auto skipping = fact::sdp::detail::solve_low_rank(C, 2, rank_two, 0.0, true);
    ASSERT_FALSE(full.certified);
    EXPECT_LT(full.certificate.min_eig, -rank_two.psd_tol);
    EXPECT_FALSE(skipping.certified);
    EXPECT_EQ((skipping.Y - full.Y).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ((skipping.certificate.lambda - full.certificate.lambda).cwiseAbs().maxCoeff(), 0.0);
    const Eigen::MatrixXd S = fact::sdp::detail::certificate_matrix(C, skipping.certificate.lambda, 2);
    EXPECT_LT((S * skipping.Y).norm(), 1e-9);  // a critical point: the gradient rules nothing out
    EXPECT_EQ(skipping.certificate.eigenvalues.size(), 0);
    EXPECT_TRUE(std::isnan(skipping.certificate.min_eig) && std::isnan(skipping.certificate.dual_bound));
  }
}

}  // namespace
