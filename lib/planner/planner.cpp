// The planning rules and the planner step (fact/planner.h).
#include "fact/planner.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace fact {

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string num(double v, const char* f = "%.2f") {
  char buf[48];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

TrajectoryLimits limits_of(const PlannerParams& p) {
  TrajectoryLimits l;
  l.v_max = p.v_max;
  l.a_max = p.a_max;
  return l;
}

TrajectoryStart start_of(const PlannerInput& in) {
  TrajectoryStart s;
  s.position = in.position;
  s.velocity = in.velocity;
  s.acceleration = in.acceleration;
  s.yaw = in.yaw;
  return s;
}

// Come to rest: a min-jerk to the braking point p + v·|v|/(2·a_max) (the current position when
// at rest), within the limits; yaw kept.
Trajectory rest_trajectory(const PlannerInput& in, const PlannerParams& p) {
  const double v = in.velocity.norm();
  const Eigen::Vector3d stop = in.position + in.velocity * (v / (2 * p.a_max));
  Trajectory tr;
  if (v < 1e-6 && in.acceleration.norm() < 1e-6) return hold_trajectory(in.position, in.yaw);
  TrajectoryLimits l = limits_of(p);
  // Already beyond the limits (should not happen): allow what the drone has.
  l.v_max = std::max(l.v_max, 1.01 * v);
  l.a_max = std::max(l.a_max, 1.01 * in.acceleration.norm());
  if (!min_jerk_within_limits(start_of(in), stop, l, &tr).empty()) return hold_trajectory(in.position, in.yaw);
  return tr;
}

Eigen::Vector3d horizontal_dir(double angle) { return Eigen::Vector3d(std::cos(angle), std::sin(angle), 0); }

}  // namespace

