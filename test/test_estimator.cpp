// The estimator on generated scenarios: exact recovery, noise bounds, ambiguity, bad input.
#include "fact/estimator.h"
#include "fact/json_io.h"
#include "fact/simgen.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

namespace fact {
namespace {

struct Errors {
  double yaw = 0;       // largest |yaw error| over resolved drones (rad)
  double position = 0;  // largest position error over resolved drones (m)
  int resolved = 0;
};

// Against the frames the odometry was in during `round` (−1: the frames without drift).
Errors errors_against_truth(const Estimate& e, const Truth& truth, int round = -1) {
  Errors out;
  const std::vector<TruePose> truth_poses =
      round < 0 ? true_poses(truth, e.reference) : true_poses_in_round(truth, e.reference, round);
  for (const DronePose& d : e.drones) {
    if (!d.resolved) continue;
    ++out.resolved;
    for (const TruePose& t : truth_poses) {
      if (t.id != d.id) continue;
      out.yaw = std::max(out.yaw, std::abs(std::remainder(d.yaw - t.yaw, 2 * M_PI)));
      out.position = std::max(out.position, (d.position - t.position).norm());
    }
  }
  return out;
}

// A swarm in a room that grows with it (side max(4, 2.5·sqrt(N)) m), noise-free unless changed.
SimOptions swarm(int drones, int rounds, std::uint64_t seed) {
  SimOptions o;
  o.drones = drones;
  o.rounds = rounds;
  o.seed = seed;
  o.room = std::max(4.0, 2.5 * std::sqrt(static_cast<double>(drones)));
  return o;
}

// The swarm as a depth camera sees it in a cluttered room: depth noise, 6 m range, obstacles,
// false positives and misses (per drone per round); no VIO drift unless with_drift adds it.
SimOptions field_swarm(int drones, int rounds, std::uint64_t seed, int obstacles, double false_positives,
                       double miss_rate) {
  SimOptions o = swarm(drones, rounds, seed);
  o.noise = NoiseKind::depth;
  o.range_limit = 6;
  o.obstacles = obstacles;
  o.false_positives = false_positives;
  o.miss_rate = miss_rate;
  return o;
}

// VIO drift at the default noise model's random walk per round.
SimOptions with_drift(SimOptions o) {
  o.drift_yaw = 0.006;
  o.drift_position = 0.03;
  return o;
}

// The sensor model a user states for exact data: millimetre-level noise and no odometry error.
NoiseModel exact_sensor() {
  NoiseModel n;
  n.floor = 0.002;
  n.quadratic = 0;
  n.bearing = 0.0005;
  n.odometry = 0.001;
  n.odometry_yaw = 0.0005;
  n.odometry_walk = 0;
  n.odometry_yaw_walk = 0;
  return n;
}

Estimate run(const Scenario& s, Mode mode, int max_rounds = 0, const NoiseModel& noise = exact_sensor()) {
  EstimateOptions o;
  o.mode = mode;
  o.max_rounds = max_rounds;
  o.noise = noise;
  return estimate_poses(s.rounds, o);
}

void expect_exact(const Estimate& e, const Scenario& s, int drones) {
  ASSERT_EQ(e.status, EstimateStatus::certified) << e.reason;
  const Errors err = errors_against_truth(e, s.truth);
  EXPECT_EQ(err.resolved, drones);
  EXPECT_LT(err.yaw, 1e-6);
  EXPECT_LT(err.position, 1e-6);
}

TEST(Estimator, PaperModeRecoversNoiseFreeSwarmWithEnoughRounds) {
  const Scenario s = generate_scenario(swarm(4, 6, 3));
  const Estimate e = run(s, Mode::paper);
  EXPECT_EQ(e.mode, Mode::paper);
  expect_exact(e, s, 4);
  EXPECT_EQ(e.rounds_used, 6);
}

TEST(Estimator, ComplexModeRecoversNoiseFreeSwarmInNMinusOneRounds) {
  for (int n : {3, 5, 8}) {
    const Scenario s = generate_scenario(swarm(n, n - 1, 10 + n));
    SCOPED_TRACE("N = " + std::to_string(n));
    const Estimate e = run(s, Mode::complex);
    EXPECT_EQ(e.mode, Mode::complex);
    expect_exact(e, s, n);
    // The certificate carries the SDP's bound_error: finite and positive (it counts rounding, of
    // the order of ε‖C‖), and the objective lies above the bound lowered by it.
    EXPECT_TRUE(std::isfinite(e.certificate.bound_error));
    EXPECT_GT(e.certificate.bound_error, 0.0);
    EXPECT_GE(e.certificate.objective, e.certificate.dual_objective - e.certificate.bound_error);
  }
}

TEST(Estimator, SummedModesAreNotCertifiedWithTooFewRounds) {
  const Scenario s = generate_scenario(swarm(6, 2, 4));
  for (Mode m : {Mode::paper, Mode::complex}) {
    const Estimate e = run(s, m);
    EXPECT_EQ(e.status, EstimateStatus::ambiguous) << to_string(m);
    EXPECT_FALSE(e.unresolved.empty());
  }
}

TEST(Estimator, AssociatedModeRecoversNoiseFreeSwarmFromOneRound) {
  for (int n : {4, 5, 10}) {
    const Scenario s = generate_scenario(swarm(n, 1, 20 + n));
    SCOPED_TRACE("N = " + std::to_string(n));
    expect_exact(run(s, Mode::associated), s, n);
  }
}

// One round of 2 or 3 drones gives each pair only its defining mutual pair and at most one shared
// neighbour: not enough to rule out a coincidence. A second round confirms.
TEST(Estimator, TwoOrThreeDronesNeedTwoRoundsInAssociatedMode) {
  for (int n : {2, 3}) {
    const Scenario s = generate_scenario(swarm(n, 2, 5));
    const Estimate one = run(s, Mode::associated, 1);
    EXPECT_EQ(one.status, EstimateStatus::ambiguous);
    EXPECT_EQ(one.rounds_used, 1);
    EXPECT_NE(one.reason.find("too little evidence"), std::string::npos) << one.reason;
    expect_exact(run(s, Mode::associated, 2), s, n);
  }
}

TEST(Estimator, AutoPrefersAssociated) {
  const Scenario s = generate_scenario(swarm(5, 1, 8));
  const Estimate e = run(s, Mode::automatic);
  EXPECT_EQ(e.mode, Mode::associated);
  expect_exact(e, s, 5);
  EXPECT_EQ(e.timing_us.back().first, "total");
}

TEST(Estimator, AssociatedErrorIsBoundedUnderDepthNoise) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    SimOptions o = swarm(8, 2, seed);
    o.noise = NoiseKind::depth;
    o.range_limit = 6.0;
    const Scenario s = generate_scenario(o);
    const Estimate e = run(s, Mode::automatic, 0, NoiseModel{});
    SCOPED_TRACE("seed " + std::to_string(seed) + ": " + e.reason);
    if (!e.certified()) continue;  // certification rate is a benchmark figure; wrongness is not allowed
    const Errors err = errors_against_truth(e, s.truth);
    EXPECT_LT(err.yaw, 0.03);
    EXPECT_LT(err.position, 0.15);
  }
}

