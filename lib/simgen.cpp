// The scenario generator: a swarm in a room, observed over rounds, with its ground truth.
// The model is described in fact/simgen.h. Frames: world FLU (z up); f_i = drone i's odometry
// frame; body = the drone's gravity-aligned body frame (x along its heading, z up). Units: m, rad.
#include "fact/simgen.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

namespace fact {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kObstacleHeight = 3.0;           // m, height of the random cylinders
constexpr double kFalsePositiveMinRange = 0.5;    // m
constexpr double kFalsePositiveMaxRange = 8.0;    // m, when range_limit = 0 (unlimited)
constexpr double kHalfVerticalFov = 29.0 * kPi / 180.0;  // rad, D430: 58° vertical field of view
constexpr int kPlacementRestarts = 10;            // random formation: full restarts
constexpr int kPlacementTries = 1000;             // random formation: candidates per drone
constexpr int kObstacleTries = 1000;              // candidates per random obstacle
constexpr int kMoveTries = 100;                   // candidates per move, else the drone stays

// ---------------------------------------------------------------------------------------------
// Small helpers

std::string text(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

std::string text(const Eigen::Vector3d& v) {
  return "(" + text(v.x()) + ", " + text(v.y()) + ", " + text(v.z()) + ")";
}

[[noreturn]] void fail(const std::string& option, const std::string& value, const std::string& why) {
  throw std::invalid_argument("invalid option " + option + " = " + value + ": " + why);
}

// An angle wrapped into (−π, π] (rad).
double wrap(double angle) {
  const double a = std::remainder(angle, 2 * kPi);  // [−π, π]
  return a <= -kPi ? a + 2 * kPi : a;
}

// v rotated by `angle` (rad) about the z axis.
Eigen::Vector3d rotate_z(double angle, const Eigen::Vector3d& v) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()) * v;
}

// The vector of length `range` at azimuth `azimuth` (from x toward y) and elevation `elevation`
// (from the xy plane toward z), in whatever frame the angles are measured in.
Eigen::Vector3d spherical(double range, double azimuth, double elevation) {
  return range * Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth),
                                 std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
}

double horizontal_distance(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return (a.head<2>() - b.head<2>()).norm();
}

// Whether a drone centre p is closer than `clearance` to the cylinder (side or top).
bool blocked(const Eigen::Vector3d& p, const Obstacle& o, double clearance) {
  return horizontal_distance(p, o.center) < o.radius + clearance && p.z() < o.center.z() + o.height + clearance &&
         p.z() > o.center.z() - clearance;
}

// Whether the segment a→b passes through the solid cylinder o.
bool segment_hits(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Obstacle& o) {
  const Eigen::Vector3d d = b - a;
  double lo = 0, hi = 1;  // segment parameters t, point a + t·d
  const double base = o.center.z(), top = o.center.z() + o.height;
  if (std::abs(d.z()) < 1e-12) {
    if (a.z() < base || a.z() > top) return false;
  } else {
    const double t1 = (base - a.z()) / d.z(), t2 = (top - a.z()) / d.z();
    lo = std::max(lo, std::min(t1, t2));
    hi = std::min(hi, std::max(t1, t2));
    if (lo > hi) return false;
  }
  // Horizontal: |w + t·e|² ≤ r², a quadratic A t² + B t + C ≤ 0.
  const Eigen::Vector2d w = a.head<2>() - o.center.head<2>(), e = d.head<2>();
  const double qa = e.squaredNorm(), qb = 2 * w.dot(e), qc = w.squaredNorm() - o.radius * o.radius;
  if (qa < 1e-24) return qc <= 0;
  const double disc = qb * qb - 4 * qa * qc;
  if (disc < 0) return false;
  const double root = std::sqrt(disc);
  return std::max(lo, (-qb - root) / (2 * qa)) <= std::min(hi, (-qb + root) / (2 * qa));
}

bool in_room(const Eigen::Vector3d& p, double room) {
  return std::abs(p.x()) <= room / 2 && std::abs(p.y()) <= room / 2;
}

// ---------------------------------------------------------------------------------------------
// Validation: every check throws std::invalid_argument naming the option and its value.

void require_finite(const std::string& name, double v) {
  if (!std::isfinite(v)) fail(name, text(v), "must be a finite number");
}

