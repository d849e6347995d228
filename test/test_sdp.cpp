// Tests of fact::sdp::solve and its helpers on
//     minimize ⟨C, X⟩  s.t.  X ⪰ 0,  X_ii = I_d  (C n×n symmetric, n = d·N).
// Every expected value is computed independently of the solver: closed forms for N = 2,
// planted rank-d optima (noise-free rotation costs, phase-synchronisation Laplacians) and the
// optima of SDPA and CSDP stored in test/data/sdp/optima.csv.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "fact/rotation_cost.h"
#include "fact/sdp.h"
#include "sdp_test_costs.h"
#include "sdpa_sparse_reader.h"

namespace fact::sdp {
// Lets GoogleTest print statuses by name in failure messages.
void PrintTo(Status s, std::ostream* os) { *os << to_string(s); }
}  // namespace fact::sdp

namespace {

using fact::sdp::Method;
using fact::sdp::Options;
using fact::sdp::Result;
using fact::sdp::Status;

// Deterministic n×m matrix of standard normal entries.
Eigen::MatrixXd gaussian(Eigen::Index rows, Eigen::Index cols, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index j = 0; j < cols; ++j)
    for (Eigen::Index i = 0; i < rows; ++i) m(i, j) = g(rng);
  return m;
}

Eigen::MatrixXd random_psd(Eigen::Index n, unsigned seed) {
  const Eigen::MatrixXd g = gaussian(n, n, seed);
  return g * g.transpose();
}

Eigen::MatrixXd random_symmetric(Eigen::Index n, unsigned seed) {
  const Eigen::MatrixXd g = gaussian(n, n, seed);
  return 0.5 * (g + g.transpose());
}

// Angle wrapped to (−π, π].
double wrap(double a) {
  a = std::remainder(a, 2.0 * M_PI);
  if (a <= -M_PI) a += 2.0 * M_PI;
  return a;
}

double rel_tol(double tol, double reference) { return tol * std::max(1.0, std::abs(reference)); }

// Properties every certified result must have, recomputed from Y and Λ.
void expect_certificate(const Eigen::MatrixXd& C, int d, const Result& r) {
  ASSERT_TRUE(r.certified()) << fact::sdp::to_string(r.status) << ": " << r.reason;
  const Eigen::Index n = C.rows();
  ASSERT_EQ(r.Y.rows(), n);
  ASSERT_EQ(r.Lambda.rows(), n);
  ASSERT_EQ(r.Lambda.cols(), d);
  EXPECT_EQ(r.d, d);
  EXPECT_EQ(r.blocks, n / d);
  // Duality: weak duality and the certified gap.
  EXPECT_LE(r.dual_bound, r.objective + rel_tol(1e-9, r.objective))
      << "dual_bound " << r.dual_bound << " objective " << r.objective;
  EXPECT_TRUE(r.rel_gap <= 1e-9 || r.objective - r.dual_bound <= r.bound_error)
      << "rel_gap " << r.rel_gap << ", gap " << r.objective - r.dual_bound << ", bound_error " << r.bound_error;
  EXPECT_GE(r.min_eig_S, -1e-9);
  // Primal feasibility and the reported objective.
  const Eigen::MatrixXd X = r.X();
  for (Eigen::Index i = 0; i < n; i += d)
    EXPECT_LE((X.block(i, i, d, d) - Eigen::MatrixXd::Identity(d, d)).cwiseAbs().maxCoeff(), 1e-7)
        << "diagonal block at " << i;
  EXPECT_NEAR(r.objective, (C.cwiseProduct(X)).sum(), rel_tol(1e-9, r.objective) * std::max(1.0, C.norm()));
  // The dual bound is tr Λ + n·min(0, λ_min(S)) with S = C − blkdiag(Λ) (unscaled); the
  // reported bound_error allows for the eigensolver's error in λ_min.
  Eigen::MatrixXd S = C;
  for (Eigen::Index i = 0; i < n; i += d) S.block(i, i, d, d) -= r.Lambda.middleRows(i, d);
  EXPECT_LE((S - S.transpose()).cwiseAbs().maxCoeff(), 1e-12 * std::max(1.0, C.norm()));
  const double lmin = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(S, Eigen::EigenvaluesOnly).eigenvalues()(0);
  double trace_lambda = 0;
  for (Eigen::Index i = 0; i < n; i += d) trace_lambda += r.Lambda.middleRows(i, d).trace();
  EXPECT_NEAR(r.dual_bound, trace_lambda + static_cast<double>(n) * std::min(0.0, lmin),
              1e-9 * std::max(1.0, C.norm()));
  EXPECT_NEAR(lmin / r.scale, r.min_eig_S, 1e-9);
  EXPECT_GE(r.bound_error, 0.0);
  // (n·4nε‖S‖₂ and the roundings of tr Λ and of the scale, ‖S‖₂ ≤ ‖C‖_F + max |Λ| ≤ 2‖C‖_F)
  EXPECT_LE(r.bound_error, 16.0 * n * n * std::numeric_limits<double>::epsilon() * std::max(1.0, C.norm()));
}

// ---------------------------------------------------------------------------------------
// Closed forms for N = 2.

// d = 2, C = [[A, B], [Bᵀ, D]]. Feasible X = [[I, R], [Rᵀ, I]] with X ⪰ 0 ⇔ ‖R‖₂ ≤ 1, and
// ⟨C, X⟩ = tr A + tr D + 2⟨B, R⟩. With B = U Σ Vᵀ, min over ‖R‖₂ ≤ 1 of ⟨B, R⟩ = −Σ σ_k
// (nuclear norm, von Neumann), attained at R = −U Vᵀ (uniquely when B has full rank).
struct TwoBlockOptimum {
  double value;
  Eigen::Matrix2d R;
};

TwoBlockOptimum two_block_optimum(const Eigen::MatrixXd& C) {
  const Eigen::MatrixXd B = C.block(0, 2, 2, 2);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(B, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return {C.block<2, 2>(0, 0).trace() + C.block<2, 2>(2, 2).trace() - 2.0 * svd.singularValues().sum(),
          -svd.matrixU() * svd.matrixV().transpose()};
}

void check_two_block(const Eigen::MatrixXd& C) {
  const TwoBlockOptimum expected = two_block_optimum(C);
  const Result r = fact::sdp::solve(C, 2);
  EXPECT_EQ(r.status, Status::certified_unique) << r.reason;
  EXPECT_NEAR(r.objective, expected.value, rel_tol(1e-8, expected.value));
  EXPECT_EQ(r.rank, 2);
  const Eigen::MatrixXd X = r.X();
  EXPECT_LE((X.block<2, 2>(0, 2) - expected.R).cwiseAbs().maxCoeff(), 1e-6) << "X_12 =\n"
                                                                             << X.block<2, 2>(0, 2) << "\nexpected\n"
                                                                             << expected.R;
  expect_certificate(C, 2, r);
}

TEST(SdpClosedForm, TwoBlocksD2PsdCostIsTraceMinusTwiceNuclearNorm) {
  for (unsigned seed = 1; seed <= 8; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    check_two_block(random_psd(4, seed));
  }
}

TEST(SdpClosedForm, TwoBlocksD2IndefiniteCostIsTraceMinusTwiceNuclearNorm) {
  for (unsigned seed = 101; seed <= 104; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    check_two_block(random_symmetric(4, seed));
  }
}

// d = 1: X = [[1, x], [x, 1]], |x| ≤ 1, ⟨C, X⟩ = c11 + c22 + 2 c12 x ⇒ optimum c11 + c22 − 2|c12|
// at x = −sign(c12).
TEST(SdpClosedForm, TwoBlocksD1IsDiagonalMinusTwiceAbsOffDiagonal) {
  for (unsigned seed = 1; seed <= 8; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Eigen::MatrixXd C = seed % 2 ? random_psd(2, seed) : random_symmetric(2, seed);
    const double expected = C(0, 0) + C(1, 1) - 2.0 * std::abs(C(0, 1));
    const Result r = fact::sdp::solve(C, 1);
    EXPECT_EQ(r.status, Status::certified_unique) << r.reason;
    EXPECT_NEAR(r.objective, expected, rel_tol(1e-8, expected));
    EXPECT_NEAR(r.X()(0, 1), C(0, 1) > 0 ? -1.0 : 1.0, 1e-6);
    expect_certificate(C, 1, r);
  }
}

// ---------------------------------------------------------------------------------------
// Exact recovery on noise-free rotation data.

fact::SyntheticRounds noise_free(int drones, int rounds, std::uint64_t seed) {
  fact::SyntheticOptions o;
  o.drones = drones;
  o.rounds = rounds;
  o.noise = 0.0;
  o.seed = seed;
  return fact::make_synthetic_rounds(o);
}

void expect_yaws_recovered(const Result& r, const std::vector<double>& yaw) {
  const std::vector<double> angles = fact::sdp::rotation_angles(fact::sdp::round_rotations(r, 0));
  ASSERT_EQ(angles.size(), yaw.size());
  for (std::size_t i = 0; i < yaw.size(); ++i)
    EXPECT_NEAR(wrap(angles[i] - (yaw[i] - yaw[0])), 0.0, 1e-6)
        << "drone " << i << ": got " << angles[i] << ", truth " << wrap(yaw[i] - yaw[0]);
}

TEST(SdpRecovery, ComplexFormNoiseFreeIsUniqueRankTwoAndRecoversYaws) {
  for (int n = 3; n <= 8; ++n) {
    SCOPED_TRACE("N = " + std::to_string(n));
    const fact::SyntheticRounds s = noise_free(n, n + 1, 10 + n);
    const Eigen::MatrixXd C = fact::sdp::complex_form(fact::paper_cost(s.sums));
    const Result r = fact::sdp::solve(C, 2);
    EXPECT_EQ(r.status, Status::certified_unique) << r.reason;
    EXPECT_EQ(r.rank, 2);
    EXPECT_NEAR(r.objective, 0.0, 1e-9 * C.norm());
    expect_yaws_recovered(r, s.yaw);
    expect_certificate(C, 2, r);
  }
}

TEST(SdpRecovery, PlainFormNoiseFreeWithTwoNRoundsRecoversYaws) {
  for (int n = 3; n <= 8; ++n) {
    SCOPED_TRACE("N = " + std::to_string(n));
    const fact::SyntheticRounds s = noise_free(n, 2 * n, 20 + n);
    const Eigen::MatrixXd C = fact::paper_cost(s.sums);
    const Result r = fact::sdp::solve(C, 2);
    EXPECT_EQ(r.status, Status::certified_unique) << r.reason;
    EXPECT_EQ(r.rank, 2);
    EXPECT_NEAR(r.objective, 0.0, 1e-9 * C.norm());
    expect_yaws_recovered(r, s.yaw);
    expect_certificate(C, 2, r);
  }
}

// ---------------------------------------------------------------------------------------
// Real embedding of a Hermitian problem.
//
// With z_k = e^{iφ_k}, a connected graph and weights w_kl > 0, H = Deg − W, W_kl = w_kl z_k z̄_l,
// is unitarily similar to the graph Laplacian: H ⪰ 0 with null space span{z}. So
// min ⟨H, Z⟩ over Hermitian Z ⪰ 0, Z_kk = 1 is 0, attained only by Z = z z*. Adding a real
// diagonal Δ shifts the optimum by tr Δ (Z_kk = 1) without moving the optimiser. The real
// embedding doubles the optimum, and its unique optimum is X with 2×2 blocks
// X_kl = [[Re Z_kl, −Im Z_kl], [Im Z_kl, Re Z_kl]] = rot(φ_k − φ_l).
struct PhaseInstance {
  Eigen::MatrixXcd H;
  std::vector<double> phi;
};

PhaseInstance phase_laplacian() {
  const std::vector<double> phi = {0.3, -2.1, 1.7, 2.9};
  const std::vector<std::pair<int, int>> edges = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 2}};
  const std::vector<double> weight = {1.0, 0.5, 2.0, 1.5, 0.8};
  Eigen::MatrixXcd H = Eigen::MatrixXcd::Zero(4, 4);
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const auto [k, l] = edges[e];
    const std::complex<double> zk = std::polar(1.0, phi[k]), zl = std::polar(1.0, phi[l]);
    H(k, l) -= weight[e] * zk * std::conj(zl);
    H(l, k) -= weight[e] * zl * std::conj(zk);
    H(k, k) += weight[e];
    H(l, l) += weight[e];
  }
  return {H, phi};
}

