// The planning rules: takeoff height, max move (and the argument: two drones planning blind
// toward each other never come closer than the minimum separation, also over random pairs with
// other drones around), the farthest-drone target, the random direction's probability, the
// deliberate move when ambiguous, the hold when certified; the libccd push-out (a target inside a
// box ends outside its inflation at the nearest point); collision fallbacks (a wall in the way →
// a shorter move; boxed in → hover with the reason); NaN inputs rejected with the field named.
#include "fact/planner.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <utility>

namespace {

using Eigen::Vector3d;

fact::PlannerInput input_at(const Vector3d& p, fact::ResultStatus status = fact::ResultStatus::not_certified,
                            uint64_t seed = 1) {
  fact::PlannerInput in;
  in.position = p;
  in.status = status;
  in.rng.state = seed;
  return in;
}

fact::ObstacleBox box(const Vector3d& lo, const Vector3d& hi) {
  fact::ObstacleBox b;
  b.lo = lo;
  b.hi = hi;
  return b;
}

// The smallest distance between two trajectories flown at the same time.
double min_distance(const fact::Trajectory& a, const fact::Trajectory& b) {
  const double T = std::max(a.duration(), b.duration());
  double m = std::numeric_limits<double>::infinity();
  for (double t = 0; t <= T + 1e-3; t += 2e-3) m = std::min(m, (a.sample(t).position - b.sample(t).position).norm());
  return m;
}

TEST(PlannerRules, TakeoffHeightWithinLimitsAndSeeded) {
  fact::PlannerParams p;
  double lo = 1e9, hi = -1e9;
  for (uint64_t s = 1; s <= 500; ++s) {
    fact::PlannerRng rng{s};
    const double h = fact::takeoff_height(p, &rng);
    EXPECT_GE(h, p.takeoff_min);
    EXPECT_LE(h, p.takeoff_max);
    lo = std::min(lo, h);
    hi = std::max(hi, h);
  }
  EXPECT_LT(lo, p.takeoff_min + 0.05);
  EXPECT_GT(hi, p.takeoff_max - 0.05);
  const fact::Plan a = fact::plan_takeoff(Vector3d(0.3, 0.2, 0), 0.4, p, fact::PlannerRng{42});
  const fact::Plan b = fact::plan_takeoff(Vector3d(0.3, 0.2, 0), 0.4, p, fact::PlannerRng{42});
  ASSERT_EQ(a.kind, fact::PlanKind::move);
  EXPECT_EQ(a.target, b.target);  // same state, same height
  EXPECT_NE(a.rng.state, 42u);    // the state advanced and is handed back
  EXPECT_NEAR((a.trajectory.end_position() - Vector3d(0.3, 0.2, a.target.z())).norm(), 0, 1e-9);
  EXPECT_DOUBLE_EQ(a.trajectory.sample(1.0).yaw, 0.4);
}

TEST(PlannerRules, MaxMoveFormula) {
  fact::PlannerParams p;  // s = 1, margin 0.1, move_max 1.5
  EXPECT_DOUBLE_EQ(fact::max_move_distance(std::numeric_limits<double>::infinity(), p), 1.5);
  EXPECT_DOUBLE_EQ(fact::max_move_distance(10.0, p), 1.5);
  EXPECT_NEAR(fact::max_move_distance(2.0, p), 0.4, 1e-12);
  EXPECT_DOUBLE_EQ(fact::max_move_distance(1.2, p), 0.0);
  EXPECT_DOUBLE_EQ(fact::max_move_distance(0.5, p), 0.0);
}

TEST(PlannerRules, TwoDronesPlanningBlindTowardEachOther) {
  fact::PlannerParams p;
  p.random_move_probability = 0;
  for (double D : {1.3, 2.0, 2.8, 3.5, 5.0}) {
    fact::PlannerInput a = input_at(Vector3d(0, 0, 1.5)), b = input_at(Vector3d(D, 0.1, 1.6));
    a.observed = {b.position};
    b.observed = {a.position};
    const fact::Plan pa = fact::plan_step(a, {}, p), pb = fact::plan_step(b, {}, p);
    if (fact::max_move_distance(D, p) >= p.min_useful_move) {
      ASSERT_EQ(pa.kind, fact::PlanKind::move) << D << " " << pa.reason;
      ASSERT_EQ(pb.kind, fact::PlanKind::move) << D << " " << pb.reason;
      // Each moves toward the other (the only, hence farthest, drone), the full max move.
      EXPECT_GT((pa.target - a.position).x(), 0);
      EXPECT_LT((pb.target - b.position).x(), 0);
      EXPECT_NEAR((pa.target - a.position).norm(), pa.max_move, 1e-9);
    }
    const double m = min_distance(pa.trajectory, pb.trajectory);
    EXPECT_GE(m, p.min_separation) << "D = " << D;
    EXPECT_LE(m, p.min_separation + 2 * p.move_margin + 0.2 + std::max(0.0, D - 3 - 1.0)) << "D = " << D;
  }
}

TEST(PlannerRules, RandomSwarmsPlanningBlindKeepTheSeparation) {
  // Random swarms of 3–8 drones in 6 × 6 m, each seeing every other (d_i ≤ |p_i − p_j|), moving
  // toward the farthest or at random: every pair stays ≥ min_separation at every time.
  fact::PlannerParams p;
  p.random_move_probability = 0.3;
  std::mt19937_64 gen(11);
  std::uniform_real_distribution<double> u(-3, 3), h(1.2, 1.6);
  double worst = 1e9;
  int moves = 0;
  for (int trial = 0; trial < 150; ++trial) {
    const int n = 3 + trial % 6;
    std::vector<Vector3d> pos;
    while (static_cast<int>(pos.size()) < n) {
      const Vector3d q(u(gen), u(gen), h(gen));
      bool ok = true;
      for (const Vector3d& o : pos) ok = ok && (o - q).norm() >= p.min_separation;
      if (ok) pos.push_back(q);
    }
    std::vector<fact::Plan> plans;
    for (int i = 0; i < n; ++i) {
      fact::PlannerInput in = input_at(pos[i], trial % 3 == 0 ? fact::ResultStatus::ambiguous : fact::ResultStatus::not_certified,
                                       1000 * trial + i + 1);
      for (int j = 0; j < n; ++j)
        if (j != i) in.observed.push_back(pos[j]);
      plans.push_back(fact::plan_step(in, {}, p));
      moves += plans.back().kind == fact::PlanKind::move;
    }
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j) worst = std::min(worst, min_distance(plans[i].trajectory, plans[j].trajectory));
  }
  EXPECT_GE(worst, p.min_separation);
  EXPECT_GT(moves, 300);
}