// " (unit)", or "" for a dimensionless value.
std::string in_units(const std::string& unit) { return unit.empty() ? "" : " (" + unit + ")"; }

void require_at_least(const std::string& name, double v, double min, const std::string& unit) {
  require_finite(name, v);
  if (v < min) fail(name, text(v), "must be ≥ " + text(min) + in_units(unit));
}

void require_positive(const std::string& name, double v, const std::string& unit) {
  require_finite(name, v);
  if (v <= 0) fail(name, text(v), "must be > 0" + in_units(unit));
}

// Upper ends beyond any swarm the estimator takes (review, session 32: 2^31 rounds or 1e9 false
// positives ate the machine's memory, a 1e308 m room wrote rounds fact-solve refuses).
void require_at_most(const std::string& name, double v, double max, const std::string& unit) {
  if (v > max) fail(name, text(v), "must be ≤ " + text(max) + in_units(unit));
}

void validate_counts(const SimOptions& o) {
  if (o.drones < 2) fail("drones", std::to_string(o.drones), "need at least 2 drones");
  if (o.rounds < 1) fail("rounds", std::to_string(o.rounds), "need at least 1 round");
  if (o.obstacles < 0) fail("obstacles", std::to_string(o.obstacles), "must be ≥ 0");
  require_at_most("drones", o.drones, kMaxDrones, "the estimator's limit");
  require_at_most("rounds", o.rounds, 10000, "");
  require_at_most("obstacles", o.obstacles, 10000, "");
  if (o.ids.empty()) return;
  if (static_cast<int>(o.ids.size()) != o.drones)
    fail("ids", std::to_string(o.ids.size()) + " ids", "need one per drone, drones = " + std::to_string(o.drones));
  std::set<int> seen;
  for (std::size_t i = 0; i < o.ids.size(); ++i) {
    const std::string name = "ids[" + std::to_string(i) + "]";
    if (o.ids[i] < 0) fail(name, std::to_string(o.ids[i]), "ids must be ≥ 0");
    if (!seen.insert(o.ids[i]).second) fail(name, std::to_string(o.ids[i]), "duplicate id");
  }
}

void validate_geometry(const SimOptions& o) {
  require_positive("room", o.room, "m");
  require_at_most("room", o.room, 1000, "m");
  require_positive("spacing", o.spacing, "m");
  require_at_least("height_min", o.height_min, 0, "m");
  require_at_least("height_max", o.height_max, 0, "m");
  if (o.height_min > o.height_max)
    fail("height_min", text(o.height_min), "above height_max = " + text(o.height_max));
  require_at_least("min_separation", o.min_separation, 0, "m");
  require_at_least("move", o.move, 0, "m");
  require_positive("obstacle_radius", o.obstacle_radius, "m");
  const bool fixed = o.formation == Formation::polygon || o.formation == Formation::grid || o.formation == Formation::line;
  if (fixed && o.spacing < o.min_separation)
    fail("spacing", text(o.spacing), std::string("below min_separation = ") + text(o.min_separation) +
                                         " for formation " + to_string(o.formation));
}

void validate_sensor(const SimOptions& o) {
  require_at_least("paper_sigma", o.paper_sigma, 0, "");
  require_at_least("depth_c", o.depth_c, 0, "1/m");
  require_at_least("depth_b", o.depth_b, 0, "rad");
  require_at_least("range_limit", o.range_limit, 0, "m; 0 = unlimited");
  require_at_least("fov_horizontal", o.fov_horizontal, 0, "rad");
  if (o.fov_horizontal > 2 * kPi) fail("fov_horizontal", text(o.fov_horizontal), "must be ≤ 2π rad");
  require_at_least("miss_rate", o.miss_rate, 0, "");
  if (o.miss_rate > 1) fail("miss_rate", text(o.miss_rate), "is a probability, must be ≤ 1");
  require_at_least("false_positives", o.false_positives, 0, "per drone per round");
  require_at_most("false_positives", o.false_positives, 100, "per drone per round");
  require_at_most("paper_sigma", o.paper_sigma, 10, "");
  require_at_most("depth_c", o.depth_c, 10, "1/m");
  require_at_least("drift_yaw", o.drift_yaw, 0, "rad per round");
  require_at_least("drift_position", o.drift_position, 0, "m per round");
}