TEST(SdpRealEmbedding, PhaseLaplacianHasZeroOptimumAttainedByThePhases) {
  const PhaseInstance inst = phase_laplacian();
  // Sanity of the construction itself: H z = 0, H ⪰ 0 with a one-dimensional null space.
  Eigen::VectorXcd z(4);
  for (int k = 0; k < 4; ++k) z(k) = std::polar(1.0, inst.phi[k]);
  ASSERT_LE((inst.H * z).norm(), 1e-12);
  const Eigen::VectorXd hev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>(inst.H).eigenvalues();
  ASSERT_NEAR(hev(0), 0.0, 1e-12);
  ASSERT_GT(hev(1), 0.1);

  const Eigen::MatrixXd C = fact::sdp::real_embedding(inst.H);
  ASSERT_LE((C - C.transpose()).cwiseAbs().maxCoeff(), 1e-15);
  const Result r = fact::sdp::solve(C, 2);
  EXPECT_EQ(r.status, Status::certified_unique) << r.reason;
  EXPECT_EQ(r.rank, 2);
  EXPECT_NEAR(r.objective, 0.0, 1e-9 * C.norm());
  expect_certificate(C, 2, r);

  // The optimum is the embedding of z z*: block (k,l) = rot(φ_k − φ_l).
  const Eigen::MatrixXd X = r.X();
  for (int k = 0; k < 4; ++k)
    for (int l = 0; l < 4; ++l) {
      const Eigen::Matrix2d expected = Eigen::Rotation2Dd(inst.phi[k] - inst.phi[l]).toRotationMatrix();
      EXPECT_LE((X.block<2, 2>(2 * k, 2 * l) - expected).cwiseAbs().maxCoeff(), 1e-6) << "block " << k << "," << l;
    }
  // In sdp.h's convention X_kl = R_kᵀ R_l, so R_k = rot(−φ_k) and round_rotations(·, 0)[k] =
  // R_0ᵀ R_k = rot(φ_0 − φ_k): the phases up to the global phase φ_0, with the sign flipped.
  const std::vector<double> angles = fact::sdp::rotation_angles(fact::sdp::round_rotations(r, 0));
  ASSERT_EQ(angles.size(), 4u);
  for (int k = 0; k < 4; ++k)
    EXPECT_NEAR(wrap(angles[k] - (inst.phi[0] - inst.phi[k])), 0.0, 1e-6) << "phase " << k;
}

TEST(SdpRealEmbedding, ObjectiveIsTwiceTheComplexOptimum) {
  const PhaseInstance inst = phase_laplacian();
  const std::vector<double> shift = {0.4, 1.3, -0.2, 2.5};  // complex optimum = Σ shift = 4.0
  Eigen::MatrixXcd H = inst.H;
  double complex_optimum = 0;
  for (int k = 0; k < 4; ++k) {
    H(k, k) += shift[k];
    complex_optimum += shift[k];
  }
  const Eigen::MatrixXd C = fact::sdp::real_embedding(H);
  const Result r = fact::sdp::solve(C, 2);
  EXPECT_EQ(r.status, Status::certified_unique) << r.reason;
  EXPECT_NEAR(r.objective, 2.0 * complex_optimum, rel_tol(1e-8, 2.0 * complex_optimum));
  expect_certificate(C, 2, r);
  const std::vector<double> angles = fact::sdp::rotation_angles(fact::sdp::round_rotations(r, 2));
  for (int k = 0; k < 4; ++k)
    EXPECT_NEAR(wrap(angles[k] - (inst.phi[2] - inst.phi[k])), 0.0, 1e-6) << "phase " << k;
}

TEST(SdpRealEmbedding, BlocksFollowTheDocumentedLayout) {
  Eigen::MatrixXcd H(2, 2);
  H << std::complex<double>(2, 0), std::complex<double>(0.5, -1.5), std::complex<double>(0.5, 1.5),
      std::complex<double>(3, 0);
  const Eigen::MatrixXd C = fact::sdp::real_embedding(H);
  ASSERT_EQ(C.rows(), 4);
  ASSERT_EQ(C.cols(), 4);
  Eigen::Matrix2d b01;
  b01 << 0.5, 1.5, -1.5, 0.5;  // [[Re h, −Im h], [Im h, Re h]] for h = 0.5 − 1.5i
  EXPECT_EQ(Eigen::Matrix2d(C.block<2, 2>(0, 2)), b01);
  EXPECT_EQ(Eigen::Matrix2d(C.block<2, 2>(0, 0)), (2.0 * Eigen::Matrix2d::Identity()).eval());
  EXPECT_EQ(C, C.transpose());
}

// ---------------------------------------------------------------------------------------
// Agreement with the optima of SDPA and CSDP (test/data/sdp/optima.csv).

struct PeerRow {
  std::string name;
  int n = 0, d = 0;
  double sdpa = 0, csdp = 0, csdp_binary = 0;
};

std::vector<PeerRow> load_peer_optima() {
  std::vector<PeerRow> rows;
  std::ifstream in(std::string(FACT_TEST_DATA) + "/sdp/optima.csv");
  std::string line;
  if (!std::getline(in, line)) return rows;  // header
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) f.push_back(cell);
    if (f.size() != 6) return {};
    rows.push_back({f[0], std::stoi(f[1]), std::stoi(f[2]), std::stod(f[3]), std::stod(f[4]), std::stod(f[5])});
  }
  return rows;
}

TEST(SdpPeers, OptimaTableIsReadable) {
  std::ifstream in(std::string(FACT_TEST_DATA) + "/sdp/optima.csv");
  std::string header;
  ASSERT_TRUE(std::getline(in, header)) << FACT_TEST_DATA "/sdp/optima.csv";
  EXPECT_EQ(header, "name,n,d,sdpa_objective,csdp_objective,csdp_binary_objective");
  EXPECT_EQ(load_peer_optima().size(), 12u);
}

void PrintTo(const PeerRow& row, std::ostream* os) { *os << row.name; }

class SdpPeerAgreement : public ::testing::TestWithParam<PeerRow> {};

TEST_P(SdpPeerAgreement, MatchesSdpaAndCsdp) {
  const PeerRow& row = GetParam();
  int d = 0;
  const Eigen::MatrixXd C = fact::test::read_sdpa_sparse(std::string(FACT_TEST_DATA) + "/sdp/" + row.name + ".dat-s", &d);
  ASSERT_EQ(C.rows(), row.n);
  ASSERT_EQ(d, row.d);
  const Result r = fact::sdp::solve(C, d);
  EXPECT_TRUE(r.certified()) << fact::sdp::to_string(r.status) << ": " << r.reason;
  EXPECT_NEAR(r.objective, row.sdpa, rel_tol(1e-6, row.sdpa)) << "SDPA";
  EXPECT_NEAR(r.objective, row.csdp, rel_tol(1e-6, row.csdp)) << "CSDP library";
  EXPECT_NEAR(r.objective, row.csdp_binary, rel_tol(1e-6, row.csdp_binary)) << "csdp executable (8 digits)";
  if (r.certified()) expect_certificate(C, d, r);
}