// Synchronised spins: the slot is the rest-to-rest min-jerk time of a move_max flight (peak
// speed 1.875 D/T at v_max = 0.8 m/s: T = 3.516 s) plus move_settle, and no planned move (random
// swarms, with and without obstacles, every status) lasts longer than the slot without the settle.
TEST(PlannerRules, NoMoveOutlastsTheSynchronisedSpinSlot) {
  fact::PlannerParams p;
  const double flight = 1.875 * p.move_max / p.v_max;  // the velocity bound dominates at the defaults
  ASSERT_GT(flight, std::sqrt(5.7735 * p.move_max / p.a_max));
  EXPECT_NEAR(fact::move_slot(p), flight + p.move_settle, 0.05 * flight);
  EXPECT_GE(fact::move_slot(p), flight + p.move_settle - 1e-9);
  EXPECT_NEAR(fact::takeoff_slot(0.0, p), 1.875 * p.takeoff_max / p.v_max + p.move_settle, 0.05 * flight);
  EXPECT_DOUBLE_EQ(fact::takeoff_slot(p.takeoff_max, p), p.move_settle);  // already there: only the settle
  const std::vector<fact::ObstacleBox> pieces = {box(Vector3d(-0.5, 1.0, 0), Vector3d(0.5, 1.4, 3)),
                                                 box(Vector3d(1.2, -2, 0), Vector3d(1.5, 2, 3))};
  std::mt19937_64 gen(5);
  std::uniform_real_distribution<double> u(-3, 3), h(1.2, 1.6);
  const fact::ResultStatus statuses[] = {fact::ResultStatus::ambiguous, fact::ResultStatus::not_certified,
                                         fact::ResultStatus::none};
  double longest = 0;
  int moves = 0;
  for (int trial = 0; trial < 300; ++trial) {
    fact::PlannerInput in = input_at(Vector3d(u(gen), u(gen), h(gen)), statuses[trial % 3], trial + 1);
    for (int k = 0; k < 1 + trial % 4; ++k) in.observed.push_back(Vector3d(u(gen), u(gen), h(gen)));
    const fact::Plan plan = fact::plan_step(in, trial % 2 ? pieces : std::vector<fact::ObstacleBox>{}, p);
    if (plan.kind != fact::PlanKind::move) continue;
    ++moves;
    longest = std::max(longest, plan.trajectory.duration());
  }
  EXPECT_GT(moves, 150);
  EXPECT_LE(longest, fact::move_slot(p) - p.move_settle + 1e-9);
  EXPECT_GT(longest, 0.8 * flight) << "the trials should include full-length moves";
  fact::PlannerParams bad = p;
  bad.move_settle = -0.1;
  EXPECT_NE(fact::planner_params_error(bad).find("move_settle"), std::string::npos);
  bad.move_settle = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(fact::planner_params_error(bad).find("move_settle"), std::string::npos);
  // Values no drone of this swarm flies with (review, session 30: all were accepted and gave
  // infinite or hour-long trajectories).
  const std::pair<double fact::PlannerParams::*, double> absurd[] = {
      {&fact::PlannerParams::v_max, 1e9},         {&fact::PlannerParams::a_max, 1e9},
      {&fact::PlannerParams::spin_rate, 1e-12},   {&fact::PlannerParams::yaw_accel, 1e-12},
      {&fact::PlannerParams::move_max, 1e300},    {&fact::PlannerParams::move_settle, 1e300},
      {&fact::PlannerParams::takeoff_max, 1e9},   {&fact::PlannerParams::z_max, 1e9}};
  for (const auto& [field, value] : absurd) {
    fact::PlannerParams q = p;
    q.*field = value;
    EXPECT_NE(fact::planner_params_error(q), "") << value;
  }
  EXPECT_EQ(fact::planner_params_error(p), "");
}