void validate_positions(const SimOptions& o) {
  if (o.formation != Formation::given) {
    if (!o.positions.empty())
      fail("positions", std::to_string(o.positions.size()) + " positions",
           std::string("only used with formation given, formation is ") + to_string(o.formation));
    return;
  }
  if (static_cast<int>(o.positions.size()) != o.drones)
    fail("positions", std::to_string(o.positions.size()) + " positions",
         "formation given needs one per drone, drones = " + std::to_string(o.drones));
  for (std::size_t i = 0; i < o.positions.size(); ++i) {
    const std::string name = "positions[" + std::to_string(i) + "]";
    const Eigen::Vector3d& p = o.positions[i];
    if (!p.allFinite()) fail(name, text(p), "must be finite");
    if (!in_room(p, o.room)) fail(name, text(p), "outside the room, |x|, |y| ≤ room/2 = " + text(o.room / 2));
    for (std::size_t j = 0; j < i; ++j)
      if ((p - o.positions[j]).norm() < o.min_separation)
        fail(name, text(p), text((p - o.positions[j]).norm()) + " m from positions[" + std::to_string(j) +
                                "], below min_separation = " + text(o.min_separation));
  }
}

void validate_given_obstacles(const SimOptions& o) {
  for (std::size_t k = 0; k < o.given_obstacles.size(); ++k) {
    const std::string name = "given_obstacles[" + std::to_string(k) + "]";
    const Obstacle& ob = o.given_obstacles[k];
    if (!ob.center.allFinite()) fail(name + ".center", text(ob.center), "must be finite");
    require_positive(name + ".radius", ob.radius, "m");
    require_positive(name + ".height", ob.height, "m");
  }
}

void validate(const SimOptions& o) {
  validate_counts(o);
  validate_geometry(o);
  validate_sensor(o);
  validate_positions(o);
  validate_given_obstacles(o);
}

// ---------------------------------------------------------------------------------------------
// Fixed formations: horizontal world positions (m), centred on the origin.

std::vector<Eigen::Vector2d> polygon_xy(int n, double side) {
  const double radius = side / (2 * std::sin(kPi / n));  // circumradius of the regular n-gon
  std::vector<Eigen::Vector2d> xy;
  for (int i = 0; i < n; ++i) xy.emplace_back(radius * std::cos(2 * kPi * i / n), radius * std::sin(2 * kPi * i / n));
  return xy;
}

std::vector<Eigen::Vector2d> grid_xy(int n, double step) {
  const int columns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n))));
  const int rows = (n + columns - 1) / columns;
  std::vector<Eigen::Vector2d> xy;
  for (int i = 0; i < n; ++i)
    xy.emplace_back((i % columns - (columns - 1) / 2.0) * step, (i / columns - (rows - 1) / 2.0) * step);
  return xy;
}

std::vector<Eigen::Vector2d> line_xy(int n, double step) {
  std::vector<Eigen::Vector2d> xy;
  for (int i = 0; i < n; ++i) xy.emplace_back((i - (n - 1) / 2.0) * step, 0.0);
  return xy;
}

std::vector<Eigen::Vector2d> fixed_xy(const SimOptions& o) {
  std::vector<Eigen::Vector2d> xy = o.formation == Formation::polygon ? polygon_xy(o.drones, o.spacing)
                                    : o.formation == Formation::grid  ? grid_xy(o.drones, o.spacing)
                                                                      : line_xy(o.drones, o.spacing);
  double extent = 0;  // largest |x| or |y| (m)
  for (const Eigen::Vector2d& p : xy) extent = std::max(extent, p.cwiseAbs().maxCoeff());
  if (extent > o.room / 2 + 1e-9)
    fail("room", text(o.room), std::string("formation ") + to_string(o.formation) + " of " +
                                   std::to_string(o.drones) + " drones at spacing " + text(o.spacing) +
                                   " m reaches " + text(extent) + " m from the centre, beyond room/2");
  return xy;
}

// ---------------------------------------------------------------------------------------------
// The generator: one random engine, seeded once, and the world state.

class Generator {
 public:
  explicit Generator(const SimOptions& o) : o_(o), rng_(o.seed) {}
  Scenario run();

 private:
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
  double gauss() { return normal_(rng_); }
  double draw_height();

  void sort_drones();
  void place_drones();
  std::vector<Eigen::Vector3d> place_random();
  void place_obstacles();
  bool clear_of_others(const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& others, int skip) const;
  bool clear_of_obstacles(const Eigen::Vector3d& p) const;