INSTANTIATE_TEST_SUITE_P(OptimaCsv, SdpPeerAgreement, ::testing::ValuesIn(load_peer_optima()),
                         [](const ::testing::TestParamInfo<PeerRow>& info) { return info.param.name; });

// ---------------------------------------------------------------------------------------
// The complex form, solved in complex arithmetic.

using fact::test::noisy_plain_cost;

TEST(SdpComplexForm, AutomaticSolvesItInComplexArithmeticAndAgreesWithTheInteriorPoint) {
  int climbed = 0;  // instances whose optimum has rank > 2: the staircase had to climb
  for (int n : {3, 5, 6, 8, 12}) {
    for (std::uint64_t seed : {1u, 2u, 3u}) {
      SCOPED_TRACE("N = " + std::to_string(n) + ", seed " + std::to_string(seed));
      const Eigen::MatrixXd C = fact::sdp::complex_form(noisy_plain_cost(n, seed));
      const Result r = fact::sdp::solve(C, 2);
      EXPECT_EQ(r.method_used, Method::complex_low_rank);
      expect_certificate(C, 2, r);
      // Λ_ii = μ_i I₂: the complex certificate's multipliers sit on the block diagonals.
      for (Eigen::Index i = 0; i < C.rows(); i += 2) {
        EXPECT_EQ(r.Lambda(i, 1), 0.0);
        EXPECT_EQ(r.Lambda(i + 1, 0), 0.0);
        EXPECT_EQ(r.Lambda(i, 0), r.Lambda(i + 1, 1));
      }
      if (r.rank > 2) ++climbed;
      // The rank (counted from the complex factor's own Gram) is Y's: its singular values above
      // 1e-4 of the largest, by an SVD.
      const Eigen::VectorXd singular = Eigen::JacobiSVD<Eigen::MatrixXd>(r.Y).singularValues();
      EXPECT_EQ(r.rank, (singular.array() > 1e-4 * singular[0]).count());
      Options o;
      o.method = Method::interior_point;
      const Result ip = fact::sdp::solve(C, 2, o);
      EXPECT_LE(r.dual_bound, ip.objective + 1e-12 * r.scale);
      if (ip.certified()) {
        EXPECT_LE(ip.dual_bound, r.objective + 1e-12 * r.scale);
      }
    }
  }
  EXPECT_GT(climbed, 0) << "no instance had a high-rank optimum: the staircase was not exercised";
}

// A complex-form cost whose optimum has a rank the automatic staircase does not climb to
// (N = 32: its Newton system is capped at 80 unknowns, so rank 1 only) goes to an interior
// point (the complex one; the real one when that does not certify), and is certified with a
// complex certificate (Λ_ii = μ_i I₂, where the real interior point's blocks are general) at the
// real interior point's optimum.
TEST(SdpComplexForm, AutomaticCertifiesAHighRankOptimumBeyondTheStaircase) {
  for (std::uint64_t seed : {1u, 2u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Eigen::MatrixXd C = fact::sdp::complex_form(noisy_plain_cost(32, seed));
    const Result r = fact::sdp::solve(C, 2);
    EXPECT_EQ(r.method_used, Method::interior_point) << r.reason;
    EXPECT_GT(r.rank, 2);
    expect_certificate(C, 2, r);
    for (Eigen::Index i = 0; i < C.rows(); i += 2) {
      EXPECT_EQ(r.Lambda(i, 1), 0.0);
      EXPECT_EQ(r.Lambda(i, 0), r.Lambda(i + 1, 1));
    }
    Options o;
    o.method = Method::interior_point;
    const Result ip = fact::sdp::solve(C, 2, o);  // the real interior point alone, no polish
    EXPECT_LE(r.dual_bound, ip.objective + 1e-12 * r.scale);  // r's bound holds for ip's feasible X
    EXPECT_NEAR(r.objective, ip.objective, 1e-7 * std::abs(ip.objective));
  }
}

TEST(SdpComplexForm, ExplicitMethodRejectsACostThatIsNotAComplexEmbedding) {
  Options o;
  o.method = Method::complex_low_rank;
  const Result plain = fact::sdp::solve(noisy_plain_cost(5, 1), 2, o);
  EXPECT_EQ(plain.status, Status::invalid_input);
  EXPECT_NE(plain.reason.find("complex_low_rank"), std::string::npos) << plain.reason;
  EXPECT_NE(plain.reason.find("not the real embedding of a Hermitian matrix"), std::string::npos) << plain.reason;
  EXPECT_NE(plain.reason.find("C(0,"), std::string::npos) << plain.reason;
  const Result d1 = fact::sdp::solve(random_psd(6, 3), 1, o);
  EXPECT_EQ(d1.status, Status::invalid_input);
  EXPECT_NE(d1.reason.find("d = 1"), std::string::npos) << d1.reason;
}

TEST(SdpComplexForm, ABrokenBlockPatternFallsBackToTheRealSolver) {
  Eigen::MatrixXd C = fact::sdp::complex_form(noisy_plain_cost(6, 2));
  C(2, 4) = C(4, 2) = std::nextafter(C(2, 4), 1e300);  // one ulp: no longer [[a, −b], [b, a]]
  const Result r = fact::sdp::solve(C, 2);
  EXPECT_NE(r.method_used, Method::complex_low_rank);
  expect_certificate(C, 2, r);
  const Result exact = fact::sdp::solve(fact::sdp::complex_form(noisy_plain_cost(6, 2)), 2);
  EXPECT_NEAR(r.objective, exact.objective, 1e-9 * std::max(1.0, std::abs(exact.objective)));
}

// ---------------------------------------------------------------------------------------
// Degenerate (non-unique) optima.

TEST(SdpStatus, ZeroCostIsCertifiedNotUnique) {
  const Eigen::MatrixXd C = Eigen::MatrixXd::Zero(8, 8);
  const Result r = fact::sdp::solve(C, 2);
  EXPECT_EQ(r.status, Status::certified_not_unique) << r.reason;
  EXPECT_EQ(r.objective, 0.0);
  EXPECT_GT(r.nullity, 2);
  expect_certificate(C, 2, r);
}

TEST(SdpStatus, TooFewRoundsIsCertifiedNotUnique) {
  const fact::SyntheticRounds s = noise_free(5, 1, 3);
  const Eigen::MatrixXd C = fact::sdp::complex_form(fact::paper_cost(s.sums));
  const Result r = fact::sdp::solve(C, 2);
  EXPECT_EQ(r.status, Status::certified_not_unique) << r.reason;
  EXPECT_NEAR(r.objective, 0.0, 1e-9 * C.norm());
  EXPECT_GT(r.nullity, 2);
  expect_certificate(C, 2, r);
}

// The plain relaxation of noise-free rounds (N + 1 of them): the optimum is 0, attained on C's
// null space of dimension N − 1. The interior point used to stall above the gap tolerance there
// (relative gap 1.3e-7 at N = 8, seed 1) and these solves ended not_certified (10 of 40 seeds
// at N = 8); with the primal direction formed through Z's factor near the optimum they certify.
// With a zero optimum the only optimal dual is Λ = 0 ((C − Λ) X = 0 and C X = 0 give Λ_ii = 0),
// so S = C with nullity N − 1 > 2: not unique (these seeds reach the interior point, which used to
// call some of them unique; StatusOfADegenerateOptimumDoesNotDependOnThePath covers both paths).
TEST(SdpStatus, PlainFormNoiseFreeRoundsAreCertified) {
  for (const auto& [drones, seed] : {std::pair{8, 1}, {8, 7}, {8, 9}, {8, 11}, {12, 2}, {12, 5}, {4, 1}, {4, 35}, {5, 8}}) {
    SCOPED_TRACE("N = " + std::to_string(drones) + ", seed " + std::to_string(seed));
    const Eigen::MatrixXd C = fact::paper_cost(noise_free(drones, drones + 1, seed).sums);
    const Result r = fact::sdp::solve(C, 2);
    expect_certificate(C, 2, r);
    EXPECT_NEAR(r.objective, 0.0, 1e-9 * C.norm());
    EXPECT_EQ(r.status, Status::certified_not_unique) << r.reason;
    EXPECT_GT(r.nullity, 2) << r.reason;
  }
}

// Where the optimum is not strictly complementary (its only optimal Λ has S with nullity > d),
// the status must not depend on the path. Before such results were certified against their
// rank-d factor's own Λ, a noise-free instance below came out certified_unique only through the
// interior point (its near-optimal Λ shows λ_{d+1}(S) of the order of √μ, here 1e-10 … 1e-9) or
// an unconverged staircase factor, never through rank-d Newton: plain form, N = 4, N + 1 rounds,
// 25 of 40 seeds unique (all 25 interior-point solves); complex form, N = 4, 2 rounds, 7 of 40
// (5 of the 7 interior-point solves, and 2 staircase factors of rank 4 that had not converged).
// The plain seeds reach both paths, and the test checks that they still do.
TEST(SdpStatus, StatusOfADegenerateOptimumDoesNotDependOnThePath) {
  int by_newton = 0, by_interior_point = 0;  // plain-form solves per path
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Eigen::MatrixXd plain = fact::paper_cost(noise_free(4, 5, seed).sums);
    const Eigen::MatrixXd tight = fact::sdp::complex_form(fact::paper_cost(noise_free(4, 2, seed).sums));
    for (const Eigen::MatrixXd* C : {&plain, &tight}) {
      const Result r = fact::sdp::solve(*C, 2);
      EXPECT_EQ(r.status, Status::certified_not_unique) << (C == &plain ? "plain: " : "complex: ") << r.reason;
      EXPECT_GT(r.nullity, 2) << r.reason;
      if (C == &plain) {
        by_newton += r.method_used == Method::low_rank ? 1 : 0;
        by_interior_point += r.method_used == Method::interior_point ? 1 : 0;
      }
    }
  }
  EXPECT_GE(by_newton, 5);  // 15 and 25 of 40 with -march=native on x86-64
  EXPECT_GE(by_interior_point, 5);
}