TEST(PlannerRules, TargetTowardTheFarthestObservedDrone) {
  fact::PlannerParams p;
  p.random_move_probability = 0;
  fact::PlannerInput in = input_at(Vector3d(0, 0, 1.5));
  in.observed = {Vector3d(3, 0, 1.5), Vector3d(-1, 4, 2.5), Vector3d(0, -2.5, 1.0)};
  const fact::Plan plan = fact::plan_step(in, {}, p);
  ASSERT_EQ(plan.kind, fact::PlanKind::move) << plan.reason;
  const double d = std::sqrt(0.25 + 6.25);  // nearest: (0, −2.5, 1.0)
  EXPECT_NEAR(plan.nearest_drone, d, 1e-12);
  EXPECT_NEAR(plan.max_move, fact::max_move_distance(d, p), 1e-12);
  const Vector3d step = plan.target - in.position;
  EXPECT_NEAR(step.z(), 0, 1e-12);  // horizontal
  EXPECT_NEAR(step.norm(), plan.max_move, 1e-9);
  EXPECT_NEAR(std::atan2(step.y(), step.x()), std::atan2(4.0, -1.0), 1e-9);  // (−1, 4) is the farthest
  EXPECT_NE(plan.reason.find("farthest observed"), std::string::npos) << plan.reason;
}