TEST(Estimator, SymmetricFormationAtEqualHeightsIsAmbiguous) {
  for (int n : {3, 4, 6}) {
    SimOptions o = swarm(n, 1, 30 + n);
    o.formation = Formation::polygon;
    o.equal_heights = true;
    o.spacing = 2.5;
    const Scenario s = generate_scenario(o);
    for (Mode m : {Mode::associated, Mode::automatic}) {
      const Estimate e = run(s, m, 0, NoiseModel{});
      SCOPED_TRACE("N = " + std::to_string(n) + " " + to_string(m) + ": " + e.reason);
      EXPECT_EQ(e.status, EstimateStatus::ambiguous);
      EXPECT_FALSE(e.unresolved.empty());
    }
  }
}

// With several rounds and depth noise the summed modes have enough data, and the noise gives the
// summed SDP a unique optimum: it picked one of the triangle's three relabellings by chance and
// modes complex and auto certified it, yaws 2.09 rad and positions 2 m off in 8 of these 24
// scenarios (review, session 34). The association finds every pair ambiguous, so no mode may
// certify.
TEST(Estimator, NoisySymmetricTriangleIsNotCertifiedByAnyMode) {
  for (int rounds : {3, 6})
    for (std::uint64_t seed = 1; seed <= 12; ++seed) {
      SimOptions o;
      o.drones = 3;
      o.rounds = rounds;
      o.formation = Formation::polygon;
      o.equal_heights = true;
      o.move = 0;
      o.noise = NoiseKind::depth;
      o.seed = seed;
      const Scenario s = generate_scenario(o);
      for (Mode m : {Mode::automatic, Mode::complex, Mode::paper, Mode::associated}) {
        EstimateOptions eo;
        eo.mode = m;
        const Estimate e = estimate_poses(s.rounds, eo);
        SCOPED_TRACE("K = " + std::to_string(rounds) + ", seed " + std::to_string(seed) + ", " + to_string(m) + ": " +
                     e.reason);
        EXPECT_FALSE(e.certified());
        const Errors err = errors_against_truth(e, s.truth);
        EXPECT_EQ(err.resolved, 1);  // the reference only
      }
    }
}