// fact-bench-sdp's plain_noisy instance: the paper's plain cost of N drones, N + 1 rounds, noise
// 0.05, seed 2000 + N.
Eigen::MatrixXd bench_plain_noisy_cost(int drones) {
  fact::SyntheticOptions o;
  o.drones = drones;
  o.rounds = drones + 1;
  o.noise = 0.05;
  o.seed = 2000 + drones;
  return fact::paper_cost(fact::make_synthetic_rounds(o).sums);
}

// The interior point alone (no Newton polish) reaches the gap on the paper's noisy plain cost;
// before, it stalled at a relative gap of 3e-9 (N = 5) and 1.4e-8 (N = 8).
TEST(SdpStatus, InteriorPointAloneCertifiesTheNoisyPlainForm) {
  for (int drones : {5, 8}) {
    SCOPED_TRACE("N = " + std::to_string(drones));
    const Eigen::MatrixXd C = bench_plain_noisy_cost(drones);
    Options options;
    options.method = Method::interior_point;
    const Result r = fact::sdp::solve(C, 2, options);
    EXPECT_EQ(r.status, Status::certified_not_unique) << r.reason;
    expect_certificate(C, 2, r);
  }
}

// Rank-2 Newton that stops with S ⪰ 0 but a bound just short of the gap (noise-free plain form,
// N = 4: λ_min(S) ≈ −1e-13, a relative gap of a few 1e-9 on a zero optimum) takes one more step
// and certifies, instead of handing the problem to the interior point. Which seeds end in that
// state depends on the last bits of the arithmetic (on arm64, where the compiler fuses
// multiply-adds, seed 9's Newton converges to another critical point), so the test runs 40 seeds:
// every rank-2 Newton run that reaches S ⪰ 0 (low_rank capped at rank 2 and 25 steps, the
// automatic mode's first try) must certify, and the automatic solve must then keep it.
TEST(SdpStatus, NewtonShortOfTheGapTakesOneMoreStep) {
  int reached = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    const Eigen::MatrixXd C = fact::paper_cost(noise_free(4, 5, seed).sums);
    fact::sdp::Options rank_d;
    rank_d.method = Method::low_rank;
    rank_d.max_rank = 2;
    rank_d.max_newton_iterations = 25;
    const Result newton = fact::sdp::solve(C, 2, rank_d);
    if (newton.min_eig_S < -rank_d.psd_tol) continue;  // another critical point: the interior point's case
    ++reached;
    EXPECT_TRUE(newton.certified()) << "seed " << seed << ": " << newton.reason;
    const Result r = fact::sdp::solve(C, 2);
    EXPECT_EQ(r.method_used, Method::low_rank) << "seed " << seed << ": " << r.reason;
    expect_certificate(C, 2, r);
  }
  EXPECT_GE(reached, 6);  // 12 of 40 seeds with x86-64 baseline flags, 20 with fused multiply-adds (native build)
}

TEST(SdpStatus, UncoupledD1BlocksAreCertifiedNotUnique) {
  Eigen::MatrixXd C(2, 2);
  C << 1.5, 0.0, 0.0, 2.5;  // ⟨C, X⟩ = 4 for every feasible X
  const Result r = fact::sdp::solve(C, 1);
  EXPECT_EQ(r.status, Status::certified_not_unique) << r.reason;
  EXPECT_NEAR(r.objective, 4.0, 1e-9);
  expect_certificate(C, 1, r);
}

// ---------------------------------------------------------------------------------------
// The zero optimum: C ⪰ 0 whose null space holds a feasible X (Method::null_space).

// A PSD cost of rank `rank` (n × n) with a planted zero optimum: Y₀ (n × k) Gaussian with every
// d-row block replaced by its polar factor (orthonormal rows, so Y₀ Y₀ᵀ is feasible), and
// C = B Bᵀ with B = (I − Q Qᵀ) G, Q an orthonormal basis of Y₀'s range and G n × rank Gaussian.
// Then C Y₀ = 0: the optimum is 0 and X = Y₀ Y₀ᵀ attains it.
Eigen::MatrixXd planted_zero_cost(Eigen::Index n, int d, Eigen::Index k, Eigen::Index rank, unsigned seed) {
  Eigen::MatrixXd Y0 = gaussian(n, k, seed);
  for (Eigen::Index i = 0; i < n; i += d) {
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(Y0.middleRows(i, d), Eigen::ComputeThinU | Eigen::ComputeThinV);
    Y0.middleRows(i, d) = svd.matrixU() * svd.matrixV().transpose();
  }
  const Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(Y0).householderQ() * Eigen::MatrixXd::Identity(n, k);
  const Eigen::MatrixXd B = gaussian(n, rank, seed + 1) - Q * (Q.transpose() * gaussian(n, rank, seed + 1));
  return B * B.transpose();
}