// The farthest drone lies beyond the fence's edge: the move turns away rather than leaving the
// fence (the planner had no x/y limit; fact-fc-bridge then rejected the setpoints and the stream
// stopped: review, session 30).
TEST(PlannerRules, MovesStayInsideTheFence) {
  fact::PlannerParams p;
  p.random_move_probability = 0;
  p.fence = {-2, 2, -2, 2};
  fact::PlannerInput in = input_at(Vector3d(1.5, 0, 1.5));
  in.observed = {Vector3d(6, 0, 1.5), Vector3d(0.5, -0.2, 1.5)};
  const fact::Plan plan = fact::plan_step(in, {}, p);
  ASSERT_EQ(plan.kind, fact::PlanKind::move) << plan.reason;
  EXPECT_LE(plan.target.x(), 2 - p.drone_radius + 1e-9) << plan.reason;
  EXPECT_GE(plan.target.x(), -2 + p.drone_radius - 1e-9);
  EXPECT_LE(std::abs(plan.target.y()), 2 - p.drone_radius + 1e-9);
  p.fence = {-1, 1, 0, 0.3};  // narrower than the drone
  EXPECT_NE(fact::planner_params_error(p).find("fence y [0.000000, 0.300000] m is not wider than 2·drone_radius = 0.420000 m"),
            std::string::npos)
      << fact::planner_params_error(p);
}

TEST(PlannerRules, RandomDirectionWithItsProbability) {
  fact::PlannerParams p;
  p.random_move_probability = 0.1;
  int random = 0;
  const int n = 2000;
  for (int s = 1; s <= n; ++s) {
    fact::PlannerInput in = input_at(Vector3d(0, 0, 1.5), fact::ResultStatus::not_certified, s);
    in.observed = {Vector3d(4, 0, 1.5)};
    const fact::Plan plan = fact::plan_step(in, {}, p);
    ASSERT_EQ(plan.kind, fact::PlanKind::move);
    if (plan.reason.find("random direction") != std::string::npos) {
      ++random;
    } else {
      EXPECT_NEAR(plan.target.y(), 0, 1e-12);
      EXPECT_GT(plan.target.x(), 0);
    }
  }
  EXPECT_NEAR(random / static_cast<double>(n), 0.1, 0.025);
  p.random_move_probability = 1.0;
  fact::PlannerInput in = input_at(Vector3d(0, 0, 1.5), fact::ResultStatus::none, 9);
  in.observed = {Vector3d(4, 0, 1.5)};
  const fact::Plan plan = fact::plan_step(in, {}, p);
  EXPECT_NE(plan.reason.find("random direction"), std::string::npos);
}

// The deliberate move of an ambiguous formation is random, but never away from the drones seen:
// within ±90° of their centroid, both sides drawn; with none seen, every quadrant is drawn.
TEST(PlannerRules, AmbiguousMoveStaysWithin90DegreesOfTheSeenDrones) {
  fact::PlannerParams p;
  const Vector3d start(0, 0, 1.5);
  int left = 0, right = 0;
  for (uint64_t s = 1; s <= 400; ++s) {
    fact::PlannerInput in = input_at(start, fact::ResultStatus::ambiguous, s);
    in.observed = {Vector3d(5, 1, 1.5), Vector3d(5, -1, 1.5)};  // centroid straight ahead (+x)
    const fact::Plan plan = fact::plan_step(in, {}, p);
    ASSERT_EQ(plan.kind, fact::PlanKind::move) << plan.reason;
    const Vector3d step = plan.target - start;
    EXPECT_GE(step.x(), -1e-9) << "seed " << s << ": " << step.transpose();
    (step.y() > 0 ? left : right) += 1;
    EXPECT_NE(plan.reason.find("within 90° of the observed drones"), std::string::npos) << plan.reason;
  }
  EXPECT_GT(left, 120);
  EXPECT_GT(right, 120);
  int quadrants[4] = {0, 0, 0, 0};
  for (uint64_t s = 1; s <= 400; ++s) {
    const fact::Plan plan = fact::plan_step(input_at(start, fact::ResultStatus::ambiguous, s), {}, p);
    const Vector3d step = plan.target - start;
    ++quadrants[(step.x() < 0 ? 1 : 0) + (step.y() < 0 ? 2 : 0)];
  }
  for (int q : quadrants) EXPECT_GT(q, 60);
}