// A hovering triangle of unequal heights: the association certifies the truth, but the summed
// cost has a relabelling nearly as good, which complex mode certified 2.1 rad and 2 m off in 9 of
// 200 such scenarios (review, session 34; these seeds are among them). A summed result that
// contradicts the association's certified poses is not certified.
TEST(Estimator, SummedModesDoNotCertifyPosesTheAssociationContradicts) {
  int refused = 0;
  for (int rounds : {5, 8, 12})
    for (std::uint64_t seed : {2, 20, 27, 31, 36}) {
      SimOptions o;
      o.drones = 3;
      o.rounds = rounds;
      o.formation = Formation::polygon;
      o.move = 0;
      o.noise = NoiseKind::depth;
      o.room = 4.330127018922193;
      o.seed = seed;
      const Scenario s = generate_scenario(o);
      for (Mode m : {Mode::complex, Mode::paper}) {
        EstimateOptions eo;
        eo.mode = m;
        const Estimate e = estimate_poses(s.rounds, eo);
        SCOPED_TRACE("K = " + std::to_string(rounds) + ", seed " + std::to_string(seed) + ", " + to_string(m) + ": " +
                     e.reason);
        refused += e.reason.find("contradicts the association") != std::string::npos;
        const Errors err = errors_against_truth(e, s.truth);
        EXPECT_LT(err.yaw, 0.1);
        EXPECT_LT(err.position, 0.3);
      }
    }
  EXPECT_GT(refused, 0);
}

// A detection's age is counted in rounds by index: rounds 0, 1 and 29 of a drifting swarm (a
// rounds file cut or merged by hand) are 29, 28 and 0 rounds old. They were
// weighed as 2, 1 and 0 rounds old, the drift of the missing rounds was not modelled, and wrong
// poses were certified (review, session 34: 154 of 1000 scenarios).
TEST(Estimator, RoundsMissingBetweenIndexesCountTowardTheDrift) {
  int certified = 0;
  bool index_matters = false;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    SimOptions o;
    o.drones = 4;
    o.rounds = 30;
    o.noise = NoiseKind::depth;
    o.drift_yaw = 0.006;
    o.drift_position = 0.017;
    o.seed = seed;
    const Scenario s = generate_scenario(o);
    Rounds gap;
    gap.drones = s.rounds.drones;
    for (int k : {0, 1, 29}) gap.rounds.push_back(s.rounds.rounds[static_cast<size_t>(k)]);
    const Estimate e = estimate_poses(gap, EstimateOptions{});
    SCOPED_TRACE("seed " + std::to_string(seed) + ": " + e.reason);
    Rounds renumbered = gap;
    renumbered.rounds[2].index = 2;
    const Estimate r = estimate_poses(renumbered, EstimateOptions{});
    for (size_t i = 0; i < e.drones.size(); ++i)
      index_matters = index_matters || e.drones[i].resolved != r.drones[i].resolved ||
                      (e.drones[i].resolved && (e.drones[i].position - r.drones[i].position).norm() > 1e-12);
    if (!e.certified()) continue;
    ++certified;
    const Errors err = errors_against_truth(e, s.truth, 29);
    EXPECT_LT(err.yaw, 0.1);
    EXPECT_LT(err.position, 0.3);
  }
  EXPECT_TRUE(index_matters) << "the estimate ignored the rounds' indexes";
  std::printf("certified with rounds 0, 1, 29: %d of 40\n", certified);
}

