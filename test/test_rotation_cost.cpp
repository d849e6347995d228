// Tests of the paper's rotation cost Q = Σ_k s_k s_kᵀ and the synthetic round generator.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "fact/rotation_cost.h"

namespace {

using Rounds = std::vector<std::vector<Eigen::Vector2d>>;

fact::SyntheticRounds rounds(int drones, int k, double noise, std::uint64_t seed) {
  fact::SyntheticOptions o;
  o.drones = drones;
  o.rounds = k;
  o.noise = noise;
  o.seed = seed;
  return fact::make_synthetic_rounds(o);
}

// R = [R_1 … R_N] (2 × 2N), R_j = rot(yaw_j): f_j → world.
Eigen::MatrixXd stacked_rotations(const std::vector<double>& yaw) {
  Eigen::MatrixXd R(2, 2 * yaw.size());
  for (std::size_t j = 0; j < yaw.size(); ++j) R.block<2, 2>(0, 2 * j) = Eigen::Rotation2Dd(yaw[j]).toRotationMatrix();
  return R;
}

// The message of the std::invalid_argument that paper_cost throws, or "" when it throws none.
std::string paper_cost_error(const Rounds& sums) {
  try {
    fact::paper_cost(sums);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(PaperCost, IsSymmetricPsdWithRankAtMostRounds) {
  struct Case {
    int drones, rounds;
    double noise;
  };
  for (const Case c : {Case{4, 2, 0.0}, Case{5, 3, 0.05}, Case{6, 1, 0.05}, Case{3, 10, 0.05}, Case{8, 5, 0.0}}) {
    SCOPED_TRACE("N = " + std::to_string(c.drones) + ", K = " + std::to_string(c.rounds));
    const fact::SyntheticRounds s = rounds(c.drones, c.rounds, c.noise, 17);
    const Eigen::MatrixXd Q = fact::paper_cost(s.sums);
    ASSERT_EQ(Q.rows(), 2 * c.drones);
    ASSERT_EQ(Q.cols(), 2 * c.drones);
    EXPECT_EQ(Q, Q.transpose());

    // Independent construction: Σ_k s_k s_kᵀ.
    Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(2 * c.drones, 2 * c.drones);
    for (const auto& round : s.sums) {
      Eigen::VectorXd sk(2 * c.drones);
      for (int j = 0; j < c.drones; ++j) sk.segment<2>(2 * j) = round[j];
      expected += sk * sk.transpose();
    }
    EXPECT_LE((Q - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff());

    const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Q).eigenvalues();
    const double top = ev(ev.size() - 1);
    ASSERT_GT(top, 0.0);
    EXPECT_GE(ev(0), -1e-12 * top);
    const int rank = static_cast<int>((ev.array() > 1e-10 * top).count());
    EXPECT_LE(rank, c.rounds);
    EXPECT_LE(rank, 2 * c.drones);
    // Noise-free, the two columns of Rᵀ are in the null space (Σ_j R_j s_jk = 0).
    if (c.noise == 0.0) {
      EXPECT_LE(rank, 2 * c.drones - 2);
    }
  }
}

TEST(PaperCost, TruthRotationsHaveZeroCostOnNoiseFreeData) {
  for (int n = 2; n <= 8; ++n) {
    SCOPED_TRACE("N = " + std::to_string(n));
    const fact::SyntheticRounds s = rounds(n, n + 3, 0.0, 40 + n);
    ASSERT_EQ(s.yaw.size(), static_cast<std::size_t>(n));
    const Eigen::MatrixXd Q = fact::paper_cost(s.sums);
    const Eigen::MatrixXd R = stacked_rotations(s.yaw);
    const Eigen::MatrixXd Z = R.transpose() * R;
    EXPECT_NEAR((Q * Z).trace(), 0.0, 1e-12 * Q.trace() * n);
    // The underlying identity: Σ_j R_j s_jk = 0 for every round.
    for (std::size_t k = 0; k < s.sums.size(); ++k) {
      Eigen::Vector2d total = Eigen::Vector2d::Zero();
      double scale = 0;
      for (int j = 0; j < n; ++j) {
        total += Eigen::Rotation2Dd(s.yaw[j]).toRotationMatrix() * s.sums[k][j];
        scale += s.sums[k][j].norm();
      }
      EXPECT_LE(total.norm(), 1e-12 * scale) << "round " << k;
    }
  }
}

TEST(PaperCost, NoisyDataOrWrongRotationsHavePositiveCost) {
  const fact::SyntheticRounds noisy = rounds(5, 6, 0.05, 3);
  const Eigen::MatrixXd Qn = fact::paper_cost(noisy.sums);
  const Eigen::MatrixXd Rn = stacked_rotations(noisy.yaw);
  EXPECT_GT((Qn * Rn.transpose() * Rn).trace(), 1e-6 * Qn.trace());

  const fact::SyntheticRounds clean = rounds(5, 6, 0.0, 3);
  std::vector<double> wrong = clean.yaw;
  wrong[2] += 0.3;
  const Eigen::MatrixXd Q = fact::paper_cost(clean.sums);
  const Eigen::MatrixXd R = stacked_rotations(wrong);
  EXPECT_GT((Q * R.transpose() * R).trace(), 1e-3 * Q.trace());
  // A global rotation of every frame leaves the cost at zero (the gauge freedom).
  std::vector<double> turned = clean.yaw;
  for (double& y : turned) y += 1.1;
  const Eigen::MatrixXd Rt = stacked_rotations(turned);
  EXPECT_NEAR((Q * Rt.transpose() * Rt).trace(), 0.0, 1e-11 * Q.trace());
}

TEST(PaperCost, NoRoundsThrows) {
  const std::string why = paper_cost_error({});
  EXPECT_NE(why.find("no rounds"), std::string::npos) << "'" << why << "'";
}

TEST(PaperCost, RoundWithDifferentDroneCountThrowsNamingTheRound) {
  Rounds sums = rounds(4, 4, 0.0, 1).sums;
  sums[2].pop_back();
  const std::string why = paper_cost_error(sums);
  EXPECT_NE(why.find("rounds[2]"), std::string::npos) << "'" << why << "'";
  EXPECT_NE(why.find("3 drones"), std::string::npos) << "'" << why << "'";
  EXPECT_NE(why.find("expected 4"), std::string::npos) << "'" << why << "'";

  sums = rounds(4, 4, 0.0, 1).sums;
  sums[1].push_back(Eigen::Vector2d(1.0, 2.0));
  const std::string why_more = paper_cost_error(sums);
  EXPECT_NE(why_more.find("rounds[1]"), std::string::npos) << "'" << why_more << "'";
}

TEST(PaperCost, FewerThanTwoDronesThrowsNamingTheRound) {
  const std::string one = paper_cost_error({{Eigen::Vector2d(1.0, 0.0)}, {Eigen::Vector2d(0.0, 1.0)}});
  EXPECT_NE(one.find("rounds[0]"), std::string::npos) << "'" << one << "'";
  EXPECT_NE(one.find("1 drones"), std::string::npos) << "'" << one << "'";
  const std::string none = paper_cost_error({{}});
  EXPECT_NE(none.find("rounds[0]"), std::string::npos) << "'" << none << "'";
  EXPECT_NE(none.find("0 drones"), std::string::npos) << "'" << none << "'";
}

TEST(SyntheticRounds, ShapeAndYawRange) {
  const fact::SyntheticRounds s = rounds(6, 9, 0.05, 2);
  ASSERT_EQ(s.yaw.size(), 6u);
  ASSERT_EQ(s.sums.size(), 9u);
  for (const auto& round : s.sums) EXPECT_EQ(round.size(), 6u);
  for (double y : s.yaw) {
    EXPECT_GE(y, -M_PI);
    EXPECT_LE(y, M_PI);
  }
}

TEST(SyntheticRounds, DeterministicBySeedAndDifferentAcrossSeeds) {
  for (double noise : {0.0, 0.05}) {
    SCOPED_TRACE("noise " + std::to_string(noise));
    const fact::SyntheticRounds a = rounds(5, 4, noise, 7);
    const fact::SyntheticRounds b = rounds(5, 4, noise, 7);
    const fact::SyntheticRounds c = rounds(5, 4, noise, 8);
    EXPECT_EQ(a.yaw, b.yaw);
    ASSERT_EQ(a.sums.size(), b.sums.size());
    for (std::size_t k = 0; k < a.sums.size(); ++k)
      for (std::size_t j = 0; j < a.sums[k].size(); ++j) EXPECT_EQ(a.sums[k][j], b.sums[k][j]) << k << "," << j;
    EXPECT_NE(a.yaw, c.yaw);
    EXPECT_NE(fact::paper_cost(a.sums), fact::paper_cost(c.sums));
  }
}

TEST(SyntheticRounds, NoiseChangesTheSumsButNotTheYaws) {
  const fact::SyntheticRounds clean = rounds(5, 4, 0.0, 11);
  const fact::SyntheticRounds noisy = rounds(5, 4, 0.05, 11);
  EXPECT_EQ(clean.yaw, noisy.yaw);
  EXPECT_NE(fact::paper_cost(clean.sums), fact::paper_cost(noisy.sums));
}

}  // namespace