  void move_drones();
  void step_drift();
  void drifted_frame(int i, double* yaw, Eigen::Vector3d* origin) const;
  Round observe(int k, std::vector<std::vector<int>>* targets);
  DroneRound observe_drone(int i, std::vector<int>* targets);
  bool visible(int i, int j) const;
  Observation report(int i, double heading, const Eigen::Vector3d& body_vector) const;
  Observation detection(int i, int j);
  Observation false_positive(int i);
  int false_positive_count();
  Eigen::Vector3d add_noise(const Eigen::Vector3d& v);
  Eigen::Vector3d reported_position(int i) const;
  void shuffle(std::vector<Observation>* observations, std::vector<int>* targets);

  const SimOptions& o_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};

  std::vector<int> ids_;                     // ascending
  std::vector<Eigen::Vector3d> given_;       // positions for Formation::given, in ids_ order
  std::vector<Eigen::Vector3d> position_;    // world centre now (m)
  std::vector<double> frame_yaw_;            // yaw of f_i in the world (rad)
  std::vector<Eigen::Vector3d> origin_;      // origin of f_i in the world (m)
  std::vector<double> drift_yaw_;            // accumulated VIO yaw drift (rad)
  std::vector<Eigen::Vector3d> drift_position_;  // accumulated VIO position drift, in f_i (m)
  std::vector<Obstacle> obstacles_;
};

double Generator::draw_height() {
  if (o_.equal_heights) return (o_.height_min + o_.height_max) / 2;
  return uniform(o_.height_min, o_.height_max);
}

// ids_ ascending; given positions follow their ids.
void Generator::sort_drones() {
  std::vector<int> ids = o_.ids;
  if (ids.empty()) {
    ids.resize(o_.drones);
    std::iota(ids.begin(), ids.end(), 0);
  }
  std::vector<int> order(ids.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return ids[a] < ids[b]; });
  for (int i : order) {
    ids_.push_back(ids[i]);
    if (o_.formation == Formation::given) given_.push_back(o_.positions[i]);
  }
}

bool Generator::clear_of_others(const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& others, int skip) const {
  for (std::size_t j = 0; j < others.size(); ++j)
    if (static_cast<int>(j) != skip && (p - others[j]).norm() < o_.min_separation) return false;
  return true;
}

bool Generator::clear_of_obstacles(const Eigen::Vector3d& p) const {
  for (const Obstacle& ob : obstacles_)
    if (blocked(p, ob, o_.min_separation / 2)) return false;
  return true;
}

// Rejection sampling, uniform in the room, heights as drawn, 3-D separation.
std::vector<Eigen::Vector3d> Generator::place_random() {
  const double half = o_.room / 2;
  for (int restart = 0; restart < kPlacementRestarts; ++restart) {
    std::vector<Eigen::Vector3d> placed;
    for (int i = 0; i < o_.drones; ++i) {
      for (int t = 0; t < kPlacementTries; ++t) {
        // The draws are named so their order is fixed (C++ leaves the order of constructor
        // arguments unspecified: GCC takes them right to left on x86-64, left to right on
        // aarch64). z, y, x is the order every x86-64 scenario so far was drawn in.
        const double z = draw_height();
        const double y = uniform(-half, half);
        const double x = uniform(-half, half);
        const Eigen::Vector3d p(x, y, z);
        if (clear_of_others(p, placed, -1) && clear_of_obstacles(p)) {
          placed.push_back(p);
          break;
        }
      }
      if (static_cast<int>(placed.size()) != i + 1) break;
    }
    if (static_cast<int>(placed.size()) == o_.drones) return placed;
  }
  const std::string clear = obstacles_.empty() ? "" : ", clear of the given obstacles,";
  fail("min_separation", text(o_.min_separation),
       "cannot place " + std::to_string(o_.drones) + " drones that far apart (3-D) in a " + text(o_.room) + " m × " +
           text(o_.room) + " m room" + clear + " in " + std::to_string(kPlacementRestarts) + " × " +
           std::to_string(kPlacementTries) + " tries per drone; lower drones or min_separation, or raise room");
}