TEST(Estimator, DroneOutOfRangeOfEveryoneIsNamedUnresolved) {
  SimOptions o = swarm(4, 2, 3);
  o.formation = Formation::given;
  o.positions = {{0, 0, 1.5}, {2, 0.5, 1.2}, {0.5, 2.5, 1.8}, {30, 30, 1.5}};
  o.room = 80;
  o.move = 0;
  o.range_limit = 6;
  const Scenario s = generate_scenario(o);
  const Estimate e = run(s, Mode::associated);
  EXPECT_EQ(e.status, EstimateStatus::ambiguous);
  ASSERT_EQ(e.unresolved.size(), 1u);
  EXPECT_EQ(e.unresolved[0], s.rounds.drones[3]);
  EXPECT_NE(e.reason.find(std::to_string(s.rounds.drones[3])), std::string::npos) << e.reason;
  // The three that see each other are still right.
  const Errors err = errors_against_truth(e, s.truth);
  EXPECT_EQ(err.resolved, 3);
  EXPECT_LT(err.yaw, 1e-6);
}

// The summed modes with a drone that no matched detection connects: the connected drones count as
// resolved only after the residual and precision checks (they were resolved without them, 2–3 m
// and up to 3 rad off on these scenarios), and a resolved drone is right whatever the status.
TEST(Estimator, SummedModesResolveOnlyCheckedDronesWhenOneIsUnconnected) {
  int partial = 0;  // results with some but not every drone unresolved
  for (std::uint64_t seed = 1; seed <= 30; ++seed) {
    SimOptions o;
    o.drones = 4;
    o.noise = NoiseKind::depth;
    o.seed = seed;
    if (seed == 1) {  // a line at equal heights, hovering: drone 1 is hidden behind its neighbours
      o.rounds = 3;
      o.formation = Formation::line;
      o.equal_heights = true;
      o.move = 0;
      o.seed = 2;
    } else {
      o.rounds = 5;
      o.false_positives = 1;
    }
    const Scenario s = generate_scenario(o);
    for (Mode mode : {Mode::complex, Mode::paper}) {
      EstimateOptions eo;
      eo.mode = mode;
      const Estimate e = estimate_poses(s.rounds, eo);
      const Errors err = errors_against_truth(e, s.truth);
      EXPECT_LT(err.yaw, 0.1) << "seed " << o.seed << " " << to_string(mode) << ": " << e.reason;
      EXPECT_LT(err.position, 0.3) << "seed " << o.seed << " " << to_string(mode) << ": " << e.reason;
      if (!e.unresolved.empty() && err.resolved > 1) ++partial;
    }
  }
  std::printf("partially resolved results: %d\n", partial);
}

// paper and complex modes check min_separation as associated mode does: two drones in one place
// contradict the poses.
TEST(Estimator, SummedModesRefuseTwoDronesInOnePlace) {
  SimOptions o;
  o.drones = 4;
  o.rounds = 4;
  o.noise = NoiseKind::depth;
  o.seed = 3;
  const Scenario s = generate_scenario(o);
  int checked = 0;
  for (Mode mode : {Mode::complex, Mode::paper}) {
    EstimateOptions eo;
    eo.mode = mode;
    if (!estimate_poses(s.rounds, eo).certified()) continue;  // paper's plain relaxation is not tight here
    ++checked;
    eo.min_separation = 50;
    const Estimate e = estimate_poses(s.rounds, eo);
    EXPECT_EQ(e.status, EstimateStatus::ambiguous) << to_string(mode);
    EXPECT_NE(e.reason.find("closer than min_separation 50"), std::string::npos) << e.reason;
    EXPECT_EQ(e.unresolved.size(), 3u) << e.reason;
  }
  EXPECT_GE(checked, 1);
}