TEST(PlannerRules, AmbiguousMakesADeliberateMoveEvenWithNoDroneObserved) {
  fact::PlannerParams p;
  p.random_move_probability = 0;
  // Nothing observed: the farthest-drone rule gives no move ...
  const fact::Plan none = fact::plan_step(input_at(Vector3d(0, 0, 1.5), fact::ResultStatus::not_certified), {}, p);
  EXPECT_EQ(none.kind, fact::PlanKind::hold);
  EXPECT_NE(none.reason.find("no drone observed"), std::string::npos) << none.reason;
  // ... but an ambiguous formation always moves, the full max move.
  for (uint64_t s = 1; s <= 20; ++s) {
    const fact::Plan amb = fact::plan_step(input_at(Vector3d(0, 0, 1.5), fact::ResultStatus::ambiguous, s), {}, p);
    ASSERT_EQ(amb.kind, fact::PlanKind::move) << amb.reason;
    EXPECT_NEAR((amb.target - Vector3d(0, 0, 1.5)).norm(), p.move_max, 1e-9);
    EXPECT_NE(amb.reason.find("ambiguous"), std::string::npos);
  }
  // Also when the farthest drone is straight above.
  fact::PlannerInput up = input_at(Vector3d(0, 0, 1.0), fact::ResultStatus::ambiguous, 3);
  up.observed = {Vector3d(0, 0, 3.5)};
  EXPECT_EQ(fact::plan_step(up, {}, p).kind, fact::PlanKind::move);
}

TEST(PlannerRules, CertifiedHolds) {
  fact::PlannerParams p;
  fact::PlannerInput in = input_at(Vector3d(1, 1, 1.5), fact::ResultStatus::certified);
  in.observed = {Vector3d(4, 0, 1.5)};
  const fact::Plan plan = fact::plan_step(in, {}, p);
  EXPECT_EQ(plan.kind, fact::PlanKind::hold);
  EXPECT_EQ(plan.target, in.position);
  EXPECT_EQ(plan.trajectory.duration(), 0);
  EXPECT_EQ(plan.trajectory.sample(5).position, in.position);
  EXPECT_NE(plan.reason.find("certified"), std::string::npos);
  // Moving when certified: comes to rest, within the limits, ahead along the velocity.
  in.velocity = Vector3d(0.5, 0, 0);
  const fact::Plan brake = fact::plan_step(in, {}, p);
  EXPECT_EQ(brake.kind, fact::PlanKind::hold);
  EXPECT_GT(brake.target.x(), in.position.x());
  EXPECT_EQ(brake.trajectory.sample(brake.trajectory.duration()).velocity.norm(), 0);
}

// Too close to move toward the nearest drone (1.1 m with 1 m separation: (d − s)/2 − margin < 0):
// the drone moves away from it instead of holding (two such drones used to hold side by side for
// the whole session). Sandwiched between two, it moves across the line joining them. Straight
// below another, it holds.
TEST(PlannerRules, TooCloseMovesAwayFromTheNearestDrone) {
  fact::PlannerParams p;
  fact::PlannerInput in = input_at(Vector3d(0, 0, 1.5), fact::ResultStatus::ambiguous);
  in.known = {Vector3d(1.1, 0, 1.5)};
  const fact::Plan plan = fact::plan_step(in, {}, p);
  ASSERT_EQ(plan.kind, fact::PlanKind::move) << plan.reason;
  EXPECT_NE(plan.reason.find("moving away"), std::string::npos) << plan.reason;
  EXPECT_NEAR(plan.target.x(), -p.move_max, 1e-9);  // straight away, the full move
  EXPECT_NEAR(plan.target.y(), 0, 1e-9);

  in.known = {Vector3d(1.1, 0, 1.5), Vector3d(-1.2, 0, 1.5)};
  const fact::Plan across = fact::plan_step(in, {}, p);
  ASSERT_EQ(across.kind, fact::PlanKind::move) << across.reason;
  EXPECT_NEAR(across.target.x(), 0, 1e-9);  // no component toward either
  EXPECT_NEAR(std::abs(across.target.y()), p.move_max, 1e-9);

  in.known = {Vector3d(1.1, 0, 1.5), Vector3d(-1.2, 0, 1.5), Vector3d(0, 1.15, 1.5), Vector3d(0, -1.3, 1.5)};
  const fact::Plan boxed = fact::plan_step(in, {}, p);  // every direction approaches one of them
  EXPECT_EQ(boxed.kind, fact::PlanKind::hover_fallback) << boxed.reason;
  in.known = {Vector3d(1.1, 0, 1.5), Vector3d(-1.2, 0.5, 1.5), Vector3d(0.3, 2.0, 1.5)};
  const fact::Plan free = fact::plan_step(in, {}, p);
  ASSERT_EQ(free.kind, fact::PlanKind::move) << free.reason;
  for (const Vector3d& q : in.known) {  // its part toward each drone fits that drone's half
    const Vector3d r = q - in.position;
    const double toward = (free.target - in.position).dot(r.normalized());
    EXPECT_LE(toward, std::max(0.0, (r.norm() - p.min_separation) / 2 - p.move_margin) + 1e-9);
  }

  in.known = {Vector3d(0, 0, 2.4)};
  const fact::Plan below = fact::plan_step(in, {}, p);
  EXPECT_EQ(below.kind, fact::PlanKind::hold);
  EXPECT_NE(below.reason.find("max move"), std::string::npos) << below.reason;
}