// Round-0 positions and the odometry frames (origin on the floor below, random yaw).
void Generator::place_drones() {
  if (o_.formation == Formation::random) {
    position_ = place_random();
  } else if (o_.formation == Formation::given) {
    position_ = given_;
  } else {
    for (const Eigen::Vector2d& xy : fixed_xy(o_)) position_.emplace_back(xy.x(), xy.y(), draw_height());
  }
  for (std::size_t i = 0; i < position_.size(); ++i) {
    for (std::size_t k = 0; k < obstacles_.size(); ++k)
      if (blocked(position_[i], obstacles_[k], o_.min_separation / 2))
        fail("given_obstacles[" + std::to_string(k) + "]", text(obstacles_[k].center),
             "within min_separation/2 = " + text(o_.min_separation / 2) + " m of drone " + std::to_string(ids_[i]) +
                 " at " + text(position_[i]));
    origin_.emplace_back(position_[i].x(), position_[i].y(), 0.0);
    frame_yaw_.push_back(kPi - uniform(0, 2 * kPi));  // (−π, π]
  }
  drift_yaw_.assign(position_.size(), 0.0);
  drift_position_.assign(position_.size(), Eigen::Vector3d::Zero());
}

// Random cylinders, uniform in the room, ≥ min_separation + radius from every takeoff spot.
void Generator::place_obstacles() {
  const double half = o_.room / 2, clearance = o_.min_separation + o_.obstacle_radius;
  for (int k = 0; k < o_.obstacles; ++k) {
    bool placed = false;
    for (int t = 0; t < kObstacleTries && !placed; ++t) {
      const double y = uniform(-half, half);  // y then x: the order x86-64 drew them in (see above)
      const double x = uniform(-half, half);
      const Eigen::Vector3d c(x, y, 0.0);
      placed = std::all_of(origin_.begin(), origin_.end(),
                           [&](const Eigen::Vector3d& spot) { return horizontal_distance(c, spot) >= clearance; });
      if (placed) obstacles_.push_back(Obstacle{c, o_.obstacle_radius, kObstacleHeight});
    }
    if (!placed)
      fail("obstacles", std::to_string(o_.obstacles),
           "obstacle " + std::to_string(k) + " found no spot at least min_separation + obstacle_radius = " +
               text(clearance) + " m from every takeoff spot in " + std::to_string(kObstacleTries) + " tries");
  }
}

// Each drone in turn moves horizontally up to o_.move, or stays when no candidate is free.
void Generator::move_drones() {
  if (o_.move <= 0) return;
  for (std::size_t i = 0; i < position_.size(); ++i) {
    for (int t = 0; t < kMoveTries; ++t) {
      const double direction = uniform(0, 2 * kPi), distance = uniform(0, o_.move);
      const Eigen::Vector3d p =
          position_[i] + distance * Eigen::Vector3d(std::cos(direction), std::sin(direction), 0.0);
      if (in_room(p, o_.room) && clear_of_others(p, position_, static_cast<int>(i)) && clear_of_obstacles(p)) {
        position_[i] = p;
        break;
      }
    }
  }
}

// One random-walk step of every drone's VIO drift. Always four draws per drone, so the
// drift σ does not change the rest of the scenario.
void Generator::step_drift() {
  for (std::size_t i = 0; i < position_.size(); ++i) {
    drift_yaw_[i] += o_.drift_yaw * gauss();
    for (int a = 0; a < 3; ++a) drift_position_[i][a] += o_.drift_position * gauss();
  }
}

bool Generator::visible(int i, int j) const {
  const Eigen::Vector3d& a = position_[i];
  const Eigen::Vector3d& b = position_[j];
  if (o_.range_limit > 0 && (b - a).norm() > o_.range_limit) return false;
  return std::none_of(obstacles_.begin(), obstacles_.end(), [&](const Obstacle& ob) { return segment_hits(a, b, ob); });
}

// What drone i reports in f_i (with its drift): its position, (m). The drift moves the whole
// frame: its yaw turns positions as well as headings, as a drifting VIO's does.
Eigen::Vector3d Generator::reported_position(int i) const {
  return rotate_z(drift_yaw_[i], rotate_z(-frame_yaw_[i], position_[i] - origin_[i])) + drift_position_[i];
}

