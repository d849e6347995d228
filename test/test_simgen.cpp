// Tests of the scenario generator (fact/simgen.h): determinism, geometry kept in every round,
// visibility (range, occlusion), exact noise-free vectors, noise and rate statistics, drift,
// shuffling, option validation and the true poses. World frame FLU, metres, radians.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "fact/simgen.h"

namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Vector3d rotate_z(double angle, const Eigen::Vector3d& v) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()) * v;
}

// The world position an observation points at, rebuilt from the truth frame of its observer,
// its odometry (pose in f_i) and its body-frame vector.
Eigen::Vector3d seen_world(const fact::Truth& t, std::size_t i, const fact::Observation& o) {
  return t.frame_origin[i] + rotate_z(t.frame_yaw[i], o.odom_position) + rotate_z(t.frame_yaw[i] + o.odom_yaw, o.vector);
}

std::size_t index_of(const fact::Truth& t, int id) {
  return static_cast<std::size_t>(std::find(t.ids.begin(), t.ids.end(), id) - t.ids.begin());
}

// The message of the std::invalid_argument generate_scenario throws, or "" when none.
std::string error_of(const fact::SimOptions& o) {
  try {
    fact::generate_scenario(o);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

bool same_observation(const fact::Observation& a, const fact::Observation& b) {
  return a.odom_position == b.odom_position && a.odom_yaw == b.odom_yaw && a.vector == b.vector;
}

bool same_rounds(const fact::Rounds& a, const fact::Rounds& b) {
  if (a.drones != b.drones || a.rounds.size() != b.rounds.size()) return false;
  for (std::size_t k = 0; k < a.rounds.size(); ++k) {
    const fact::Round& ra = a.rounds[k];
    const fact::Round& rb = b.rounds[k];
    if (ra.index != rb.index || ra.drones.size() != rb.drones.size()) return false;
    for (const auto& [id, da] : ra.drones) {
      const auto it = rb.drones.find(id);
      if (it == rb.drones.end()) return false;
      const fact::DroneRound& db = it->second;
      if (da.position != db.position || da.yaw != db.yaw || da.observations.size() != db.observations.size())
        return false;
      for (std::size_t o = 0; o < da.observations.size(); ++o)
        if (!same_observation(da.observations[o], db.observations[o])) return false;
    }
  }
  return true;
}

int count_targets(const fact::Truth& t, bool false_positives) {
  int n = 0;
  for (const auto& round : t.targets)
    for (const auto& drone : round)
      for (int target : drone) n += (target < 0) == false_positives;
  return n;
}

fact::SimOptions busy_options() {
  fact::SimOptions o;
  o.drones = 6;
  o.rounds = 5;
  o.noise = fact::NoiseKind::depth;
  o.obstacles = 2;
  o.miss_rate = 0.1;
  o.false_positives = 0.5;
  o.drift_yaw = 0.01;
  o.drift_position = 0.02;
  o.range_limit = 7;
  o.seed = 42;
  return o;
}

TEST(Simgen, SameSeedGivesIdenticalScenarioOtherSeedDiffers) {
  const fact::SimOptions o = busy_options();
  const fact::Scenario a = fact::generate_scenario(o);
  const fact::Scenario b = fact::generate_scenario(o);
  EXPECT_TRUE(same_rounds(a.rounds, b.rounds));
  EXPECT_EQ(a.truth.frame_yaw, b.truth.frame_yaw);
  EXPECT_EQ(a.truth.targets, b.truth.targets);
  EXPECT_EQ(a.truth.positions, b.truth.positions);

  fact::SimOptions other = o;
  other.seed = 43;
  const fact::Scenario c = fact::generate_scenario(other);
  EXPECT_FALSE(same_rounds(a.rounds, c.rounds));
  EXPECT_NE(a.truth.frame_yaw, c.truth.frame_yaw);
}

TEST(Simgen, NoiseAndDriftSettingsDoNotChangeTheGeometry) {
  fact::SimOptions o;
  o.drones = 5;
  o.rounds = 4;
  o.seed = 9;
  const fact::Scenario clean = fact::generate_scenario(o);
  o.noise = fact::NoiseKind::paper;
  o.drift_yaw = 0.05;
  o.drift_position = 0.1;
  const fact::Scenario noisy = fact::generate_scenario(o);
  EXPECT_EQ(clean.truth.positions, noisy.truth.positions);
  EXPECT_EQ(clean.truth.frame_yaw, noisy.truth.frame_yaw);
  EXPECT_FALSE(same_rounds(clean.rounds, noisy.rounds));
}

TEST(Simgen, SeparationRoomObstaclesAndMovesKeptInEveryRound) {
  fact::SimOptions o;
  o.drones = 8;
  o.rounds = 30;
  o.room = 8;
  o.min_separation = 1.5;
  o.move = 2.0;
  o.obstacles = 3;
  o.seed = 5;
  const fact::Scenario s = fact::generate_scenario(o);
  const fact::Truth& t = s.truth;
  ASSERT_EQ(t.positions.size(), 30u);
  ASSERT_EQ(t.obstacles.size(), 3u);
  double moved = 0;
  for (std::size_t k = 0; k < t.positions.size(); ++k) {
    const auto& p = t.positions[k];
    ASSERT_EQ(p.size(), 8u);
    for (std::size_t i = 0; i < p.size(); ++i) {
      EXPECT_LE(std::abs(p[i].x()), o.room / 2);
      EXPECT_LE(std::abs(p[i].y()), o.room / 2);
      EXPECT_EQ(p[i].z(), t.positions[0][i].z()) << "heights stay after takeoff";
      for (std::size_t j = 0; j < i; ++j) EXPECT_GE((p[i] - p[j]).norm(), o.min_separation) << "round " << k;
      for (const fact::Obstacle& ob : t.obstacles)
        EXPECT_GE((p[i] - ob.center).head<2>().norm(), ob.radius + o.min_separation / 2);
      if (k == 0) continue;
      const double step = (p[i] - t.positions[k - 1][i]).norm();
      EXPECT_LE(step, o.move + 1e-12);
      moved += step;
    }
  }
  EXPECT_GT(moved, 0.0) << "the drones must move between rounds";
  for (const fact::Obstacle& ob : t.obstacles) {
    EXPECT_EQ(ob.radius, o.obstacle_radius);
    EXPECT_EQ(ob.height, 3.0);
    for (const Eigen::Vector3d& spot : t.frame_origin)
      EXPECT_GE((spot - ob.center).head<2>().norm(), o.min_separation + o.obstacle_radius);
  }
}

TEST(Simgen, TakeoffFramesAreOnTheFloorBelowRoundZero) {
  fact::SimOptions o;
  o.drones = 6;
  o.seed = 3;
  const fact::Scenario s = fact::generate_scenario(o);
  for (std::size_t i = 0; i < s.truth.ids.size(); ++i) {
    const Eigen::Vector3d& p = s.truth.positions[0][i];
    EXPECT_EQ(s.truth.frame_origin[i], Eigen::Vector3d(p.x(), p.y(), 0.0));
    EXPECT_GE(p.z(), o.height_min);
    EXPECT_LE(p.z(), o.height_max);
    EXPECT_GT(s.truth.frame_yaw[i], -kPi);
    EXPECT_LE(s.truth.frame_yaw[i], kPi);
    // Round 0, no drift: the reported position is straight above the frame origin.
    const fact::DroneRound& r = s.rounds.rounds[0].drones.at(s.truth.ids[i]);
    EXPECT_NEAR((r.position - Eigen::Vector3d(0, 0, p.z())).norm(), 0.0, 1e-12);
    EXPECT_EQ(r.yaw, 0.0);
  }
}

TEST(Simgen, NoDetectionBeyondRangeLimit) {
  fact::SimOptions o;
  o.drones = 10;
  o.rounds = 10;
  o.room = 12;
  o.range_limit = 4;
  o.false_positives = 0.5;
  o.seed = 11;
  const fact::Scenario s = fact::generate_scenario(o);
  int expected = 0, beyond = 0;  // pairs within / beyond the limit, over all rounds
  for (std::size_t k = 0; k < s.truth.positions.size(); ++k) {
    const auto& p = s.truth.positions[k];
    for (std::size_t i = 0; i < p.size(); ++i) {
      for (std::size_t j = 0; j < p.size(); ++j)
        if (i != j) ((p[j] - p[i]).norm() <= o.range_limit ? expected : beyond) += 1;
      const auto& observations = s.rounds.rounds[k].drones.at(s.truth.ids[i]).observations;
      for (std::size_t n = 0; n < observations.size(); ++n) {
        EXPECT_LE(observations[n].vector.norm(), o.range_limit + 1e-12);
        const int target = s.truth.targets[k][i][n];
        if (target >= 0) {
          EXPECT_LE((p[index_of(s.truth, target)] - p[i]).norm(), o.range_limit);
        }
      }
    }
  }
  EXPECT_GT(beyond, 0) << "the scenario must have pairs out of range for this test to mean anything";
  EXPECT_EQ(count_targets(s.truth, false), expected);
}

TEST(Simgen, ObstacleBetweenTwoDronesHidesThemFromEachOther) {
  fact::SimOptions o;
  o.drones = 3;
  o.rounds = 2;
  o.move = 0;
  o.ids = {7, 3, 5};
  o.formation = fact::Formation::given;
  o.positions = {{-2, 0, 1.5}, {2, 0, 1.5}, {0, 3, 1.5}};  // ids 7, 3, 5
  fact::Obstacle wall;
  wall.center = {0, 0, 0};
  wall.radius = 0.4;
  wall.height = 3;
  o.given_obstacles = {wall};
  const fact::Scenario s = fact::generate_scenario(o);
  ASSERT_EQ(s.truth.ids, (std::vector<int>{3, 5, 7}));
  EXPECT_EQ(s.truth.positions[0][2], Eigen::Vector3d(-2, 0, 1.5)) << "positions follow their ids";
  for (const auto& round : s.truth.targets) {
    std::map<int, std::vector<int>> seen;
    for (std::size_t i = 0; i < 3; ++i) {
      seen[s.truth.ids[i]] = round[i];
      std::sort(seen[s.truth.ids[i]].begin(), seen[s.truth.ids[i]].end());
    }
    EXPECT_EQ(seen[7], (std::vector<int>{5}));
    EXPECT_EQ(seen[3], (std::vector<int>{5}));
    EXPECT_EQ(seen[5], (std::vector<int>{3, 7}));
  }
  // A drone flying above the obstacle's top sees over it.
  o.positions[0].z() = 3.6;
  o.positions[1].z() = 3.6;
  const fact::Scenario high = fact::generate_scenario(o);
  EXPECT_EQ(count_targets(high.truth, false), 6 * 2);
}

TEST(Simgen, NoiseFreeVectorsRebuildTheTargetExactly) {
  fact::SimOptions o = busy_options();
  o.noise = fact::NoiseKind::none;
  o.drift_yaw = 0;
  o.drift_position = 0;
  o.rounds = 6;
  const fact::Scenario s = fact::generate_scenario(o);
  int checked = 0;
  for (std::size_t k = 0; k < s.truth.positions.size(); ++k)
    for (std::size_t i = 0; i < s.truth.ids.size(); ++i) {
      const auto& observations = s.rounds.rounds[k].drones.at(s.truth.ids[i]).observations;
      ASSERT_EQ(observations.size(), s.truth.targets[k][i].size());
      for (std::size_t n = 0; n < observations.size(); ++n) {
        const fact::Observation& obs = observations[n];
        EXPECT_NEAR((rotate_z(s.truth.frame_yaw[i], obs.odom_position) + s.truth.frame_origin[i] -
                     s.truth.positions[k][i]).norm(), 0.0, 1e-9);
        // The target sits inside the horizontal field of view.
        EXPECT_LE(std::abs(std::atan2(obs.vector.y(), obs.vector.x())), o.fov_horizontal / 2 + 1e-12);
        const int target = s.truth.targets[k][i][n];
        if (target < 0) continue;
        const Eigen::Vector3d error = seen_world(s.truth, i, obs) - s.truth.positions[k][index_of(s.truth, target)];
        EXPECT_LT(error.norm(), 1e-9) << "round " << k << " drone " << s.truth.ids[i] << " observation " << n;
        ++checked;
      }
    }
  EXPECT_GT(checked, 50);
}

TEST(Simgen, FalsePositivesArriveAtTheirRateAndShape) {
  fact::SimOptions o;
  o.drones = 3;
  o.rounds = 400;
  o.false_positives = 0.5;
  o.seed = 21;
  const fact::Scenario s = fact::generate_scenario(o);
  const double rate = count_targets(s.truth, true) / double(o.drones * o.rounds);
  EXPECT_NEAR(rate, 0.5, 0.1);  // σ of the mean ≈ 0.02
  for (std::size_t k = 0; k < s.truth.targets.size(); ++k)
    for (std::size_t i = 0; i < s.truth.ids.size(); ++i) {
      const auto& observations = s.rounds.rounds[k].drones.at(s.truth.ids[i]).observations;
      for (std::size_t n = 0; n < observations.size(); ++n) {
        if (s.truth.targets[k][i][n] >= 0) continue;
        const Eigen::Vector3d& v = observations[n].vector;
        EXPECT_GE(v.norm(), 0.5 - 1e-12);
        EXPECT_LE(v.norm(), 8.0 + 1e-12);
        EXPECT_LE(std::abs(std::asin(v.z() / v.norm())), 29.0 * kPi / 180 + 1e-12);
      }
    }
  o.false_positives = 0;
  EXPECT_EQ(count_targets(fact::generate_scenario(o).truth, true), 0);
}

TEST(Simgen, MissRateRemovesThatShareOfDetections) {
  fact::SimOptions o;
  o.drones = 4;
  o.rounds = 200;
  o.miss_rate = 0.3;
  o.seed = 8;
  const fact::Scenario s = fact::generate_scenario(o);
  const double detected = count_targets(s.truth, false) / double(o.drones * (o.drones - 1) * o.rounds);
  EXPECT_NEAR(detected, 0.7, 0.04);  // σ ≈ 0.009
  o.miss_rate = 1;
  EXPECT_EQ(count_targets(fact::generate_scenario(o).truth, false), 0);
}

TEST(Simgen, PolygonIsRegularAndRotationSymmetric) {
  for (int n : {2, 3, 5, 8}) {
    SCOPED_TRACE("N = " + std::to_string(n));
    fact::SimOptions o;
    o.drones = n;
    o.rounds = 1;
    o.formation = fact::Formation::polygon;
    o.spacing = 2.0;
    o.equal_heights = true;
    const fact::Scenario s = fact::generate_scenario(o);
    const auto& p = s.truth.positions[0];
    const double radius = o.spacing / (2 * std::sin(kPi / n));
    for (int i = 0; i < n; ++i) {
      EXPECT_NEAR(p[i].head<2>().norm(), radius, 1e-12);
      EXPECT_NEAR((p[(i + 1) % n] - p[i]).norm(), o.spacing, 1e-12);
      EXPECT_EQ(p[i].z(), 1.75);
      // Rotating by 2π/N maps the formation onto itself.
      const Eigen::Vector3d turned = rotate_z(2 * kPi / n, p[i]);
      double nearest = 1e9;
      for (int j = 0; j < n; ++j) nearest = std::min(nearest, (turned - p[j]).norm());
      EXPECT_LT(nearest, 1e-12);
    }
  }
}

TEST(Simgen, GridAndLineAreCentredAtTheirSpacing) {
  fact::SimOptions o;
  o.drones = 5;
  o.rounds = 1;
  o.formation = fact::Formation::grid;
  o.spacing = 1.5;
  const auto grid = fact::generate_scenario(o).truth.positions[0];
  // 3 columns, 2 rows: x ∈ {−1.5, 0, 1.5}, y ∈ {−0.75, 0.75}.
  EXPECT_NEAR(grid[0].x(), -1.5, 1e-12);
  EXPECT_NEAR(grid[0].y(), -0.75, 1e-12);
  EXPECT_NEAR(grid[4].x(), 0.0, 1e-12);
  EXPECT_NEAR(grid[4].y(), 0.75, 1e-12);
  o.formation = fact::Formation::line;
  const auto line = fact::generate_scenario(o).truth.positions[0];
  for (int i = 0; i < 5; ++i) {
    EXPECT_NEAR(line[i].x(), (i - 2) * 1.5, 1e-12);
    EXPECT_EQ(line[i].y(), 0.0);
  }
}

TEST(Simgen, ShuffledObservationsKeepTheirTargets) {
  fact::SimOptions o;
  o.drones = 6;
  o.rounds = 20;
  o.seed = 4;
  const fact::Scenario s = fact::generate_scenario(o);
  int unsorted = 0;
  for (std::size_t k = 0; k < s.truth.targets.size(); ++k)
    for (std::size_t i = 0; i < s.truth.ids.size(); ++i) {
      std::vector<int> targets = s.truth.targets[k][i];
      unsorted += !std::is_sorted(targets.begin(), targets.end());
      // Everyone sees everyone else exactly once (no range limit, obstacles, misses).
      std::sort(targets.begin(), targets.end());
      std::vector<int> others;
      for (int id : s.truth.ids)
        if (id != s.truth.ids[i]) others.push_back(id);
      EXPECT_EQ(targets, others);
      // Each observation's range matches the drone its truth names.
      const auto& observations = s.rounds.rounds[k].drones.at(s.truth.ids[i]).observations;
      for (std::size_t n = 0; n < observations.size(); ++n) {
        const std::size_t j = index_of(s.truth, s.truth.targets[k][i][n]);
        EXPECT_NEAR(observations[n].vector.norm(), (s.truth.positions[k][j] - s.truth.positions[k][i]).norm(), 1e-9);
      }
    }
  EXPECT_GT(unsorted, 60) << "observation order must not follow the ids";
}

TEST(Simgen, DriftIsZeroInRoundZeroThenGrowsAndIsSharedWithinARound) {
  fact::SimOptions o;
  o.drones = 4;
  o.rounds = 6;
  o.drift_yaw = 0.05;
  o.drift_position = 0.1;
  o.seed = 13;
  const fact::Scenario s = fact::generate_scenario(o);
  const fact::Truth& t = s.truth;
  double last_round_drift = 0;
  for (std::size_t k = 0; k < t.positions.size(); ++k)
    for (std::size_t i = 0; i < t.ids.size(); ++i) {
      const fact::DroneRound& r = s.rounds.rounds[k].drones.at(t.ids[i]);
      const Eigen::Vector3d truth_odom = rotate_z(-t.frame_yaw[i], t.positions[k][i] - t.frame_origin[i]);
      const double drift = (r.position - truth_odom).norm() + std::abs(r.yaw);
      if (k == 0) {
        EXPECT_NEAR(drift, 0.0, 1e-12);
      }
      if (k + 1 == t.positions.size()) last_round_drift += drift;
      for (std::size_t n = 0; n < r.observations.size(); ++n) {
        const fact::Observation& obs = r.observations[n];
        EXPECT_EQ(obs.odom_position, r.position) << "the drone spins in place";
        // The vector is physical: the heading rebuilt with the drift removed points at the target.
        const double true_heading = t.frame_yaw[i] + obs.odom_yaw - r.yaw;
        const std::size_t j = index_of(t, t.targets[k][i][n]);
        const Eigen::Vector3d world = t.positions[k][i] + rotate_z(true_heading, obs.vector);
        EXPECT_LT((world - t.positions[k][j]).norm(), 1e-9);
      }
    }
  EXPECT_GT(last_round_drift, 0.1);
}

TEST(Simgen, PaperNoiseHasSigmaProportionalToRange) {
  fact::SimOptions o;
  o.drones = 6;
  o.rounds = 100;
  o.noise = fact::NoiseKind::paper;
  o.paper_sigma = 0.05;
  o.seed = 30;
  const fact::Scenario s = fact::generate_scenario(o);
  double sum_sq = 0;  // Σ (error per axis / range)²
  int count = 0;
  for (std::size_t k = 0; k < s.truth.positions.size(); ++k)
    for (std::size_t i = 0; i < s.truth.ids.size(); ++i) {
      const auto& observations = s.rounds.rounds[k].drones.at(s.truth.ids[i]).observations;
      for (std::size_t n = 0; n < observations.size(); ++n) {
        const Eigen::Vector3d truth_world =
            s.truth.positions[k][index_of(s.truth, s.truth.targets[k][i][n])] - s.truth.positions[k][i];
        const Eigen::Vector3d error = seen_world(s.truth, i, observations[n]) - s.truth.positions[k][i] - truth_world;
        sum_sq += (error / truth_world.norm()).squaredNorm();
        count += 3;
      }
    }
  EXPECT_NEAR(std::sqrt(sum_sq / count), 0.05, 0.003);  // 9000 samples: relative σ ≈ 0.7 %
}

TEST(Simgen, DepthNoiseGrowsWithRangeSquared) {
  fact::SimOptions o;
  o.drones = 6;
  o.rounds = 100;
  o.noise = fact::NoiseKind::depth;
  o.depth_c = 0.01;
  o.depth_b = 0.0;
  o.seed = 31;
  const fact::Scenario s = fact::generate_scenario(o);
  double sum_sq = 0;  // Σ (range error / d²)²
  int count = 0;
  for (std::size_t k = 0; k < s.truth.positions.size(); ++k)
    for (std::size_t i = 0; i < s.truth.ids.size(); ++i) {
      const auto& observations = s.rounds.rounds[k].drones.at(s.truth.ids[i]).observations;
      for (std::size_t n = 0; n < observations.size(); ++n) {
        const Eigen::Vector3d truth_world =
            s.truth.positions[k][index_of(s.truth, s.truth.targets[k][i][n])] - s.truth.positions[k][i];
        const double d = truth_world.norm();
        const Eigen::Vector3d v = observations[n].vector;
        sum_sq += std::pow((v.norm() - d) / (d * d), 2);
        ++count;
        // With no bearing noise the direction is exact.
        EXPECT_LT((rotate_z(s.truth.frame_yaw[i] + observations[n].odom_yaw, v).normalized() - truth_world / d).norm(), 1e-9);
      }
    }
  EXPECT_NEAR(std::sqrt(sum_sq / count), 0.01, 0.0007);  // 3000 samples: relative σ ≈ 1.3 %
}

TEST(Simgen, DefaultIdsAndSortedCustomIds) {
  fact::SimOptions o;
  o.drones = 3;
  EXPECT_EQ(fact::generate_scenario(o).rounds.drones, (std::vector<int>{0, 1, 2}));
  o.ids = {12, 4, 9};
  const fact::Scenario s = fact::generate_scenario(o);
  EXPECT_EQ(s.rounds.drones, (std::vector<int>{4, 9, 12}));
  EXPECT_EQ(s.truth.ids, (std::vector<int>{4, 9, 12}));
  for (const fact::Round& r : s.rounds.rounds) {
    ASSERT_EQ(r.drones.size(), 3u);
    EXPECT_EQ(r.drones.begin()->first, 4);
  }
  EXPECT_EQ(fact::validate_rounds(s.rounds), "");
}

TEST(Simgen, InvalidOptionsThrowNamingTheOption) {
  struct Case {
    const char* expect;  // substring of the message
    void (*change)(fact::SimOptions&);
  };
  const Case cases[] = {
      {"drones = 1", [](fact::SimOptions& o) { o.drones = 1; }},
      {"rounds = 0", [](fact::SimOptions& o) { o.rounds = 0; }},
      {"miss_rate = 1.5", [](fact::SimOptions& o) { o.miss_rate = 1.5; }},
      {"miss_rate = -0.1", [](fact::SimOptions& o) { o.miss_rate = -0.1; }},
      {"false_positives = -1", [](fact::SimOptions& o) { o.false_positives = -1; }},
      {"height_min = 3", [](fact::SimOptions& o) { o.height_min = 3; }},
      {"move = nan", [](fact::SimOptions& o) { o.move = std::nan(""); }},
      {"room = inf", [](fact::SimOptions& o) { o.room = INFINITY; }},
      {"drift_yaw = -0.1", [](fact::SimOptions& o) { o.drift_yaw = -0.1; }},
      {"range_limit = -2", [](fact::SimOptions& o) { o.range_limit = -2; }},
      {"fov_horizontal = 7", [](fact::SimOptions& o) { o.fov_horizontal = 7; }},
      {"obstacles = -1", [](fact::SimOptions& o) { o.obstacles = -1; }},
      {"ids = 2 ids", [](fact::SimOptions& o) { o.ids = {1, 2}; }},
      {"ids[2] = 1: duplicate", [](fact::SimOptions& o) { o.ids = {1, 2, 1, 3}; }},
      {"ids[0] = -4", [](fact::SimOptions& o) { o.ids = {-4, 2, 1, 3}; }},
      {"positions = 2 positions",
       [](fact::SimOptions& o) {
         o.formation = fact::Formation::given;
         o.positions = {{0, 0, 1}, {2, 0, 1}};
       }},
      {"positions[1] = (0.5, 0, 1)",
       [](fact::SimOptions& o) {
         o.drones = 2;
         o.formation = fact::Formation::given;
         o.positions = {{0, 0, 1}, {0.5, 0, 1}};
       }},
      {"positions = 1 positions: only used with formation given",
       [](fact::SimOptions& o) { o.positions = {{0, 0, 1}}; }},
      {"room = 10: formation line",
       [](fact::SimOptions& o) {
         o.formation = fact::Formation::line;
         o.drones = 7;
       }},
      {"spacing = 0.5: below min_separation",
       [](fact::SimOptions& o) {
         o.formation = fact::Formation::grid;
         o.spacing = 0.5;
       }},
      {"min_separation = 3: cannot place 40 drones",
       [](fact::SimOptions& o) {
         o.drones = 40;
         o.min_separation = 3;
       }},
      {"obstacles = 2: obstacle 0 found no spot",  // takeoff spots' clearances (4.9 m) cover the room
       [](fact::SimOptions& o) {
         o.obstacles = 2;
         o.formation = fact::Formation::grid;
         o.drones = 9;
         o.spacing = 4.5;
         o.min_separation = 4.5;
       }},
      {"given_obstacles[0].radius = 0", [](fact::SimOptions& o) { o.given_obstacles = {fact::Obstacle{{0, 0, 0}, 0.0, 3.0}}; }},
      {"given_obstacles[0] = (0, 0, 0): within",
       [](fact::SimOptions& o) {
         o.drones = 2;
         o.formation = fact::Formation::given;
         o.positions = {{0.3, 0, 1}, {3, 0, 1}};
         o.given_obstacles = {fact::Obstacle{{0, 0, 0}, 0.4, 3.0}};
       }},
  };
  for (const Case& c : cases) {
    fact::SimOptions o;
    c.change(o);
    const std::string message = error_of(o);
    EXPECT_NE(message.find(c.expect), std::string::npos) << "expected \"" << c.expect << "\" in \"" << message << "\"";
  }
  EXPECT_EQ(error_of(fact::SimOptions{}), "");
}

TEST(Simgen, TruePosesOfAHandMadeTruth) {
  fact::Truth t;
  t.ids = {2, 5, 9};
  t.frame_yaw = {kPi / 2, kPi, -kPi / 2};
  t.frame_origin = {{1, 1, 0}, {1, 3, 0}, {-2, 1, 0}};
  const std::vector<fact::TruePose> p = fact::true_poses(t, 2);
  ASSERT_EQ(p.size(), 3u);
  EXPECT_EQ(p[0].id, 2);
  EXPECT_NEAR(p[0].yaw, 0.0, 1e-15);
  EXPECT_NEAR(p[0].position.norm(), 0.0, 1e-15);
  // Drone 5: 2 m along world y from drone 2, whose frame's x axis points along world y.
  EXPECT_EQ(p[1].id, 5);
  EXPECT_NEAR(p[1].yaw, kPi / 2, 1e-15);
  EXPECT_NEAR((p[1].position - Eigen::Vector3d(2, 0, 0)).norm(), 0.0, 1e-15);
  // Drone 9: 3 m along world −x, which is +y of drone 2's frame; yaw −π wraps to +π.
  EXPECT_NEAR(p[2].yaw, kPi, 1e-15);
  EXPECT_NEAR((p[2].position - Eigen::Vector3d(0, 3, 0)).norm(), 0.0, 1e-15);
  // Seen from drone 9, whose frame's x axis points along world −y (so its y along world +x):
  // drone 2 is 3 m along world +x, i.e. +y of f_9.
  const std::vector<fact::TruePose> q = fact::true_poses(t, 9);
  EXPECT_NEAR(q[0].yaw, kPi, 1e-15);
  EXPECT_NEAR((q[0].position - Eigen::Vector3d(0, 3, 0)).norm(), 0.0, 1e-15);
  EXPECT_THROW(fact::true_poses(t, 4), std::invalid_argument);
}

TEST(Simgen, ParseAndPrintNames) {
  for (fact::Formation f : {fact::Formation::random, fact::Formation::polygon, fact::Formation::grid,
                            fact::Formation::line, fact::Formation::given}) {
    fact::Formation back = fact::Formation::random;
    ASSERT_TRUE(fact::parse_formation(fact::to_string(f), &back));
    EXPECT_EQ(back, f);
  }
  for (fact::NoiseKind k : {fact::NoiseKind::none, fact::NoiseKind::paper, fact::NoiseKind::depth}) {
    fact::NoiseKind back = fact::NoiseKind::none;
    ASSERT_TRUE(fact::parse_noise(fact::to_string(k), &back));
    EXPECT_EQ(back, k);
  }
  fact::Formation f = fact::Formation::grid;
  EXPECT_FALSE(fact::parse_formation("circle", &f));
  EXPECT_EQ(f, fact::Formation::grid);
  fact::NoiseKind k = fact::NoiseKind::depth;
  EXPECT_FALSE(fact::parse_noise("Paper", &k));
  EXPECT_EQ(k, fact::NoiseKind::depth);
}

}  // namespace