TEST(PlannerSafety, PenetrationMatchesTheGeometry) {
  fact::PlannerParams p;
  const double infl = fact::obstacle_inflation(p);
  const fact::ObstacleBox b = box(Vector3d(1, -1, 0), Vector3d(2, 1, 3));
  double depth;
  Vector3d dir;
  // Inside the box near the x = 1 face: out through that face.
  ASSERT_TRUE(fact::penetration(b, infl, Vector3d(1.1, 0.2, 1.5), &depth, &dir));
  EXPECT_NEAR(depth, 0.1 + infl, 1e-3);
  EXPECT_NEAR((dir - Vector3d(-1, 0, 0)).norm(), 0, 1e-3);
  // In the rounded corner region: along the diagonal from the box's corner edge.
  const Vector3d q(0.9, -1.1, 1.5);
  ASSERT_TRUE(fact::penetration(b, infl, q, &depth, &dir));
  EXPECT_NEAR(depth, infl - std::sqrt(0.02), 2e-3);
  // EPA on the rounded edge: the depth is exact to 1 mm, the direction to a few degrees.
  EXPECT_NEAR((dir - Vector3d(-1, -1, 0).normalized()).norm(), 0, 0.1);
  // Outside the inflation: no penetration.
  EXPECT_FALSE(fact::penetration(b, infl, Vector3d(0.5, 0, 1.5), &depth, &dir));
}