TEST(Estimator, NeverCertifiesWrongWithFalsePositivesMissesAndObstacles) {
  int certified = 0;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    SimOptions o = field_swarm(6, 4, 100 + seed, 3, 0.3, 0.1);
    o.room = 7;
    const Scenario s = generate_scenario(o);
    const Estimate e = run(s, Mode::automatic, 0, NoiseModel{});
    if (!e.certified()) continue;
    ++certified;
    const Errors err = errors_against_truth(e, s.truth);
    EXPECT_LT(err.yaw, 0.1) << "seed " << seed;
    EXPECT_LT(err.position, 0.3) << "seed " << seed;
  }
  EXPECT_GE(certified, 6);  // most of them certify; the rate itself is a benchmark figure
}

// Heavy clutter: 3 false positives per drone per round, 20 % misses, 3 obstacles, VIO drift, and
// rounds added one at a time until the first certified result, as the planner does. 200
// sessions at N = 2 and 100 at N = 3, 4, 6; none may certify a wrong pose. The pair evidence
// threshold (a log-likelihood ratio of 20) has a margin here: at 10, N = 2 session 2 certifies a
// pose 0.25 rad and 0.74 m off.
TEST(Estimator, HeavyClutterNeverCertifiesWrongAsRoundsAccumulate) {
  int certified = 0, sessions = 0;
  for (int n : {2, 3, 4, 6}) {
    const int count = n == 2 ? 200 : 100;
    for (int session = 0; session < count; ++session, ++sessions) {
      SimOptions o = with_drift(field_swarm(n, n + 3, 777000 + 1000 * n + session, 3, 3.0, 0.2));
      o.room = std::max(6.0, 2.5 * std::sqrt(static_cast<double>(n)));
      const Scenario s = generate_scenario(o);
      for (int k = 1; k <= o.rounds; ++k) {
        const Estimate e = run(s, Mode::automatic, k, NoiseModel{});
        if (!e.certified()) continue;
        ++certified;
        const Errors err = errors_against_truth(e, s.truth, k - 1);
        EXPECT_LT(err.yaw, 0.1) << "N = " << n << ", session " << session << ", " << k << " rounds";
        EXPECT_LT(err.position, 0.3) << "N = " << n << ", session " << session << ", " << k << " rounds";
        break;
      }
    }
  }
  EXPECT_GE(certified, sessions / 2);  // most certify; the rate itself is a benchmark figure
}

// Long sessions with VIO drift (the default model's walk per round): every estimate from the
// first K rounds, K = 1 … 10, that certifies is right about the frames of its latest round,
// and the result tracks them rather than the frames of the first round.
TEST(Estimator, DriftOverLongSessionsNeverCertifiesOldFrames) {
  int certified = 0, late = 0;
  double worst_yaw = 0, worst_position = 0;
  for (std::uint64_t seed = 1; seed <= 16; ++seed) {
    // 30 % misses: sparse sightings, so sessions run long
    const SimOptions o = with_drift(field_swarm(4, 10, 300 + seed, 2, 0.0, 0.3));
    const Scenario s = generate_scenario(o);
    for (int k = 1; k <= o.rounds; ++k) {
      const Estimate e = run(s, Mode::automatic, k, NoiseModel{});
      if (!e.certified()) continue;
      ++certified;
      late += k >= 5;
      const Errors err = errors_against_truth(e, s.truth, k - 1);
      worst_yaw = std::max(worst_yaw, err.yaw);
      worst_position = std::max(worst_position, err.position);
      EXPECT_LT(err.yaw, 0.05) << "seed " << seed << ", " << k << " rounds";
      EXPECT_LT(err.position, 0.2) << "seed " << seed << ", " << k << " rounds";
    }
  }
  EXPECT_GE(late, 10) << "too few long sessions certified to test drift";
  std::printf("drift: %d certified estimates (%d from >= 5 rounds), worst yaw %.4f rad, position %.3f m\n", certified,
              late, worst_yaw, worst_position);
}