// What a zero optimum found on C's null space must be: certified against Λ = 0 (S = C), an
// objective of 0 up to rounding, and a factor that C annihilates.
void expect_zero_optimum(const Eigen::MatrixXd& C, int d, const Result& r) {
  EXPECT_EQ(r.method_used, Method::null_space) << r.reason;
  EXPECT_EQ(r.status, Status::certified_not_unique) << r.reason;
  expect_certificate(C, d, r);
  EXPECT_EQ(r.Lambda.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_NEAR(r.objective, 0.0, 1e-12 * C.norm());
  EXPECT_LE((C * r.Y).norm(), 1e-10 * C.norm() * std::sqrt(static_cast<double>(C.rows())));
  EXPECT_GT(r.nullity, d);
}

// The paper's plain relaxation with N + 1 noisy rounds has a zero optimum from N ≈ 10 on (C has
// nullity N − 1): fact-bench-sdp's plain_noisy N = 12 and 16. Automatic mode finds it on C's null
// space (before rank-2 Newton, which cannot end there), and the interior point alone reaches the
// same optimum.
TEST(SdpNullSpace, PlainFormWithAZeroOptimumIsSolvedOnTheNullSpace) {
  for (int drones : {12, 16}) {
    SCOPED_TRACE("N = " + std::to_string(drones));
    const Eigen::MatrixXd C = bench_plain_noisy_cost(drones);
    const Result r = fact::sdp::solve(C, 2);
    expect_zero_optimum(C, 2, r);
    EXPECT_EQ(r.rank, drones - 1);  // X = V P Vᵀ with P ≻ 0 on the (N − 1)-dimensional null space
    Options ip;
    ip.method = Method::interior_point;
    const Result interior = fact::sdp::solve(C, 2, ip);
    ASSERT_TRUE(interior.certified()) << interior.reason;
    EXPECT_NEAR(interior.objective, r.objective, 1e-9 * C.norm());
  }
}

// Automatic mode on C (d = 2) certifies an optimum of rank above 2 through `method`, at the
// interior point's objective.
void expect_high_rank_optimum_by(const Eigen::MatrixXd& C, Method method) {
  const Result r = fact::sdp::solve(C, 2);
  expect_certificate(C, 2, r);
  EXPECT_EQ(r.method_used, method) << r.reason;
  EXPECT_GT(r.rank, 2);
  Options ip;
  ip.method = Method::interior_point;
  const Result interior = fact::sdp::solve(C, 2, ip);
  ASSERT_TRUE(interior.certified()) << interior.reason;
  EXPECT_NEAR(r.objective, interior.objective, 1e-8 * std::max(1.0, std::abs(interior.objective)));
}

// For d = 2 and n ≤ 8 automatic mode climbs the real staircase past rank 2 before the interior
// point: the plain form at N = 3 and 4 and a full-rank random C at N = 4 have optima of rank 3,
// which the staircase certifies itself, at the interior point's objective.
TEST(SdpStaircase, SmallRealProblemsClimbPastRankTwo) {
  struct Case {
    std::string label;
    Eigen::MatrixXd C;
  };
  for (const Case& c : {Case{"plain N = 3", bench_plain_noisy_cost(3)}, Case{"plain N = 4", bench_plain_noisy_cost(4)},
                        Case{"full rank N = 4", random_psd(8, 48)}}) {
    SCOPED_TRACE(c.label);
    expect_high_rank_optimum_by(c.C, Method::low_rank);
  }
}

// At n = 10 and 12 automatic mode climbs past rank 2 only from a steep saddle (λ_min(S) below
// −kSteepClimbEig at the rank-2 critical point): full-rank random C (fact-bench-sdp's
// random_fullrank N = 5 and 6) has optima of rank 3 and 4 that the staircase certifies at the
// interior point's objective (λ_min(S) ≈ −0.06 and −0.07 at rank 2); the plain form at N = 5 and
// 6, whose rank-2 saddle is shallow (λ_min(S) ≈ −6e-4 and −1.3e-3), goes to the interior point.
TEST(SdpStaircase, TenAndTwelveRowsClimbOnlyFromASteepSaddle) {
  struct Case {
    std::string label;
    Eigen::MatrixXd C;
    Method expected;
  };
  for (const Case& c : {Case{"full rank N = 5", random_psd(10, 4005), Method::low_rank},
                        Case{"full rank N = 6", random_psd(12, 4006), Method::low_rank},
                        Case{"plain N = 5", bench_plain_noisy_cost(5), Method::interior_point},
                        Case{"plain N = 6", bench_plain_noisy_cost(6), Method::interior_point}}) {
    SCOPED_TRACE(c.label);
    expect_high_rank_optimum_by(c.C, c.expected);
  }
}

// Planted zero optima for both block sizes, by the explicit method and in automatic mode: d = 2
// on N = 4 and 6 blocks with null spaces of dimension 5 and 9 (a rank-2 factor in them would need
// 2k − 1 ≥ 3N, so rank-2 Newton cannot end there), d = 1 on N = 10 with a null space of dimension 8.
TEST(SdpNullSpace, PlantedZeroOptimaOfBothBlockSizesAreFound) {
  struct Case {
    Eigen::MatrixXd C;
    int d;
  };
  for (const Case& c : {Case{planted_zero_cost(8, 2, 5, 3, 41), 2}, Case{planted_zero_cost(12, 2, 9, 3, 42), 2},
                        Case{planted_zero_cost(10, 1, 8, 2, 43), 1}}) {
    SCOPED_TRACE("n = " + std::to_string(c.C.rows()) + ", d = " + std::to_string(c.d));
    Options explicit_method;
    explicit_method.method = Method::null_space;
    expect_zero_optimum(c.C, c.d, fact::sdp::solve(c.C, c.d, explicit_method));
    const Result automatic = fact::sdp::solve(c.C, c.d);
    expect_certificate(c.C, c.d, automatic);
    EXPECT_EQ(automatic.method_used, Method::null_space) << automatic.reason;  // tried before rank d
    EXPECT_NEAR(automatic.objective, 0.0, 1e-12 * c.C.norm());
  }
}

// Where a rank-d factor fits in the null space automatic mode tries rank-d Newton first and the
// null space after it: with Newton given too few steps to end there (n = 12, d = 2, null space of
// dimension 10, room for a rank-2 factor: 2k − 1 ≥ 3N) the zero optimum comes from the null space,
// and the steps of both count.
TEST(SdpNullSpace, AfterRankDNewtonFailsAutomaticModeTriesTheNullSpace) {
  const Eigen::MatrixXd C = planted_zero_cost(12, 2, 10, 2, 46);
  constexpr int kNewtonSteps = 2;
  Options few_steps;
  few_steps.max_newton_iterations = kNewtonSteps;
  few_steps.max_sweeps = 0;
  const Result r = fact::sdp::solve(C, 2, few_steps);
  expect_zero_optimum(C, 2, r);
  Options null_only = few_steps;
  null_only.method = Method::null_space;
  const Result alone = fact::sdp::solve(C, 2, null_only);
  expect_zero_optimum(C, 2, alone);
  EXPECT_EQ(r.iterations, alone.iterations + kNewtonSteps);  // rank-2 Newton's steps count too
  const Result normal = fact::sdp::solve(C, 2);  // with its steps rank-2 Newton ends there itself
  EXPECT_EQ(normal.method_used, Method::low_rank) << normal.reason;
  EXPECT_NEAR(normal.objective, 0.0, 1e-12 * C.norm());
}

// Dependent constraints: the counts say a null space of dimension k = 2 cannot hold a feasible X
// for N = 9 (3 unknowns in P, 9 equations), but the rows of the planted rank-2 factor take only
// three directions, so three of the equations decide P and Newton's system is singular. The
// explicit method still finds the zero optimum X = Y₀ Y₀ᵀ. (That optimum is unique, one P meets
// the three equations, but S = C has nullity 2 > d = 1, so the status is certified_not_unique.)
TEST(SdpNullSpace, DependentConstraintsDoNotStopTheExplicitMethod) {
  Eigen::MatrixXd Y0(9, 2);  // unit rows at 0°, 50° and 110°, 4 + 3 + 2 of them: Y0ᵀ Y0 is not ∝ I
  const double deg = std::acos(-1.0) / 180.0;
  for (int i = 0; i < 9; ++i) {
    const double angle = (i < 4 ? 0.0 : i < 7 ? 50.0 : 110.0) * deg;
    Y0.row(i) << std::cos(angle), std::sin(angle);
  }
  const Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(Y0).householderQ() * Eigen::MatrixXd::Identity(9, 2);
  const Eigen::MatrixXd B = gaussian(9, 9, 47) - Q * (Q.transpose() * gaussian(9, 9, 47));  // columns ⟂ Y0's
  const Eigen::MatrixXd C = B * B.transpose();                                                 // null(C) = range(Y0)
  Options null_only;
  null_only.method = Method::null_space;
  const Result r = fact::sdp::solve(C, 1, null_only);
  expect_zero_optimum(C, 1, r);
  EXPECT_GT(r.iterations, 0);  // P = (n/k)·I is not feasible: Newton ran on the singular system
  EXPECT_LE((r.X() - Y0 * Y0.transpose()).cwiseAbs().maxCoeff(), 1e-9);
}

// C = 0: every feasible X is optimal; the null space is everything and X = I is found at once.
TEST(SdpNullSpace, ZeroCostIsSolvedAtTheIdentity) {
  Options null_only;
  null_only.method = Method::null_space;
  const Result r = fact::sdp::solve(Eigen::MatrixXd::Zero(6, 6), 2, null_only);
  EXPECT_EQ(r.status, Status::certified_not_unique) << r.reason;
  EXPECT_EQ(r.objective, 0.0);
  EXPECT_EQ(r.iterations, 0);
  EXPECT_LE((r.X() - Eigen::MatrixXd::Identity(6, 6)).cwiseAbs().maxCoeff(), 1e-12);
}

// Where the null space holds no feasible X the explicit method says so and returns no point, and
// automatic mode goes on to the interior point: a full-rank C (null space of dimension 0), an
// indefinite C, and the plain form at N = 8 (null space of dimension 7, optimum > 0).
TEST(SdpNullSpace, WithoutAFeasiblePointItReportsWhyAndAutomaticGoesOn) {
  struct Case {
    std::string label;
    Eigen::MatrixXd C;
    std::string reason;
  };
  const std::vector<Case> cases = {
      {"full rank", random_psd(8, 44), "null space (dimension 0) is smaller than d = 2"},
      {"indefinite", random_symmetric(8, 45), "not positive semidefinite"},
      {"plain N = 8", bench_plain_noisy_cost(8), "null space (dimension 7) gave no feasible X"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.label);
    Options explicit_method;
    explicit_method.method = Method::null_space;
    const Result r = fact::sdp::solve(c.C, 2, explicit_method);
    EXPECT_EQ(r.status, Status::not_certified);
    EXPECT_EQ(r.method_used, Method::null_space);
    EXPECT_EQ(r.Y.size(), 0);
    EXPECT_TRUE(std::isnan(r.objective) && std::isnan(r.dual_bound) && std::isnan(r.bound_error) &&
                std::isnan(r.rel_gap) && std::isnan(r.min_eig_S) && std::isnan(r.eig_gap))
        << r.objective;
    EXPECT_EQ(r.Lambda.size(), 0);
    EXPECT_NE(r.reason.find(c.reason), std::string::npos) << r.reason;
    const Result automatic = fact::sdp::solve(c.C, 2);
    EXPECT_NE(automatic.method_used, Method::null_space);
    expect_certificate(c.C, 2, automatic);
    EXPECT_GT(std::abs(automatic.objective), 1e-6 * c.C.norm());
  }
}

// The plain form with N + 1 rounds at N = 7 and 8: C's null space (dimension 6 and 7) has 21 and
// 28 unknowns for 21 and 24 constraints, fewer than N to spare, and a feasible P in it is rarely
// positive semidefinite; automatic mode does not try it and starts with the interior point, and
// ends where the explicit interior point ends. The explicit null-space method confirms it has no
// feasible X there. At N = 9 (dimension 8, 36 unknowns for 27 constraints: N to spare) automatic
// mode still tries the null space first.
TEST(SdpNullSpace, ARoomForFewPointsIsNotTried) {
  struct Case { int drones; std::uint64_t seed; };
  for (const Case c : {Case{7, 2007}, Case{7, 11}, Case{7, 12}, Case{8, 2008}, Case{8, 11}}) {
    SCOPED_TRACE("N = " + std::to_string(c.drones) + ", seed " + std::to_string(c.seed));
    const Eigen::MatrixXd C = fact::test::plain_cost(c.drones, c.drones + 1, 0.05, c.seed);
    const Result automatic = fact::sdp::solve(C, 2);
    expect_certificate(C, 2, automatic);
    ASSERT_FALSE(automatic.stages.empty());
    EXPECT_EQ(automatic.stages[0].method, "interior_point");
    for (const fact::sdp::Stage& stage : automatic.stages) EXPECT_NE(stage.method, "null_space");
    Options explicit_method;
    explicit_method.method = Method::null_space;
    const Result null = fact::sdp::solve(C, 2, explicit_method);
    EXPECT_EQ(null.status, Status::not_certified);
    const std::string dimension = "null space (dimension " + std::to_string(c.drones - 1) + ") gave no feasible X";
    EXPECT_NE(null.reason.find(dimension), std::string::npos) << null.reason;
    explicit_method.method = Method::interior_point;
    const Result interior = fact::sdp::solve(C, 2, explicit_method);
    ASSERT_TRUE(interior.certified()) << interior.reason;
    EXPECT_NEAR(automatic.objective, interior.objective, 1e-8 * std::abs(interior.objective));
  }
  const Result nine = fact::sdp::solve(bench_plain_noisy_cost(9), 2);
  ASSERT_FALSE(nine.stages.empty());
  EXPECT_EQ(nine.stages[0].method, "null_space");
}

// ---------------------------------------------------------------------------------------
// Bad input.

struct BadInput {
  std::string label;
  Eigen::MatrixXd C;
  int d;
  std::vector<std::string> reason_contains;
};

std::vector<BadInput> bad_inputs() {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<BadInput> cases;
  Eigen::MatrixXd c = random_psd(4, 5);
  c(1, 2) = c(2, 1) = nan;
  cases.push_back({"NaN entry", c, 2, {"not finite", "nan"}});
  c = random_psd(4, 5);
  c(3, 0) = c(0, 3) = inf;
  cases.push_back({"+inf entry", c, 2, {"not finite", "inf"}});
  c = random_psd(4, 5);
  c(0, 3) += 0.25;
  cases.push_back({"non-symmetric", c, 2, {"not symmetric", "C(3,0)"}});
  cases.push_back({"non-square", gaussian(4, 6, 1), 2, {"4×6", "square"}});
  cases.push_back({"n = 5, d = 2", random_psd(5, 2), 2, {"5×5", "divisible", "d = 2"}});
  cases.push_back({"N = 1", random_psd(2, 3), 2, {"N = 1", "at least 2"}});
  cases.push_back({"N = 0", Eigen::MatrixXd(0, 0), 2, {"N = 0"}});
  cases.push_back({"d = 3", random_psd(6, 4), 3, {"d = 3"}});
  cases.push_back({"d = 0", random_psd(6, 4), 0, {"d = 0"}});
  // ‖C‖_F = 4e308 overflows; the scale became inf and a zero C was certified (review, session 29)
  Eigen::MatrixXd huge(4, 4);
  huge << 1, 1, 0, 0, 1, 1, 0, 0, 0, 0, 1, -1, 0, 0, -1, 1;
  cases.push_back({"entries of 1e308", 1e308 * huge, 1, {"too large", "C(0,0) = 1e+308"}});
  // ‖C‖_F = 1.3e307 is finite, but the optimum −1.7e309 is not: certified with objective −inf
  cases.push_back({"optimum beyond a double", -1e307 * Eigen::MatrixXd::Ones(13, 13), 1, {"too large", "n = 13"}});
  // the unscaled Λ is rounded to the subnormal grid: λ_min(C − Λ) = −1.3e-8·‖C‖_F, certified unique
  cases.push_back({"subnormal entries", 1e-318 * random_psd(8, 8), 2, {"subnormal", "scale C up"}});
  return cases;
}

TEST(SdpInvalidInput, EveryBadInputIsRejectedWithAReason) {
  for (const BadInput& b : bad_inputs()) {
    SCOPED_TRACE(b.label);
    const std::string why = fact::sdp::validate(b.C, b.d);
    EXPECT_FALSE(why.empty());
    const Result r = fact::sdp::solve(b.C, b.d);
    EXPECT_EQ(r.status, Status::invalid_input);
    EXPECT_FALSE(r.certified());
    for (const std::string& s : b.reason_contains) {
      EXPECT_NE(why.find(s), std::string::npos) << "validate: '" << why << "' lacks '" << s << "'";
      EXPECT_NE(r.reason.find(s), std::string::npos) << "solve: '" << r.reason << "' lacks '" << s << "'";
    }
  }
}

// Options out of their range: the reason names the field and its value; the defaults validate.
TEST(SdpInvalidInput, BadOptionsAreRejectedWithAReason) {
  const Eigen::MatrixXd C = random_psd(4, 5);
  EXPECT_EQ(fact::sdp::validate(Options{}), "");
  const auto with = [](auto change) {
    Options o;
    change(o);
    return o;
  };
  const std::vector<std::pair<Options, std::string>> cases = {
      {with([](Options& o) { o.gap_tol = std::numeric_limits<double>::quiet_NaN(); }), "gap_tol = nan"},
      {with([](Options& o) { o.psd_tol = -1e-9; }), "psd_tol = -1e-09"},
      {with([](Options& o) { o.null_tol = std::numeric_limits<double>::infinity(); }), "null_tol = inf"},
      {with([](Options& o) { o.max_sweeps = -1; }), "max_sweeps = -1"},
      {with([](Options& o) { o.max_ipm_iterations = -5; }), "max_ipm_iterations = -5"},
      {with([](Options& o) { o.max_newton_iterations = -2; }), "max_newton_iterations = -2"},
      {with([](Options& o) { o.max_rank = -3; }), "max_rank = -3"},
      {with([](Options& o) { o.method = static_cast<fact::sdp::Method>(17); }), "method = 17"},
  };
  for (const auto& [options, field] : cases) {
    SCOPED_TRACE(field);
    EXPECT_NE(fact::sdp::validate(options).find(field), std::string::npos) << fact::sdp::validate(options);
    const Result r = fact::sdp::solve(C, 2, options);
    EXPECT_EQ(r.status, Status::invalid_input);
    EXPECT_NE(r.reason.find(field), std::string::npos) << r.reason;
  }
}

// The edges of C's range solve: the largest entry just inside kLargestObjective/n² and
// kSmallestEntry, each with the status and objective (scaled) of the same C at scale 1.
TEST(SdpInvalidInput, EntriesAtTheEdgesOfTheRangeSolve) {
  const Eigen::MatrixXd C = random_psd(6, 7);
  const Result base = fact::sdp::solve(C, 2);
  ASSERT_TRUE(base.certified()) << base.reason;
  const double largest = C.cwiseAbs().maxCoeff();
  for (const double s : {0.99 * fact::sdp::kLargestObjective / 36 / largest, 1.01 * fact::sdp::kSmallestEntry / largest}) {
    SCOPED_TRACE("scale " + std::to_string(std::log10(s)));
    EXPECT_EQ(fact::sdp::validate(s * C, 2), "");
    const Result r = fact::sdp::solve(s * C, 2);
    EXPECT_EQ(r.status, base.status) << r.reason;
    EXPECT_NEAR(r.objective / s, base.objective, 1e-9 * std::abs(base.objective));
    EXPECT_TRUE(std::isfinite(r.dual_bound) && std::isfinite(r.bound_error));
  }
}

TEST(SdpInvalidInput, GoodInputValidates) {
  EXPECT_EQ(fact::sdp::validate(random_psd(4, 1), 2), "");
  EXPECT_EQ(fact::sdp::validate(random_psd(4, 1), 1), "");
  EXPECT_EQ(fact::sdp::validate(random_symmetric(6, 2), 2), "");
  EXPECT_EQ(fact::sdp::validate(Eigen::MatrixXd::Zero(8, 8), 2), "");
  // Asymmetry at rounding level is accepted (tolerance 1e-9 relative to the largest entry).
  Eigen::MatrixXd c = random_psd(4, 1);
  c(0, 1) += 1e-14;
  EXPECT_EQ(fact::sdp::validate(c, 2), "");
}

// ---------------------------------------------------------------------------------------
// Rounding errors.

TEST(SdpRounding, BadReferenceThrows) {
  const Result r = fact::sdp::solve(random_psd(6, 7), 2);
  ASSERT_TRUE(r.certified()) << r.reason;
  EXPECT_NO_THROW(fact::sdp::round_rotations(r, 2));
  EXPECT_THROW(fact::sdp::round_rotations(r, -1), std::invalid_argument);
  EXPECT_THROW(fact::sdp::round_rotations(r, 3), std::invalid_argument);
}

TEST(SdpRounding, D1ResultThrows) {
  const Result r = fact::sdp::solve(random_psd(4, 7), 1);
  ASSERT_TRUE(r.certified()) << r.reason;
  EXPECT_THROW(fact::sdp::round_rotations(r, 0), std::invalid_argument);
}

TEST(SdpRounding, InvalidResultThrows) {
  const Result r = fact::sdp::solve(random_psd(5, 7), 2);
  ASSERT_EQ(r.status, Status::invalid_input);
  EXPECT_THROW(fact::sdp::round_rotations(r, 0), std::invalid_argument);
}

TEST(SdpRounding, RotationAnglesAreInMinusPiToPi) {
  std::vector<Eigen::Matrix2d> rots;
  for (double a : {0.0, 1.0, -1.0, M_PI, -M_PI, 3.0, -3.0})
    rots.push_back(Eigen::Rotation2Dd(a).toRotationMatrix());
  const std::vector<double> angles = fact::sdp::rotation_angles(rots);
  const std::vector<double> expected = {0.0, 1.0, -1.0, M_PI, M_PI, 3.0, -3.0};
  ASSERT_EQ(angles.size(), expected.size());
  for (std::size_t i = 0; i < angles.size(); ++i) {
    EXPECT_NEAR(angles[i], expected[i], 1e-12) << i;
    EXPECT_GT(angles[i], -M_PI);
    EXPECT_LE(angles[i], M_PI);
  }
}

// ---------------------------------------------------------------------------------------
// Determinism and duality.

TEST(SdpDeterminism, RepeatedSolvesAreBitIdentical) {
  const std::vector<Eigen::MatrixXd> costs = {noisy_plain_cost(6, 4), fact::sdp::complex_form(noisy_plain_cost(5, 9)),
                                              random_symmetric(10, 12)};
  for (Method m : {Method::automatic, Method::low_rank, Method::interior_point, Method::complex_low_rank}) {
    for (std::size_t k = 0; k < costs.size(); ++k) {
      SCOPED_TRACE(std::string(fact::sdp::to_string(m)) + " cost " + std::to_string(k));
      Options o;
      o.method = m;
      const Result a = fact::sdp::solve(costs[k], 2, o);
      const Result b = fact::sdp::solve(costs[k], 2, o);
      EXPECT_EQ(a.status, b.status);
      EXPECT_EQ(a.objective, b.objective);
      EXPECT_EQ(a.dual_bound, b.dual_bound);
      EXPECT_EQ(a.iterations, b.iterations);
      ASSERT_EQ(a.Y.rows(), b.Y.rows());
      ASSERT_EQ(a.Y.cols(), b.Y.cols());
      EXPECT_TRUE((a.Y.array() == b.Y.array()).all());
      EXPECT_TRUE((a.Lambda.array() == b.Lambda.array()).all());
    }
  }
}

TEST(SdpDuality, CertifiedResultsHaveConsistentBoundsForEveryMethod) {
  struct Instance {
    std::string label;
    Eigen::MatrixXd C;
    int d;
  };
  const std::vector<Instance> instances = {
      {"plain noisy N=4", noisy_plain_cost(4, 1), 2},
      {"plain noisy N=7", noisy_plain_cost(7, 2), 2},
      {"plain noisy N=8 (automatic: interior point handed off to Newton)", noisy_plain_cost(8, 6), 2},
      {"complex noisy N=6", fact::sdp::complex_form(noisy_plain_cost(6, 3)), 2},
      {"random symmetric n=12 d=2", random_symmetric(12, 31), 2},
      {"random psd n=9 d=1", random_psd(9, 32), 1},
      {"random symmetric n=10 d=1", random_symmetric(10, 33), 1},
      {"scaled by 1e4", 1e4 * noisy_plain_cost(5, 4), 2},
      {"scaled by 1e-4", 1e-4 * noisy_plain_cost(5, 4), 2},
  };
  for (const Instance& inst : instances) {
    SCOPED_TRACE(inst.label);
    const Result automatic = fact::sdp::solve(inst.C, inst.d);
    expect_certificate(inst.C, inst.d, automatic);
    for (Method m : {Method::low_rank, Method::interior_point, Method::complex_low_rank, Method::null_space}) {
      SCOPED_TRACE(fact::sdp::to_string(m));
      Options o;
      o.method = m;
      const Result r = fact::sdp::solve(inst.C, inst.d, o);
      if (m == Method::complex_low_rank && inst.label.rfind("complex", 0) != 0) {
        EXPECT_EQ(r.status, Status::invalid_input);  // only the complex form has the block pattern
        continue;
      }
      EXPECT_EQ(r.method_used, m);
      if (!r.certified()) continue;  // a single method may legitimately fail to certify
      expect_certificate(inst.C, inst.d, r);
      // Each certified dual bound is a lower bound on the optimum, hence on the other
      // method's objective; the objectives themselves agree to within the two gaps.
      const double slack = 1e-12 * r.scale;
      EXPECT_LE(automatic.dual_bound, r.objective + slack);
      EXPECT_LE(r.dual_bound, automatic.objective + slack);
    }
  }
}


// Findings of an independent review (session 24), each a case that was certified wrongly.

// The largest entry of X_ii − I over the blocks.
double block_feasibility_error(const Result& r) {
  const Eigen::MatrixXd X = r.X();
  double worst = 0;
  for (Eigen::Index i = 0; i < X.rows(); i += r.d)
    worst = std::max(worst, (X.block(i, i, r.d, r.d) - Eigen::MatrixXd::Identity(r.d, r.d)).cwiseAbs().maxCoeff());
  return worst;
}

// ‖C‖_F overflowed to inf from entries of 1e154 on and underflowed to 0 below 1e-162: C·s must
// give s times C's objective, with C's status, at any s a double can hold.
TEST(SdpReview, ResultsScaleWithCAtExtremeMagnitudes) {
  std::mt19937 rng(3);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Eigen::MatrixXd A = fact::test::gaussian_matrix<Eigen::MatrixXd>(6, 6, rng, gauss);
  Eigen::MatrixXd swap(2, 2);
  swap << 0, 1, 1, 0;  // N = 2, d = 1: optimum −2, unique
  for (const Eigen::MatrixXd& C : {Eigen::MatrixXd(swap), Eigen::MatrixXd(A + A.transpose())}) {
    const Result base = fact::sdp::solve(C, 1);
    ASSERT_TRUE(base.certified()) << base.reason;
    for (double s : {1e-200, 1e-170, 1e-150, 1e155, 1e200}) {
      SCOPED_TRACE("n = " + std::to_string(C.rows()) + ", s = " + std::to_string(std::log10(s)));
      const Result r = fact::sdp::solve(s * C, 1);
      EXPECT_EQ(r.status, base.status) << r.reason;
      EXPECT_NEAR(r.objective / s, base.objective, 1e-9 * std::abs(base.objective));
      EXPECT_LT(block_feasibility_error(r), 1e-9);
    }
  }
}

// The symmetry check was absolute for small C (1e-9·max(1, max|C|)): a one-sided entry of
// 5e-10 passed, and the eigensolvers read only the other triangle. It is now relative.
TEST(SdpReview, OneSidedSmallEntryIsRejected) {
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(4, 4);
  C(0, 1) = 5e-10;
  const Result r = fact::sdp::solve(C, 1);
  EXPECT_EQ(r.status, Status::invalid_input);
  EXPECT_NE(r.reason.find("not symmetric"), std::string::npos) << r.reason;
}

// N = 2, d = 2 with a zero off-diagonal block: every feasible X is optimal (any R with ‖R‖ ≤ 1),
// and the closed-form 2 × 2 polar factor, run on rounding for a rank-1 block of the spectral
// start, returned rows far from orthonormal that were certified unique (11 of 400 seeds).
TEST(SdpReview, ZeroOffDiagonalBlockGivesAFeasibleNonUniqueOptimum) {
  for (unsigned seed = 1; seed <= 400; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> gauss(0.0, 1.0);
    Eigen::MatrixXd C = Eigen::MatrixXd::Zero(4, 4);
    for (int b = 0; b < 4; b += 2)
      for (int i = 0; i < 2; ++i)
        for (int j = 0; j <= i; ++j) C(b + i, b + j) = C(b + j, b + i) = gauss(rng);
    for (Method m : {Method::automatic, Method::low_rank}) {
      Options o;
      o.method = m;
      const Result r = fact::sdp::solve(C, 2, o);
      SCOPED_TRACE("seed " + std::to_string(seed) + ", method " + fact::sdp::to_string(m));
      ASSERT_TRUE(r.certified()) << r.reason;
      EXPECT_EQ(r.status, Status::certified_not_unique);
      EXPECT_LT(block_feasibility_error(r), 1e-9);
      EXPECT_NEAR(r.objective, C.trace(), 1e-9 * std::max(1.0, std::abs(C.trace())));
    }
  }
}

// A random symmetric C (d = 1, N = 17, the review's seed) had λ_min(S) = −1.2e-10 and
// λ_2(S) = 1.3e-10 with X of rank 2, and was called unique; a unique optimum has rank d.
TEST(SdpReview, UniqueOnlyAtRankD) {
  for (unsigned seed : {2700u, 800u, 3000u}) {
    for (int d : {1, 2}) {
      std::mt19937 rng(seed);
      std::normal_distribution<double> gauss(0.0, 1.0);
      const int n = 17 * d;  // N = 17, the review's size
      const Eigen::MatrixXd A = fact::test::gaussian_matrix<Eigen::MatrixXd>(n, n, rng, gauss);
      for (Method m : {Method::automatic, Method::interior_point}) {
        Options o;
        o.method = m;
        const Result r = fact::sdp::solve(A + A.transpose(), d, o);
        SCOPED_TRACE("seed " + std::to_string(seed) + ", d = " + std::to_string(d));
        ASSERT_TRUE(r.certified()) << r.reason;
        if (r.status == Status::certified_unique) {
          EXPECT_EQ(r.rank, d) << r.reason;
        }
      }
    }
  }
}

// The dual bound was tr Λ + n·min(0, λ_min(S) + e), e the eigensolver's error bound: that moves
// a slightly negative λ_min up to 0, so C = v vᵀ − t·J (v = e₀ − e₁, J all ones, t = 2⁻⁵¹, λ_min(C)
// = −n t) got bound 0 above the objective ⟨C, J⟩ = −n² t of the feasible X = J. The bound is now the
// issue's tr Λ + n·min(0, λ_min(S)) with the computed λ_min(S) (which can itself lie above the exact
// one by up to the eigensolver's error, here 4 times n t), and bound_error covers that error.
TEST(SdpReview, DualBoundIsNotRaisedByTheEigensolverTolerance) {
  for (int n : {3, 10, 40}) {
    const double t = std::ldexp(1.0, -51);
    Eigen::MatrixXd C = Eigen::MatrixXd::Constant(n, n, -t);
    C(0, 0) += 1;
    C(1, 1) += 1;
    C(0, 1) -= 1;
    C(1, 0) -= 1;
    const double objective_of_J = C.sum();  // −n² t: exact (every partial sum is representable)
    ASSERT_EQ(objective_of_J, -n * n * t);
    for (Method m : {Method::automatic, Method::null_space, Method::interior_point}) {
      Options o;
      o.method = m;
      const Result r = fact::sdp::solve(C, 1, o);
      SCOPED_TRACE("n = " + std::to_string(n) + ", method " + fact::sdp::to_string(m));
      ASSERT_TRUE(std::isfinite(r.dual_bound)) << r.reason;
      // The bound is the formula on the computed λ_min, a negative one included (the old bound
      // was 0 here with min_eig_S < 0), and below ⟨C, J⟩ once bound_error is taken off.
      const double trace_lambda = r.Lambda.sum();  // d = 1: Λ is the diagonal
      const double lowest = r.min_eig_S * r.scale;
      EXPECT_NEAR(r.dual_bound, trace_lambda + n * std::min(0.0, lowest), 1e-12 * std::abs(objective_of_J))
          << "min_eig_S " << r.min_eig_S;
      EXPECT_LE(r.dual_bound - r.bound_error, objective_of_J);
    }
  }
}

// The paper's plain cost for 250 drones with N + 1 rounds has a zero optimum on C's null space
// (n = 500). Its bound n·min(0, λ_min(C)) sits at rounding level, a relative gap of 1.2e-9 against
// the gap's floor, above gap_tol: it was not certified (the interior point ran 827 ms and did not either) once the bound
// stopped forgiving λ_min. The gap is within bound_error, and that certifies, saying so.
TEST(SdpReview, GapWithinTheBoundsRoundingCertifies) {
  fact::SyntheticOptions o;  // as fact-bench-sdp's plain_noisy at N = 250
  o.drones = 250;
  o.rounds = 251;
  o.noise = 0.05;
  o.seed = 2250;
  const Eigen::MatrixXd C = fact::paper_cost(fact::make_synthetic_rounds(o).sums);
  const Result r = fact::sdp::solve(C, 2);
  ASSERT_TRUE(r.certified()) << r.reason;
  EXPECT_LE(r.objective - r.dual_bound, r.bound_error);
  EXPECT_LT(std::abs(r.objective), 1e-9 * r.scale);
  if (r.rel_gap > 1e-9) {
    EXPECT_NE(r.reason.find("within the bound's rounding"), std::string::npos) << r.reason;
  }
}

// Result::stages names the methods a solve ran, in order, each with its own iterations (they add
// up to Result::iterations) and how it ended. Automatic mode: a noise-free tight C certifies in the
// complex staircase alone; a noisy tight one at N = 32 goes on to complex dual scaling and Newton;
// a random full-rank C at N = 25 (50 rows, above the warm start's 48) tries rank-2 Newton, then
// dual scaling from the cold start (not the primal–dual method), and ends certified. An explicit
// method runs alone; invalid input runs nothing.
std::vector<std::string> methods_of(const Result& r) {
  std::vector<std::string> names;
  for (const fact::sdp::Stage& stage : r.stages) names.push_back(stage.method);
  return names;
}

void expect_stages_add_up(const Result& r) {
  int iterations = 0;
  for (const fact::sdp::Stage& stage : r.stages) {
    EXPECT_GE(stage.iterations, 0) << stage.method;
    EXPECT_TRUE(std::isfinite(stage.time_ms) && stage.time_ms >= 0) << stage.method << ": " << stage.time_ms;
    EXPECT_FALSE(stage.outcome.empty()) << stage.method;
    iterations += stage.iterations;
  }
  EXPECT_EQ(iterations, r.iterations);
  if (r.certified()) {  // (an interior point that converged gives the certified X itself)
    EXPECT_TRUE(std::any_of(r.stages.begin(), r.stages.end(),
                            [](const auto& s) { return s.outcome == "certified" || s.outcome == "converged"; }))
        << r.reason;
  }
}

TEST(SdpStages, NameTheMethodsASolveRanInOrder) {
  const Result tight = fact::sdp::solve(fact::sdp::complex_form(fact::test::plain_cost(8, 12, 0.0, 1)), 2);
  ASSERT_TRUE(tight.certified()) << tight.reason;
  ASSERT_EQ(methods_of(tight), std::vector<std::string>{"complex_low_rank"});
  EXPECT_EQ(tight.stages[0].outcome, "certified");
  expect_stages_add_up(tight);

  const Result noisy = fact::sdp::solve(fact::sdp::complex_form(noisy_plain_cost(32, 1)), 2);
  ASSERT_TRUE(noisy.certified()) << noisy.reason;
  const std::vector<std::string> noisy_methods = methods_of(noisy);
  ASSERT_GE(noisy_methods.size(), 3u);
  EXPECT_EQ(noisy_methods[0], "complex_low_rank");
  EXPECT_EQ(noisy.stages[0].outcome, "not certified");
  EXPECT_EQ(noisy_methods[1], "complex_dual_scaling");
  EXPECT_EQ(noisy.stages[1].outcome, "handed off");
  EXPECT_EQ(noisy_methods.back(), "complex_newton");
  expect_stages_add_up(noisy);

  const Eigen::MatrixXd full = random_psd(50, 7);
  const Result cold = fact::sdp::solve(full, 2);
  ASSERT_TRUE(cold.certified()) << cold.reason;
  const std::vector<std::string> cold_methods = methods_of(cold);
  ASSERT_GE(cold_methods.size(), 2u);
  EXPECT_EQ(cold_methods[0], "low_rank");
  EXPECT_EQ(cold_methods[1], "dual_scaling");
  expect_stages_add_up(cold);

  Options interior;
  interior.method = Method::interior_point;
  const Result alone = fact::sdp::solve(full, 2, interior);
  ASSERT_EQ(methods_of(alone), std::vector<std::string>{"interior_point"});
  EXPECT_EQ(alone.stages[0].outcome, "converged");
  expect_stages_add_up(alone);

  const Result invalid = fact::sdp::solve(Eigen::MatrixXd::Identity(3, 3), 2);
  EXPECT_EQ(invalid.status, Status::invalid_input);
  EXPECT_TRUE(invalid.stages.empty());
}

// The plain form with N + 1 rounds (N = 9: C's null space has dimension N − 1 = 8, room for a
// feasible X with N unknowns to spare but generically none of rank 2), so the null space goes
// first. Under noise its Newton step fits at no length (the set is empty): the rank-2 attempt is
// skipped and the primal–dual interior point starts from near_zero_start, to the same optimum as
// the interior point alone (from X = I). Noise-free the zero optimum has no interior and the steps
// run out; rank-2 Newton then still runs. (N = 8 until session 45, when its null space, 4
// unknowns to spare, stopped being tried: ARoomForFewPointsIsNotTried.)
TEST(SdpStages, AnEmptyNullSpaceGoesStraightToTheInteriorPoint) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const Eigen::MatrixXd C = fact::test::plain_cost(9, 10, 0.05, seed);
    const Result r = fact::sdp::solve(C, 2);
    ASSERT_TRUE(r.certified()) << r.reason;
    const std::vector<std::string> methods = methods_of(r);
    ASSERT_GE(methods.size(), 2u) << "seed " << seed;
    EXPECT_EQ(methods[0], "null_space");
    EXPECT_NE(r.stages[0].outcome.find("gave no feasible X"), std::string::npos) << r.stages[0].outcome;
    EXPECT_LT(r.stages[0].iterations, 10) << r.stages[0].outcome;  // a step that fitted at no length
    EXPECT_EQ(methods[1], "interior_point") << "seed " << seed;
    EXPECT_EQ(std::count(methods.begin(), methods.end(), "low_rank"), 0) << "seed " << seed;
    expect_stages_add_up(r);
    Options interior;
    interior.method = Method::interior_point;
    const Result alone = fact::sdp::solve(C, 2, interior);
    ASSERT_TRUE(alone.certified()) << alone.reason;
    EXPECT_NEAR(r.objective, alone.objective, 1e-7 * std::abs(alone.objective)) << "seed " << seed;
  }
  // Above 48 rows the cold start is dual scaling's, as everywhere there (random C of rank 48,
  // n = 64: its null space of dimension 16 has room, and no feasible X).
  for (unsigned seed : {5u, 6u}) {
    const Eigen::MatrixXd G = gaussian(64, 48, seed);  // C's factor, 64 × 48
    const Result r = fact::sdp::solve(G * G.transpose(), 2);
    ASSERT_TRUE(r.certified()) << r.reason;
    const std::vector<std::string> methods = methods_of(r);
    ASSERT_GE(methods.size(), 2u) << "seed " << seed;
    EXPECT_EQ(methods[0], "null_space");
    EXPECT_LT(r.stages[0].iterations, 10) << r.stages[0].outcome;
    EXPECT_EQ(methods[1], "dual_scaling") << "seed " << seed;
  }
  for (std::uint64_t seed : {1, 2}) {
    const Eigen::MatrixXd C = fact::test::plain_cost(9, 10, 0.0, seed);
    const Result r = fact::sdp::solve(C, 2);
    ASSERT_TRUE(r.certified()) << r.reason;
    const std::vector<std::string> methods = methods_of(r);
    ASSERT_GE(methods.size(), 2u) << "seed " << seed;
    EXPECT_EQ(methods[0], "null_space");
    EXPECT_EQ(r.stages[0].iterations, 10) << r.stages[0].outcome;  // null_space.cpp's kMaxSteps
    EXPECT_EQ(methods[1], "low_rank") << "seed " << seed;
    EXPECT_NEAR(r.objective, 0.0, 1e-9 * C.norm());
  }
}