TEST(PlannerSafety, PushOutToTheNearestFreePoint) {
  fact::PlannerParams p;
  const double infl = fact::obstacle_inflation(p);
  const std::vector<fact::ObstacleBox> pieces = {box(Vector3d(1, -1, 0), Vector3d(2, 1, 3))};
  Vector3d out;
  int pushes = 0;
  ASSERT_TRUE(fact::push_out(Vector3d(1.1, 0.2, 1.5), pieces, p, &out, &pushes));
  EXPECT_GE(pushes, 1);
  EXPECT_GE(fact::box_distance(pieces[0], out), infl);
  // The nearest free point: straight out through the nearest face, just beyond the inflation.
  EXPECT_NEAR((out - Vector3d(1 - infl - p.push_epsilon, 0.2, 1.5)).norm(), 0, 2e-3);
  // A free target stays.
  ASSERT_TRUE(fact::push_out(Vector3d(0, 0, 1.5), pieces, p, &out));
  EXPECT_EQ(out, Vector3d(0, 0, 1.5));
  // Between two pieces with room between their inflations: out of one, then free.
  const std::vector<fact::ObstacleBox> wide = {box(Vector3d(1, -1, 0), Vector3d(2, 1, 3)),
                                               box(Vector3d(-0.2, -1, 0), Vector3d(0.2, 1, 3))};
  ASSERT_TRUE(fact::push_out(Vector3d(0.8, 0.0, 1.5), wide, p, &out));
  EXPECT_NEAR((out - Vector3d(1 - infl - p.push_epsilon, 0, 1.5)).norm(), 0, 2e-3);
  // A gap narrower than two inflations: the pushes alternate, the two pieces are merged into
  // their bounding box and the point leaves it through its nearest face (x = −0.2).
  const std::vector<fact::ObstacleBox> narrow = {box(Vector3d(1, -1, 0), Vector3d(2, 1, 3)),
                                                 box(Vector3d(-0.2, -1, 0), Vector3d(0.3, 1, 3))};
  ASSERT_TRUE(fact::push_out(Vector3d(0.8, 0.0, 1.5), narrow, p, &out, &pushes));
  for (const auto& b : narrow) EXPECT_GE(fact::box_distance(b, out), infl);
  EXPECT_NEAR(out.x(), -0.2 - infl - p.push_epsilon, 2e-3);
  EXPECT_GE(pushes, 3);
  // Randomly placed targets inside random boxes: all end free, at about the nearest free point.
  std::mt19937_64 gen(5);
  std::uniform_real_distribution<double> u(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const Vector3d lo(u(gen) * 2, u(gen) * 2, u(gen) * 2);
    const fact::ObstacleBox b = box(lo, lo + Vector3d(0.2 + u(gen), 0.2 + u(gen), 0.2 + u(gen)));
    const Vector3d q = b.lo + (b.hi - b.lo).cwiseProduct(Vector3d(u(gen), u(gen), u(gen)));
    ASSERT_TRUE(fact::push_out(q, {b}, p, &out)) << trial;
    EXPECT_GE(fact::box_distance(b, out), infl);
    // Nearest exit of a point inside an axis-aligned box: through the nearest face.
    const Vector3d dlo = q - b.lo, dhi = b.hi - q;
    const double nearest = std::min(dlo.minCoeff(), dhi.minCoeff()) + infl;
    EXPECT_NEAR((out - q).norm(), nearest + p.push_epsilon, 3e-3) << trial;
  }
}

TEST(PlannerSafety, WallInTheWayGivesAShorterMove) {
  fact::PlannerParams p;
  p.random_move_probability = 0;
  // A wall across +x from x = 1.0 to 1.2; the farthest drone is behind it.
  const std::vector<fact::ObstacleBox> wall = {box(Vector3d(1.0, -3, 0.3), Vector3d(1.2, 3, 3))};
  fact::PlannerInput in = input_at(Vector3d(0, 0, 1.5));
  in.observed = {Vector3d(5, 0, 1.5)};
  const fact::Plan plan = fact::plan_step(in, wall, p);
  ASSERT_EQ(plan.kind, fact::PlanKind::move) << plan.reason;
  EXPECT_NE(plan.reason.find("alternative"), std::string::npos) << plan.reason;
  EXPECT_LT(plan.target.x(), 1.0 - fact::obstacle_inflation(p));
  EXPECT_GT(plan.target.x(), p.min_useful_move);
  EXPECT_NEAR(plan.target.y(), 0, 1e-3);  // same direction, shorter (EPA's tolerance)
  EXPECT_EQ(fact::check_trajectory(plan.trajectory, wall, in.observed, in.position, plan.max_move, p), "");
  // The straight full move would have crossed the wall.
  fact::Trajectory straight;
  ASSERT_EQ(fact::min_jerk_within_limits(fact::TrajectoryStart{in.position, Vector3d::Zero(), Vector3d::Zero(), 0}, in.position + Vector3d(1.5, 0, 0), {}, &straight), "");
  EXPECT_NE(fact::check_trajectory(straight, wall, {}, in.position, 1e9, p).find("obstacle piece 0"), std::string::npos);
}