// Two rounds that scripts/run-sim.sh --drones 4 --seed 6 gossiped (fact-sim, rendered depth,
// fact-detector; converted from FACT_SWARM_ROUNDS_0 of its run.lcm). Drone 3 is 5.2 m from the
// reference, so each of its pairs has only 4-5 matched points, with scores under the pair
// threshold; drones 1 and 2 saw it, and one pose of it explains both. It joins the cluster
// as a whole. The truth is the simulator's VIO frames averaged over the run's round 2 (its
// report.json); the drift from the round before is under 0.01 rad and 0.03 m.
TEST(Estimator, AFarDroneWeakInEveryPairJoinsTheClusterThatSawIt) {
  std::ifstream in(std::string(FACT_TEST_DATA) + "/rounds/sim_n4_seed6_2rounds.json");
  ASSERT_TRUE(in) << FACT_TEST_DATA "/rounds/sim_n4_seed6_2rounds.json";
  std::stringstream text;
  text << in.rdbuf();
  const Rounds rounds = rounds_from_json(text.str());
  EstimateOptions o;
  o.mode = Mode::associated;
  const Estimate e = estimate_poses(rounds, o);
  ASSERT_EQ(e.status, EstimateStatus::certified) << e.reason;
  ASSERT_EQ(e.drones.size(), 4u);
  struct Frame {
    double yaw;
    Eigen::Vector3d origin;
  };
  const Frame truth[] = {{0.0, {0, 0, 0}},
                         {2.97195, {0.93647, 1.82282, -0.06735}},
                         {1.67002, {-2.15592, 0.93521, -0.03906}},
                         {0.45369, {0.51296, 5.20975, 0.00147}}};
  for (int i = 0; i < 4; ++i) {
    EXPECT_LT(std::abs(std::remainder(e.drones[i].yaw - truth[i].yaw, 2 * M_PI)), 0.05) << "drone " << i;
    EXPECT_LT((e.drones[i].position - truth[i].origin).norm(), 0.2) << "drone " << i;
  }
}

TEST(Estimator, WindowUsesOnlyTheLatestRounds) {
  const Scenario s = generate_scenario(swarm(4, 5, 8));
  EstimateOptions o;
  o.noise = exact_sensor();
  o.window = 2;
  const Estimate e = estimate_poses(s.rounds, o);
  EXPECT_EQ(e.rounds_used, 2);
  expect_exact(e, s, 4);
  o.window = -1;
  EXPECT_EQ(estimate_poses(s.rounds, o).status, EstimateStatus::invalid_input);
}

// --- invalid input -------------------------------------------------------------------------

Rounds small_rounds() { return generate_scenario(swarm(3, 2, 1)).rounds; }

void expect_invalid(const Rounds& r, const EstimateOptions& o, const std::vector<std::string>& words) {
  const Estimate e = estimate_poses(r, o);
  EXPECT_EQ(e.status, EstimateStatus::invalid_input);
  for (const std::string& w : words) EXPECT_NE(e.reason.find(w), std::string::npos) << e.reason << " lacks " << w;
  // No SDP was solved: every certificate number is NaN (null in fact-result-v1), the bound's error too.
  EXPECT_TRUE(std::isnan(e.certificate.objective));
  EXPECT_TRUE(std::isnan(e.certificate.dual_objective));
  EXPECT_TRUE(std::isnan(e.certificate.bound_error));
}

TEST(EstimatorInput, NaNInAVectorNamesRoundDroneAndField) {
  Rounds r = small_rounds();
  const int id = r.drones[1];
  r.rounds[1].drones[id].observations.at(0).vector.y() = std::numeric_limits<double>::quiet_NaN();
  expect_invalid(r, {}, {"round 1", "drone " + std::to_string(id), "observations[0].vector[1]", "nan"});
}