// The frame drone i's odometry is in while its drift is what it is now: a world point x has
// odometry coordinates R(−yaw)(x − origin), with yaw = θ − δ_yaw and origin = o − R(yaw) δ_p.
void Generator::drifted_frame(int i, double* yaw, Eigen::Vector3d* origin) const {
  *yaw = wrap(frame_yaw_[i] - drift_yaw_[i]);
  *origin = origin_[i] - rotate_z(*yaw, drift_position_[i]);
}

// A detection as drone i reports it, made while its world heading was `heading` (rad).
Observation Generator::report(int i, double heading, const Eigen::Vector3d& body_vector) const {
  Observation d;
  d.odom_position = reported_position(i);
  d.odom_yaw = wrap(heading - frame_yaw_[i] + drift_yaw_[i]);
  d.vector = body_vector;
  return d;
}

// Three standard normal draws whatever the noise kind, so the kind does not change the rest.
Eigen::Vector3d Generator::add_noise(const Eigen::Vector3d& v) {
  // Named draws, in the order x86-64 took them (C++ leaves the order of constructor arguments
  // unspecified; GCC on aarch64 took them the other way: see place_random).
  const double g2 = gauss();
  const double g1 = gauss();
  const double g0 = gauss();
  const Eigen::Vector3d g(g0, g1, g2);
  const double range = v.norm();
  if (o_.noise == NoiseKind::paper) return v + o_.paper_sigma * range * g;
  if (o_.noise == NoiseKind::none) return v;
  const double azimuth = std::atan2(v.y(), v.x()), elevation = std::atan2(v.z(), v.head<2>().norm());
  return spherical(range + o_.depth_c * range * range * g[0], azimuth + o_.depth_b * g[1],
                   elevation + o_.depth_b * g[2]);
}

// Drone i detecting drone j: heading = bearing to j + uniform offset in ±fov/2 (world, rad).
Observation Generator::detection(int i, int j) {
  const Eigen::Vector3d world = position_[j] - position_[i];
  const double heading = std::atan2(world.y(), world.x()) + o_.fov_horizontal / 2 * uniform(-1, 1);
  return report(i, heading, add_noise(rotate_z(-heading, world)));
}

// A spurious detection: random heading, range, azimuth in the image, elevation within ±29°.
Observation Generator::false_positive(int i) {
  const double heading = kPi - uniform(0, 2 * kPi);
  const double far = o_.range_limit > 0 ? o_.range_limit : kFalsePositiveMaxRange;
  const double range = uniform(std::min(kFalsePositiveMinRange, far), far);
  const double azimuth = o_.fov_horizontal / 2 * uniform(-1, 1);
  const double elevation = kHalfVerticalFov * uniform(-1, 1);
  return report(i, heading, spherical(range, azimuth, elevation));
}

int Generator::false_positive_count() {
  if (o_.false_positives <= 0) return 0;
  return std::poisson_distribution<int>(o_.false_positives)(rng_);
}

void Generator::shuffle(std::vector<Observation>* observations, std::vector<int>* targets) {
  std::vector<std::size_t> order(observations->size());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), rng_);
  std::vector<Observation> o;
  std::vector<int> t;
  for (std::size_t k : order) {
    o.push_back((*observations)[k]);
    t.push_back((*targets)[k]);
  }
  *observations = o;
  *targets = t;
}

// Drone i's round: its spin's detections (every draw made even when missed), then false
// positives, shuffled. targets receives the id each observation really saw (−1: false positive).
DroneRound Generator::observe_drone(int i, std::vector<int>* targets) {
  DroneRound r;
  r.position = reported_position(i);
  r.yaw = wrap(drift_yaw_[i]);  // each round starts facing f_i's x axis
  targets->clear();
  for (int j = 0; j < static_cast<int>(position_.size()); ++j) {
    if (j == i || !visible(i, j)) continue;
    const bool missed = uniform(0, 1) < o_.miss_rate;
    const Observation d = detection(i, j);
    if (missed) continue;
    r.observations.push_back(d);
    targets->push_back(ids_[j]);
  }
  const int spurious = false_positive_count();
  for (int f = 0; f < spurious; ++f) {
    r.observations.push_back(false_positive(i));
    targets->push_back(-1);
  }
  shuffle(&r.observations, targets);
  return r;
}

Round Generator::observe(int k, std::vector<std::vector<int>>* targets) {
  Round round;
  round.index = k;
  targets->assign(position_.size(), {});
  for (std::size_t i = 0; i < position_.size(); ++i)
    round.drones[ids_[i]] = observe_drone(static_cast<int>(i), &(*targets)[i]);
  return round;
}