std::string planner_params_error(const PlannerParams& p) {
  auto bad = [](const char* name, double v) { return std::string("PlannerParams.") + name + " = " + std::to_string(v) + " is invalid"; };
  auto pos = [](double v) { return std::isfinite(v) && v > 0; };
  // Upper ends (and the rates' lower ends) beyond any drone this planner flies: out there a value is
  // a typo, and made trajectories of infinite or hour-long duration (review, session 30: --v-max 1e9,
  // --spin-rate 1e-12, --move-max 1e300 were accepted).
  auto within = [](double v, double lo, double hi) { return v >= lo && v <= hi; };
  if (!within(p.takeoff_max, 0, 1000)) return bad("takeoff_max", p.takeoff_max);
  if (!within(p.z_min, -1000, 1000)) return bad("z_min", p.z_min);
  if (!within(p.z_max, -1000, 1000)) return bad("z_max", p.z_max);
  if (!within(p.spin_rate, 0.01, 10)) return bad("spin_rate", p.spin_rate);
  if (!within(p.yaw_accel, 0.01, 100)) return bad("yaw_accel", p.yaw_accel);
  if (!within(p.move_max, 0, 100)) return bad("move_max", p.move_max);
  if (!within(p.v_max, 0.01, 20)) return bad("v_max", p.v_max);
  if (!within(p.a_max, 0.01, 50)) return bad("a_max", p.a_max);
  if (!within(p.move_settle, 0, 60)) return bad("move_settle", p.move_settle);
  // (review, session 32: a spin_overlap of 1e300 rad spun for ever; margins and the separation of
  // 1e300 m were accepted)
  if (!within(p.spin_overlap, 0, 6.3)) return bad("spin_overlap", p.spin_overlap);
  if (!within(p.min_separation, 0, 100)) return bad("min_separation", p.min_separation);
  if (!within(p.move_margin, 0, 10)) return bad("move_margin", p.move_margin);
  if (!within(p.drone_radius, 0, 10)) return bad("drone_radius", p.drone_radius);
  if (!within(p.obstacle_margin, 0, 10)) return bad("obstacle_margin", p.obstacle_margin);
  if (!within(p.push_epsilon, 0, 1)) return bad("push_epsilon", p.push_epsilon);
  if (!within(p.check_spacing, 0, 10)) return bad("check_spacing", p.check_spacing);
  if (!within(p.min_useful_move, 0, 100)) return bad("min_useful_move", p.min_useful_move);
  if (p.push_tries > 1000) return bad("push_tries", p.push_tries);
  for (int k = 0; k < 4; ++k)
    if (!within(p.fence[k], -1e6, 1e6)) return bad(k < 2 ? "fence (x)" : "fence (y)", p.fence[k]);
  // (the message names both ends and the radius: a large drone_radius was reported as a bad XMAX)
  for (int axis = 0; axis < 2; ++axis) {
    const double lo = p.fence[2 * axis], hi = p.fence[2 * axis + 1];
    if (!(hi - lo > 2 * p.drone_radius))
      return std::string("PlannerParams.fence ") + (axis == 0 ? "x" : "y") + " [" + std::to_string(lo) + ", " +
             std::to_string(hi) + "] m is not wider than 2·drone_radius = " + std::to_string(2 * p.drone_radius) + " m";
  }
  if (!std::isfinite(p.takeoff_min) || p.takeoff_min < 0) return bad("takeoff_min", p.takeoff_min);
  if (!std::isfinite(p.takeoff_max) || p.takeoff_max < p.takeoff_min) return bad("takeoff_max", p.takeoff_max);
  if (!pos(p.spin_rate)) return bad("spin_rate", p.spin_rate);
  if (!pos(p.yaw_accel)) return bad("yaw_accel", p.yaw_accel);
  if (!std::isfinite(p.spin_overlap) || p.spin_overlap < 0) return bad("spin_overlap", p.spin_overlap);
  if (!pos(p.min_separation)) return bad("min_separation", p.min_separation);
  if (!std::isfinite(p.move_max) || p.move_max < 0) return bad("move_max", p.move_max);
  if (!std::isfinite(p.move_margin) || p.move_margin < 0) return bad("move_margin", p.move_margin);
  if (!(p.random_move_probability >= 0 && p.random_move_probability <= 1))
    return bad("random_move_probability", p.random_move_probability);
  if (!std::isfinite(p.drone_radius) || p.drone_radius < 0) return bad("drone_radius", p.drone_radius);
  if (!std::isfinite(p.obstacle_margin) || p.obstacle_margin < 0) return bad("obstacle_margin", p.obstacle_margin);
  if (p.push_tries < 1) return bad("push_tries", p.push_tries);
  if (!std::isfinite(p.push_epsilon) || p.push_epsilon < 0) return bad("push_epsilon", p.push_epsilon);
  if (!std::isfinite(p.z_min) || !std::isfinite(p.z_max) || p.z_max < p.z_min) return bad("z_max", p.z_max);
  if (!pos(p.v_max)) return bad("v_max", p.v_max);
  if (!pos(p.a_max)) return bad("a_max", p.a_max);
  if (!pos(p.check_spacing)) return bad("check_spacing", p.check_spacing);
  for (double f : p.fallback_fractions)
    if (!(f > 0 && f <= 1)) return bad("fallback_fractions[]", f);
  if (!std::isfinite(p.min_useful_move) || p.min_useful_move < 0) return bad("min_useful_move", p.min_useful_move);
  if (!std::isfinite(p.move_settle) || p.move_settle < 0) return bad("move_settle", p.move_settle);
  return "";
}