TEST(EstimatorInput, InfiniteOdometryIsNamed) {
  Rounds r = small_rounds();
  const int id = r.drones[0];
  r.rounds[0].drones[id].position.z() = std::numeric_limits<double>::infinity();
  expect_invalid(r, {}, {"round 0", "position[2]", "inf"});
  r = small_rounds();
  r.rounds[0].drones[id].observations.at(0).odom_yaw = std::nan("");
  expect_invalid(r, {}, {"odom_yaw", "nan"});
}

TEST(EstimatorInput, UnknownDroneDuplicateIdsAndTooFewDrones) {
  Rounds r = small_rounds();
  r.rounds[0].drones[77] = DroneRound{};
  expect_invalid(r, {}, {"drone 77", "not in the swarm"});
  r = small_rounds();
  r.drones.push_back(r.drones[0]);
  expect_invalid(r, {}, {"listed twice"});
  r = small_rounds();
  r.drones.resize(1);
  for (Round& round : r.rounds) round.drones.erase(std::next(round.drones.begin()), round.drones.end());
  expect_invalid(r, {}, {"at least 2"});
  r = small_rounds();
  r.rounds.clear();
  expect_invalid(r, {}, {"no rounds"});
}

// More observations than the gossip passes on (kMaxObservations) are refused, naming the round and
// drone: the association pairs every detection of one drone with every one of another's, and 400
// each ran for over 5 minutes (review, session 34).
TEST(EstimatorInput, TooManyObservationsOfOneDroneInOneRound) {
  Rounds r = small_rounds();
  const int id = r.drones[1];
  std::vector<Observation>& obs = r.rounds[1].drones[id].observations;
  const Observation one = obs.at(0);
  obs.assign(kMaxObservations, one);
  EXPECT_TRUE(validate_rounds(r).empty()) << validate_rounds(r);
  obs.push_back(one);
  expect_invalid(r, {}, {"round 1", "drone " + std::to_string(id), "65 observations", "at most 64"});
}

TEST(EstimatorInput, ZeroVectorReferenceRoundsAndNoise) {
  Rounds r = small_rounds();
  r.rounds[0].drones.begin()->second.observations.at(0).vector.setZero();
  expect_invalid(r, {}, {"vector has length 0"});
  EstimateOptions o;
  o.reference = 99;
  expect_invalid(small_rounds(), o, {"reference", "99"});
  o = {};
  o.max_rounds = -2;
  expect_invalid(small_rounds(), o, {"max_rounds", "-2"});
  o = {};
  o.noise.bearing = -1;
  expect_invalid(small_rounds(), o, {"noise.bearing", "-1"});
  o = {};
  o.noise.gate = std::nan("");
  expect_invalid(small_rounds(), o, {"noise.gate", "nan"});
  // A gate whose square overflows (the assignment's no-match cost became +inf and it threw).
  o.noise.gate = 1e300;
  expect_invalid(small_rounds(), o, {"noise.gate", "1e+300"});
  // floor and odometry both tiny: the covariance along a ray would be singular (NaN in the SDP).
  o = {};
  o.noise.floor = 1e-200;
  o.noise.odometry = 0;
  expect_invalid(small_rounds(), o, {"floor 1e-200 m", "odometry 0 m"});
}

TEST(EstimatorInput, ReferenceChoiceMovesTheFrame) {
  const Scenario s = generate_scenario(swarm(4, 1, 9));
  EstimateOptions o;
  o.noise = exact_sensor();
  o.reference = s.rounds.drones[2];
  const Estimate e = estimate_poses(s.rounds, o);
  ASSERT_TRUE(e.certified()) << e.reason;
  EXPECT_EQ(e.reference, s.rounds.drones[2]);
  for (const DronePose& d : e.drones)
    if (d.id == e.reference) {
      EXPECT_NEAR(d.yaw, 0, 1e-12);
      EXPECT_NEAR(d.position.norm(), 0, 1e-12);
    }
  EXPECT_LT(errors_against_truth(e, s.truth).yaw, 1e-6);
}

}  // namespace
}  // namespace fact