Scenario Generator::run() {
  sort_drones();
  obstacles_ = o_.given_obstacles;
  place_drones();
  place_obstacles();
  Scenario s;
  s.rounds.drones = ids_;
  for (int k = 0; k < o_.rounds; ++k) {
    if (k > 0) {
      move_drones();
      step_drift();
    }
    s.truth.positions.push_back(position_);
    s.truth.drifted_yaw.emplace_back(position_.size());
    s.truth.drifted_origin.emplace_back(position_.size());
    for (std::size_t i = 0; i < position_.size(); ++i)
      drifted_frame(static_cast<int>(i), &s.truth.drifted_yaw.back()[i], &s.truth.drifted_origin.back()[i]);
    s.truth.targets.emplace_back();
    s.rounds.rounds.push_back(observe(k, &s.truth.targets.back()));
  }
  s.truth.ids = ids_;
  s.truth.frame_yaw = frame_yaw_;
  s.truth.frame_origin = origin_;
  s.truth.obstacles = obstacles_;
  return s;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

const char* to_string(Formation f) {
  switch (f) {
    case Formation::random: return "random";
    case Formation::polygon: return "polygon";
    case Formation::grid: return "grid";
    case Formation::line: return "line";
    case Formation::given: return "given";
  }
  return "unknown";
}

bool parse_formation(const std::string& text, Formation* f) {
  for (Formation c : {Formation::random, Formation::polygon, Formation::grid, Formation::line, Formation::given})
    if (text == to_string(c)) {
      *f = c;
      return true;
    }
  return false;
}

const char* to_string(NoiseKind k) {
  switch (k) {
    case NoiseKind::none: return "none";
    case NoiseKind::paper: return "paper";
    case NoiseKind::depth: return "depth";
  }
  return "unknown";
}

bool parse_noise(const std::string& text, NoiseKind* k) {
  for (NoiseKind c : {NoiseKind::none, NoiseKind::paper, NoiseKind::depth})
    if (text == to_string(c)) {
      *k = c;
      return true;
    }
  return false;
}

Scenario generate_scenario(const SimOptions& options) {
  validate(options);
  return Generator(options).run();
}

namespace {

std::vector<TruePose> relative_poses(const Truth& truth, int reference_id, const std::vector<double>& frame_yaw,
                                     const std::vector<Eigen::Vector3d>& frame_origin) {
  const std::size_t n = truth.ids.size();
  if (frame_yaw.size() != n || frame_origin.size() != n)
    throw std::invalid_argument("true_poses: truth has " + std::to_string(n) + " ids but " +
                                std::to_string(frame_yaw.size()) + " frame yaws and " +
                                std::to_string(frame_origin.size()) + " frame origins");
  const auto ref = std::find(truth.ids.begin(), truth.ids.end(), reference_id);
  if (ref == truth.ids.end())
    throw std::invalid_argument("true_poses: reference id " + std::to_string(reference_id) + " is not in truth.ids");
  const std::size_t r = static_cast<std::size_t>(ref - truth.ids.begin());
  std::vector<TruePose> poses;
  for (std::size_t i = 0; i < n; ++i) {
    TruePose p;
    p.id = truth.ids[i];
    p.yaw = wrap(frame_yaw[i] - frame_yaw[r]);
    p.position = rotate_z(-frame_yaw[r], frame_origin[i] - frame_origin[r]);
    poses.push_back(p);
  }
  return poses;
}

}  // namespace

std::vector<TruePose> true_poses(const Truth& truth, int reference_id) {
  return relative_poses(truth, reference_id, truth.frame_yaw, truth.frame_origin);
}

std::vector<TruePose> true_poses_in_round(const Truth& truth, int reference_id, int round) {
  if (round < 0 || static_cast<std::size_t>(round) >= truth.drifted_yaw.size() ||
      truth.drifted_origin.size() != truth.drifted_yaw.size())
    throw std::invalid_argument("true_poses_in_round: round " + std::to_string(round) + " is not in the truth (" +
                                std::to_string(truth.drifted_yaw.size()) + " rounds)");
  return relative_poses(truth, reference_id, truth.drifted_yaw[round], truth.drifted_origin[round]);
}

}  // namespace fact