// The hand-off's polish drops X's ghost eigenvalues (detail::polish_rank): on the plain form at
// low noise (N = 8, N + 1 rounds, noise 0.002; seeds of fact-bench-sdp-sweep's instances) X holds,
// at the hand-off, Ritz values of 4e-6 … 8e-5 beside an optimum of rank 4 or 5 (its smallest
// eigenvalues 0.1–0.2); counting them, Newton missed the certificate and the interior point
// resumed. Without them the polish certifies at the optimum's rank, and the result is the
// interior point's alone. (Seeds whose polish fails with the ghosts counted; 7801 and 7804 until
// session 45, when the grid's step lengths moved the hand-off's iterate, and 7795, 7802 and 7803
// until session 50, when the predictor's step lengths did (kAffineStepFraction). Since session 45
// the null space is not tried first at N = 8.)
TEST(SdpStages, TheHandOffPolishDropsGhostEigenvalues) {
  for (std::uint64_t seed : {7800, 7801, 7815}) {
    const Eigen::MatrixXd C = fact::test::plain_cost(8, 9, 0.002, seed);
    const Result r = fact::sdp::solve(C, 2);
    ASSERT_TRUE(r.certified()) << r.reason;
    EXPECT_EQ(methods_of(r), (std::vector<std::string>{"interior_point", "newton_polish"})) << "seed " << seed;
    EXPECT_EQ(r.stages.back().outcome, "certified");
    Options interior;
    interior.method = Method::interior_point;
    const Result alone = fact::sdp::solve(C, 2, interior);
    ASSERT_TRUE(alone.certified()) << alone.reason;
    EXPECT_EQ(r.rank, alone.rank) << "seed " << seed;
    EXPECT_GE(r.rank, 4);
    EXPECT_NEAR(r.objective, alone.objective, 1e-7 * std::abs(alone.objective)) << "seed " << seed;
  }
}

}  // namespace