TEST(PlannerSafety, BoxedInHoversWithAReason) {
  fact::PlannerParams p;
  // Walls on every side 0.4 m away: the free cell (|x|, |y| ≤ 0.04 m) has no useful move.
  const std::vector<fact::ObstacleBox> cell = {
      box(Vector3d(0.4, -2, 0), Vector3d(0.6, 2, 3)), box(Vector3d(-0.6, -2, 0), Vector3d(-0.4, 2, 3)),
      box(Vector3d(-2, 0.4, 0), Vector3d(2, 0.6, 3)), box(Vector3d(-2, -0.6, 0), Vector3d(2, -0.4, 3))};
  const fact::Plan plan = fact::plan_step(input_at(Vector3d(0, 0, 1.5), fact::ResultStatus::ambiguous, 4), cell, p);
  EXPECT_EQ(plan.kind, fact::PlanKind::hover_fallback);
  EXPECT_NE(plan.reason.find("no safe move"), std::string::npos) << plan.reason;
  EXPECT_EQ(plan.trajectory.sample(3).position, Vector3d(0, 0, 1.5));
}

TEST(PlannerSafety, NearDroneBlocksThePath) {
  fact::PlannerParams p;
  p.random_move_probability = 0;
  fact::Trajectory tr;
  ASSERT_EQ(fact::min_jerk_within_limits(fact::TrajectoryStart{Vector3d(0, 0, 1.5), Vector3d::Zero(), Vector3d::Zero(), 0}, Vector3d(1.5, 0, 1.5), {}, &tr), "");
  const std::string why = fact::check_trajectory(tr, {}, {Vector3d(2.2, 0, 1.5)}, Vector3d(0, 0, 1.5), 1e9, p);
  EXPECT_NE(why.find("from drone 0 (min_separation 1.00 m)"), std::string::npos) << why;
  EXPECT_NE(fact::check_trajectory(tr, {}, {}, Vector3d(0, 0, 1.5), 1.0, p).find("max-move ball"), std::string::npos);
}

TEST(PlannerInputCheck, NaNRejectedWithTheFieldNamed) {
  fact::PlannerParams p;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto check = [&](const fact::PlannerInput& in, const std::string& field) {
    const fact::Plan plan = fact::plan_step(in, {}, p);
    EXPECT_EQ(plan.kind, fact::PlanKind::rejected);
    EXPECT_NE(plan.reason.find(field), std::string::npos) << plan.reason;
    EXPECT_TRUE(plan.trajectory.sample(0).position.allFinite());
  };
  fact::PlannerInput in = input_at(Vector3d(0, 0, 1.5));
  in.position.x() = nan;
  check(in, "position is not finite");
  in = input_at(Vector3d(0, 0, 1.5));
  in.velocity.z() = nan;
  check(in, "velocity is not finite");
  in = input_at(Vector3d(0, 0, 1.5));
  in.yaw = nan;
  check(in, "yaw is not finite");
  in = input_at(Vector3d(0, 0, 1.5));
  in.observed = {Vector3d(3, 0, 1), Vector3d(nan, 0, 1)};
  check(in, "observed[1] is not finite");
  in = input_at(Vector3d(0, 0, 1.5));
  in.known = {Vector3d(0, std::numeric_limits<double>::infinity(), 1)};
  check(in, "known[0] is not finite");
  in = input_at(Vector3d(0, 0, 1.5));
  in.observed = {Vector3d(3, 0, 1.5)};
  const fact::Plan bad_piece = fact::plan_step(in, {box(Vector3d(nan, 0, 0), Vector3d(1, 1, 1))}, p);
  EXPECT_EQ(bad_piece.kind, fact::PlanKind::rejected);
  EXPECT_EQ(bad_piece.reason, "pieces[0] is not finite");
  fact::PlannerParams bad = p;
  bad.v_max = nan;
  EXPECT_EQ(fact::plan_step(input_at(Vector3d(0, 0, 1.5)), {}, bad).kind, fact::PlanKind::rejected);
  EXPECT_EQ(fact::plan_takeoff(Vector3d(nan, 0, 0), 0, p, {}).kind, fact::PlanKind::rejected);
  EXPECT_EQ(fact::plan_spin(Vector3d(0, 0, 1), nan, p).kind, fact::PlanKind::rejected);
}

TEST(PlannerRules, ObservedPositionRotatesByYaw) {
  const Vector3d q = fact::observed_position(Vector3d(1, 2, 1.5), M_PI / 2, Vector3d(2, 0, 0.3));
  EXPECT_NEAR((q - Vector3d(1, 4, 1.8)).norm(), 0, 1e-12);
}

}  // namespace