uint64_t PlannerRng::next() {
  uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

double PlannerRng::uniform() { return (next() >> 11) * (1.0 / 9007199254740992.0); }

const char* to_string(ResultStatus s) {
  switch (s) {
    case ResultStatus::none: return "none";
    case ResultStatus::ambiguous: return "ambiguous";
    case ResultStatus::not_certified: return "not_certified";
    case ResultStatus::certified: return "certified";
  }
  return "?";
}

const char* to_string(PlanKind k) {
  switch (k) {
    case PlanKind::hold: return "hold";
    case PlanKind::move: return "move";
    case PlanKind::hover_fallback: return "hover_fallback";
    case PlanKind::rejected: return "rejected";
  }
  return "?";
}

Eigen::Vector3d observed_position(const Eigen::Vector3d& own_position, double own_yaw, const Eigen::Vector3d& vector_g) {
  const double c = std::cos(own_yaw), s = std::sin(own_yaw);
  return own_position + Eigen::Vector3d(c * vector_g.x() - s * vector_g.y(), s * vector_g.x() + c * vector_g.y(), vector_g.z());
}

std::string planner_input_error(const PlannerInput& in) {
  if (!in.position.allFinite()) return "position is not finite";
  if (!in.velocity.allFinite()) return "velocity is not finite";
  if (!in.acceleration.allFinite()) return "acceleration is not finite";
  if (!std::isfinite(in.yaw)) return "yaw is not finite";
  for (size_t i = 0; i < in.observed.size(); ++i)
    if (!in.observed[i].allFinite()) return "observed[" + std::to_string(i) + "] is not finite";
  for (size_t i = 0; i < in.known.size(); ++i)
    if (!in.known[i].allFinite()) return "known[" + std::to_string(i) + "] is not finite";
  return "";
}

double takeoff_height(const PlannerParams& p, PlannerRng* rng) {
  return p.takeoff_min + (p.takeoff_max - p.takeoff_min) * rng->uniform();
}

Plan plan_takeoff(const Eigen::Vector3d& position, double yaw, const PlannerParams& p, PlannerRng rng) {
  Plan plan;
  const std::string perr = planner_params_error(p);
  if (!position.allFinite() || !std::isfinite(yaw) || !perr.empty()) {
    plan.kind = PlanKind::rejected;
    plan.reason = !perr.empty() ? perr : !position.allFinite() ? "position is not finite" : "yaw is not finite";
    plan.rng = rng;
    return plan;
  }
  const double h = takeoff_height(p, &rng);
  plan.target = Eigen::Vector3d(position.x(), position.y(), h);
  TrajectoryStart s;
  s.position = position;
  s.yaw = yaw;
  const std::string err = min_jerk_within_limits(s, plan.target, limits_of(p), &plan.trajectory);
  plan.kind = err.empty() ? PlanKind::move : PlanKind::hover_fallback;
  plan.reason = err.empty() ? "takeoff to " + num(h) + " m" : "takeoff: " + err;
  if (!err.empty()) plan.trajectory = hold_trajectory(position, yaw);
  plan.rng = rng;
  return plan;
}

Plan plan_spin(const Eigen::Vector3d& position, double yaw, const PlannerParams& p, int direction) {
  Plan plan;
  if (!position.allFinite() || !std::isfinite(yaw)) {
    plan.kind = PlanKind::rejected;
    plan.reason = !position.allFinite() ? "position is not finite" : "yaw is not finite";
    return plan;
  }
  plan.kind = PlanKind::hold;
  plan.target = position;
  plan.trajectory = hold_trajectory(position, yaw);
  plan.trajectory.yaw.angle = (direction < 0 ? -1.0 : 1.0) * (2 * kPi + p.spin_overlap);
  plan.trajectory.yaw.rate = p.spin_rate;
  plan.trajectory.yaw.accel = p.yaw_accel;
  plan.reason = "spin 2π + " + num(p.spin_overlap) + " rad at ≤ " + num(p.spin_rate) + " rad/s";
  return plan;
}

namespace {
// Duration of a rest-to-rest straight flight of `distance` m at the trajectory limits (s); 0 for none.
double flight_time(double distance, const PlannerParams& p) {
  Trajectory tr;
  if (!(distance > 0) || !min_jerk_within_limits(TrajectoryStart{}, Eigen::Vector3d(distance, 0, 0), limits_of(p), &tr).empty())
    return 0;
  return tr.duration();
}
}  // namespace

double move_slot(const PlannerParams& p) { return flight_time(p.move_max, p) + p.move_settle; }

double takeoff_slot(double start_z, const PlannerParams& p) {
  return flight_time(p.takeoff_max - start_z, p) + p.move_settle;
}

double max_move_distance(double d, const PlannerParams& p) {
  if (!std::isfinite(d)) return p.move_max;
  return std::min(p.move_max, std::max(0.0, (d - p.min_separation) / 2 - p.move_margin));
}

// The max-move rule along one direction (unit vector `dir`): only the part of a move toward a
// drone must fit within that drone's half of the spare separation, so a drone too close to move
// toward its neighbour can still move away from it. With every drone's component toward another
// within (d − s)/2 − margin (the symmetric rule is the special case), their distance along the
// line between them, and so their distance, stays ≥ s + 2·margin.
double directional_max_move(const Eigen::Vector3d& position, const Eigen::Vector3d& dir,
                            const std::vector<Eigen::Vector3d>& drones, const PlannerParams& p) {
  double cap = p.move_max;
  for (const Eigen::Vector3d& q : drones) {
    const Eigen::Vector3d r = q - position;
    const double d = r.norm();
    const double toward = d > 1e-9 ? dir.dot(r) / d : 1.0;
    if (toward <= 1e-9) continue;
    cap = std::min(cap, std::max(0.0, (d - p.min_separation) / 2 - p.move_margin) / toward);
  }
  return cap;
}

Plan plan_step(const PlannerInput& in, const std::vector<ObstacleBox>& pieces, const PlannerParams& p) {
  Plan plan;
  plan.rng = in.rng;
  plan.target = in.position;
  std::string err = planner_params_error(p);
  if (err.empty()) err = planner_input_error(in);
  if (err.empty()) {
    for (size_t i = 0; i < pieces.size(); ++i)
      if (!pieces[i].lo.allFinite() || !pieces[i].hi.allFinite()) {
        err = "pieces[" + std::to_string(i) + "] is not finite";
        break;
      }
  }
  if (!err.empty()) {
    plan.kind = PlanKind::rejected;
    plan.reason = err;
    plan.trajectory = Trajectory{};
    return plan;
  }
  if (in.status == ResultStatus::certified) {
    plan.kind = PlanKind::hold;
    plan.trajectory = rest_trajectory(in, p);
    plan.target = plan.trajectory.end_position();
    plan.reason = "certified: hold";
    return plan;
  }
  // Every other drone the planner knows of.
  std::vector<Eigen::Vector3d> drones = in.observed;
  drones.insert(drones.end(), in.known.begin(), in.known.end());
  double d = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& q : drones) d = std::min(d, (q - in.position).norm());
  const double max_move = max_move_distance(d, p);
  plan.max_move = max_move;
  plan.nearest_drone = d;
  auto hold = [&](PlanKind kind, const std::string& why) {
    plan.kind = kind;
    plan.trajectory = rest_trajectory(in, p);
    plan.target = plan.trajectory.end_position();
    plan.reason = why;
    return plan;
  };
  // Too close to move toward the nearest drone: move away from it (the directional rule), so two
  // drones that took off near each other do not hold side by side round after round.
  const bool separate = max_move < std::max(p.min_useful_move, 1e-9);
  Eigen::Vector2d away = Eigen::Vector2d::Zero();
  for (const Eigen::Vector3d& q : drones)
    if ((q - in.position).norm() <= d + 1e-9) away = (in.position - q).head<2>();
  if (separate && away.norm() < 1e-6)
    return hold(PlanKind::hold, std::string(to_string(in.status)) + ": nearest drone at " + num(d) +
                                    " m (straight above or below) leaves a max move of " + num(max_move) + " m: hold");
  // Direction.
  double angle = 0;
  std::string why;
  PlannerRng rng = in.rng;
  if (separate) {
    angle = std::atan2(away.y(), away.x());
    why = std::string(to_string(in.status)) + ": nearest drone at " + num(d) + " m leaves a max move of " +
          num(max_move) + " m toward it: moving away from it";
  } else if (in.status == ResultStatus::ambiguous) {
    // A deliberate move breaks a symmetric formation: a random direction, but within ±90° of the
    // seen drones' centroid when there is one, so that a drone never turns its back on the drones
    // it must keep seeing (moving apart thins the evidence: range noise grows as range²).
    const double u = rng.uniform();
    const std::vector<Eigen::Vector3d>& pool = !in.observed.empty() ? in.observed : in.known;
    Eigen::Vector2d towards = Eigen::Vector2d::Zero();
    for (const Eigen::Vector3d& q : pool) towards += (q - in.position).head<2>();
    if (towards.norm() > 1e-6) {
      angle = std::atan2(towards.y(), towards.x()) + kPi * (u - 0.5);
      why = "ambiguous formation: deliberate move in a random direction within 90° of the " +
            std::string(!in.observed.empty() ? "observed" : "known") + " drones";
    } else {
      angle = 2 * kPi * u;
      why = "ambiguous formation: deliberate move in a random direction";
    }
  } else {
    const double r = rng.uniform();
    const double a = 2 * kPi * rng.uniform();  // drawn always, so the stream does not depend on r
    const std::vector<Eigen::Vector3d>& pool = !in.observed.empty() ? in.observed : in.known;
    if (r < p.random_move_probability) {
      angle = a;
      why = "random direction (p = " + num(p.random_move_probability) + ")";
    } else if (pool.empty()) {
      plan.rng = rng;
      return hold(PlanKind::hold, std::string(to_string(in.status)) + ": no drone observed: hold");
    } else {
      size_t far = 0;
      double best = -1;
      for (size_t i = 0; i < pool.size(); ++i) {
        const double dist = (pool[i] - in.position).norm();
        if (dist > best) best = dist, far = i;
      }
      const Eigen::Vector2d h = (pool[far] - in.position).head<2>();
      if (h.norm() < 1e-6) {
        angle = a;
        why = "farthest drone straight above/below: random direction";
      } else {
        angle = std::atan2(h.y(), h.x());
        why = "toward the farthest " + std::string(!in.observed.empty() ? "observed" : "known") + " drone (" +
              num(best) + " m)";
      }
    }
  }
  plan.rng = rng;
  // Only pieces that a target in the max-move ball, its push-out or its path can touch.
  std::vector<ObstacleBox> near;
  const double reach = (separate ? p.move_max : max_move) + obstacle_inflation(p) + 0.5;
  for (const ObstacleBox& b : pieces)
    if (box_distance(b, in.position) < reach) near.push_back(b);
  // Candidates: the direction at the fallback fractions, then turned by ±45°, ±90°, ±135°, 180°.
  const double turns[] = {0, kPi / 4, -kPi / 4, kPi / 2, -kPi / 2, 3 * kPi / 4, -3 * kPi / 4, kPi};
  std::string first_problem;
  const TrajectoryLimits lim = limits_of(p);
  const TrajectoryStart start = start_of(in);
  for (double turn : turns) {
    // A separating move's length follows the directional rule for each candidate direction.
    const double cap = separate ? directional_max_move(in.position, horizontal_dir(angle + turn), drones, p) : max_move;
    for (double frac : p.fallback_fractions) {
      const double len = cap * frac;
      if (len < p.min_useful_move) continue;
      Eigen::Vector3d target = in.position + len * horizontal_dir(angle + turn);
      target.z() = std::clamp(target.z(), p.z_min, p.z_max);
      Eigen::Vector3d pushed;
      std::string problem;
      if (!push_out(target, near, p, &pushed)) {
        problem = "target " + num(target.x()) + ", " + num(target.y()) + " could not be pushed out of the obstacles";
      } else if (pushed.z() < p.z_min - 1e-9 || pushed.z() > p.z_max + 1e-9) {
        problem = "pushed target leaves the height window";
      } else if (pushed.x() < p.fence[0] + p.drone_radius || pushed.x() > p.fence[1] - p.drone_radius ||
                 pushed.y() < p.fence[2] + p.drone_radius || pushed.y() > p.fence[3] - p.drone_radius) {
        problem = "target " + num(pushed.x()) + ", " + num(pushed.y()) + " leaves the fence";
      } else if ((pushed - in.position).norm() > cap * (1 + 1e-9)) {
        problem = "pushed target leaves the max-move ball";
      } else if ((pushed - in.position).norm() < p.min_useful_move) {
        problem = "pushed target is too close to be worth a move";
      } else {
        Trajectory tr;
        problem = min_jerk_within_limits(start, pushed, lim, &tr);
        if (problem.empty()) problem = check_trajectory(tr, near, drones, in.position, cap, p);
        if (problem.empty() && separate && directional_max_move(in.position, (pushed - in.position).normalized(), drones, p) <
                                              (pushed - in.position).norm() * (1 - 1e-9))
          problem = "pushed target moves too far toward a drone";
        if (problem.empty()) {
          plan.kind = PlanKind::move;
          plan.target = pushed;
          plan.trajectory = tr;
          plan.reason = why + ", max move " + num(cap) + " m";
          if (turn != 0 || frac != p.fallback_fractions.front())
            plan.reason += "; alternative: turned " + num(turn * 180 / kPi, "%.0f") + "°, " + num(frac) +
                           " of the move (first choice: " + first_problem + ")";
          if ((pushed - target).norm() > 1e-9) plan.reason += "; target pushed out by " + num((pushed - target).norm()) + " m";
          return plan;
        }
      }
      if (first_problem.empty()) first_problem = problem;
    }
  }
  return hold(PlanKind::hover_fallback, why + ": no safe move (first choice: " +
                                            (first_problem.empty() ? std::string("none tried") : first_problem) +
                                            "): hover");
}

}  // namespace fact
