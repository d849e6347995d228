// The simulated world's geometry: obstacles (boxes and polytopes as half-space solids, vertical
// cylinders), ray intersection, distances, random drone placement and the default world.
#include "fact/sim_world.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>

namespace fact::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;

bool finite3(const Eigen::Vector3d& v) { return v.allFinite(); }

std::string num(double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

// Box corners (8 × world points) of a box with its own axes rotated by yaw about z.
std::vector<Eigen::Vector3d> box_corners(const Eigen::Vector3d& c, const Eigen::Vector3d& size, double yaw) {
  Eigen::Matrix3d R = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i < 8; ++i) {
    Eigen::Vector3d s((i & 1) ? 0.5 : -0.5, (i & 2) ? 0.5 : -0.5, (i & 4) ? 0.5 : -0.5);
    out.push_back(c + R * s.cwiseProduct(size));
  }
  return out;
}

void set_bounds(ConvexSolid* s, const std::vector<Eigen::Vector3d>& pts) {
  s->box_min = Eigen::Vector3d::Constant(kInf);
  s->box_max = Eigen::Vector3d::Constant(-kInf);
  for (const auto& p : pts) {
    s->box_min = s->box_min.cwiseMin(p);
    s->box_max = s->box_max.cwiseMax(p);
  }
}

// Cyrus–Beck clipping of a ray against half-spaces n·x ≤ d.
bool intersect_solid(const ConvexSolid& s, const Ray& r, double t_min, double t_max, Hit* hit) {
  double t_in = -kInf, t_out = kInf;
  Eigen::Vector3d n_in = Eigen::Vector3d::UnitZ(), n_out = Eigen::Vector3d::UnitZ();
  for (const auto& pl : s.planes) {
    Eigen::Vector3d n = pl.head<3>();
    double denom = n.dot(r.direction);
    double gap = pl[3] - n.dot(r.origin);  // ≥ 0: origin inside this half-space
    if (std::abs(denom) < 1e-15) {
      if (gap < 0) return false;
      continue;
    }
    double t = gap / denom;
    if (denom < 0) {
      if (t > t_in) { t_in = t; n_in = n; }
    } else {
      if (t < t_out) { t_out = t; n_out = n; }
    }
    if (t_in > t_out) return false;
  }
  if (t_in > t_min && t_in < t_max) {
    hit->t = t_in;
    hit->normal = n_in;
    return true;
  }
  if (t_in <= t_min && t_out > t_min && t_out < t_max) {
    hit->t = t_out;
    hit->normal = -n_out;
    return true;
  }
  return false;
}

// Vertical cylinder: side roots and the two caps; the nearest t ∈ (t_min, t_max).
bool intersect_cylinder(const Cylinder& c, const Ray& r, double t_min, double t_max, Hit* hit) {
  const double ox = r.origin.x() - c.base.x(), oy = r.origin.y() - c.base.y();
  const double dx = r.direction.x(), dy = r.direction.y();
  const double z0 = c.base.z(), z1 = c.base.z() + c.height;
  double best = t_max;
  Eigen::Vector3d normal;
  bool found = false;
  const double a = dx * dx + dy * dy;
  if (a > 1e-18) {
    const double b = ox * dx + oy * dy;
    const double cc = ox * ox + oy * oy - c.radius * c.radius;
    const double disc = b * b - a * cc;
    if (disc >= 0) {
      const double sq = std::sqrt(disc);
      for (double t : {(-b - sq) / a, (-b + sq) / a}) {
        if (t <= t_min || t >= best) continue;
        double z = r.origin.z() + t * r.direction.z();
        if (z < z0 || z > z1) continue;
        best = t;
        normal = Eigen::Vector3d(ox + t * dx, oy + t * dy, 0) / c.radius;
        found = true;
      }
    }
  }
  if (std::abs(r.direction.z()) > 1e-18) {
    for (double zc : {z0, z1}) {
      double t = (zc - r.origin.z()) / r.direction.z();
      if (t <= t_min || t >= best) continue;
      double x = ox + t * dx, y = oy + t * dy;
      if (x * x + y * y > c.radius * c.radius) continue;
      best = t;
      normal = Eigen::Vector3d(0, 0, zc == z1 ? 1 : -1);
      found = true;
    }
  }
  if (!found) return false;
  hit->t = best;
  hit->normal = normal;
  return true;
}

// Axis-aligned box centred at the origin with half extents h: slab test, nearest t ∈ (t_min, t_max).
bool intersect_aabb(const Eigen::Vector3d& h, const Ray& r, double t_min, double t_max, Hit* hit) {
  double t_in = -kInf, t_out = kInf;
  int ax_in = 2, ax_out = 2;
  for (int k = 0; k < 3; ++k) {
    double d = r.direction[k], o = r.origin[k];
    if (std::abs(d) < 1e-18) {
      if (o < -h[k] || o > h[k]) return false;
      continue;
    }
    double t0 = (-h[k] - o) / d, t1 = (h[k] - o) / d;
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > t_in) { t_in = t0; ax_in = k; }
    if (t1 < t_out) { t_out = t1; ax_out = k; }
    if (t_in > t_out) return false;
  }
  if (t_in > t_min && t_in < t_max) {
    hit->t = t_in;
    hit->normal = Eigen::Vector3d::Zero();
    hit->normal[ax_in] = r.direction[ax_in] > 0 ? -1 : 1;
    return true;
  }
  if (t_in <= t_min && t_out > t_min && t_out < t_max) {
    hit->t = t_out;
    hit->normal = Eigen::Vector3d::Zero();
    hit->normal[ax_out] = r.direction[ax_out] > 0 ? -1 : 1;
    return true;
  }
  return false;
}

}  // namespace

// ----------------------------------------------------------------------------------------------
// Obstacles

Obstacle make_box(const Eigen::Vector3d& center, const Eigen::Vector3d& size, double yaw) {
  Obstacle o;
  o.kind = ObstacleKind::box;
  o.center = center;
  o.size = size;
  o.yaw = yaw;
  const Eigen::Vector3d ax(std::cos(yaw), std::sin(yaw), 0), ay(-std::sin(yaw), std::cos(yaw), 0),
      az(0, 0, 1);
  const Eigen::Vector3d axes[3] = {ax, ay, az};
  for (int k = 0; k < 3; ++k) {
    for (double s : {1.0, -1.0}) {
      Eigen::Vector3d n = s * axes[k];
      o.solid.planes.emplace_back(n.x(), n.y(), n.z(), n.dot(center) + 0.5 * size[k]);
    }
  }
  set_bounds(&o.solid, box_corners(center, size, yaw));
  return o;
}

Obstacle make_cylinder(const Eigen::Vector3d& base, double radius, double height) {
  Obstacle o;
  o.kind = ObstacleKind::cylinder;
  o.cylinder = Cylinder{base, radius, height};
  o.center = base + Eigen::Vector3d(0, 0, 0.5 * height);
  return o;
}

Obstacle make_polytope(const std::vector<Eigen::Vector3d>& vertices, std::string* error) {
  Obstacle o;
  o.kind = ObstacleKind::polytope;
  o.vertices = vertices;
  const size_t n = vertices.size();
  auto fail = [&](const std::string& why) {
    if (error) *error = why;
    o.solid.planes.clear();
    return o;
  };
  if (n < 4) return fail("a polytope needs at least 4 vertices, got " + std::to_string(n));
  if (n > 64) return fail("a polytope has at most 64 vertices, got " + std::to_string(n));
  for (size_t i = 0; i < n; ++i)
    if (!finite3(vertices[i])) return fail("vertex " + std::to_string(i) + " is not finite");
  Eigen::Vector3d lo = vertices[0], hi = vertices[0];
  for (const auto& v : vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const double scale = std::max((hi - lo).norm(), 1e-9);
  const double tol = 1e-9 * scale;
  // Brute force hull: every vertex triple whose plane has all vertices on one side is a face.
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j)
      for (size_t k = j + 1; k < n; ++k) {
        Eigen::Vector3d nrm = (vertices[j] - vertices[i]).cross(vertices[k] - vertices[i]);
        double len = nrm.norm();
        if (len < 1e-12 * scale * scale) continue;
        nrm /= len;
        double d = nrm.dot(vertices[i]);
        int above = 0, below = 0;
        for (const auto& v : vertices) {
          double s = nrm.dot(v) - d;
          if (s > tol) ++above;
          if (s < -tol) ++below;
        }
        if (above > 0 && below > 0) continue;
        if (above == 0 && below == 0) continue;  // all coplanar
        if (above > 0) {
          nrm = -nrm;
          d = -d;
        }
        bool dup = false;
        for (const auto& pl : o.solid.planes)
          if ((pl.head<3>() - nrm).norm() < 1e-9 && std::abs(pl[3] - d) < tol) dup = true;
        if (!dup) o.solid.planes.emplace_back(nrm.x(), nrm.y(), nrm.z(), d);
      }
  if (o.solid.planes.size() < 4) return fail("the vertices span no volume (all coplanar)");
  set_bounds(&o.solid, vertices);
  o.center = 0.5 * (lo + hi);
  return o;
}

void obstacle_bounds(const Obstacle& o, Eigen::Vector3d* lo, Eigen::Vector3d* hi) {
  if (o.kind == ObstacleKind::cylinder) {
    const Cylinder& c = o.cylinder;
    *lo = c.base - Eigen::Vector3d(c.radius, c.radius, 0);
    *hi = c.base + Eigen::Vector3d(c.radius, c.radius, c.height);
    return;
  }
  *lo = o.solid.box_min;
  *hi = o.solid.box_max;
}

bool intersect(const Obstacle& o, const Ray& ray, double t_min, double t_max, Hit* hit) {
  if (o.kind == ObstacleKind::cylinder) return intersect_cylinder(o.cylinder, ray, t_min, t_max, hit);
  return intersect_solid(o.solid, ray, t_min, t_max, hit);
}

double distance(const Obstacle& o, const Eigen::Vector3d& p) {
  switch (o.kind) {
    case ObstacleKind::box: {
      Eigen::Vector3d q = Eigen::AngleAxisd(-o.yaw, Eigen::Vector3d::UnitZ()) * (p - o.center);
      Eigen::Vector3d out = (q.cwiseAbs() - 0.5 * o.size).cwiseMax(0.0);
      return out.norm();
    }
    case ObstacleKind::cylinder: {
      const Cylinder& c = o.cylinder;
      double dr = std::max(0.0, (p - c.base).head<2>().norm() - c.radius);
      double dz = std::max({0.0, c.base.z() - p.z(), p.z() - c.base.z() - c.height});
      return std::hypot(dr, dz);
    }
    case ObstacleKind::polytope: {
      double worst = 0;
      for (const auto& pl : o.solid.planes) worst = std::max(worst, pl.head<3>().dot(p) - pl[3]);
      return worst;
    }
  }
  return 0;
}

// ----------------------------------------------------------------------------------------------
// World, drones

Eigen::Vector3d room_min(const World& w) { return Eigen::Vector3d(-0.5 * w.room_size.x(), -0.5 * w.room_size.y(), 0); }
Eigen::Vector3d room_max(const World& w) { return Eigen::Vector3d(0.5 * w.room_size.x(), 0.5 * w.room_size.y(), w.room_size.z()); }

std::vector<int> drone_ids(const DroneConfig& c) {
  if (!c.ids.empty()) return c.ids;
  std::vector<int> ids;
  for (int i = 0; i < c.count; ++i) ids.push_back(i);
  return ids;
}

namespace {

// Whether a takeoff spot keeps `clearance` from walls and obstacles along its whole climb
// column (z from the spot to height_max) and `separation` (horizontal) from earlier spots.
bool spot_ok(const World& w, const Eigen::Vector3d& p, const std::vector<DroneStart>& placed, double separation) {
  const DroneConfig& c = w.drone_config;
  for (const auto& s : placed)
    if ((s.position - p).head<2>().norm() < separation) return false;
  const double top = std::max(c.height_max, p.z());
  for (double z = p.z(); z <= top + 1e-9; z += 0.25) {
    Eigen::Vector3d q(p.x(), p.y(), z);
    for (const auto& o : w.obstacles)
      if (distance(o, q) < c.clearance) return false;
    if (z >= top) break;
  }
  return true;
}

}  // namespace

std::string place_random_starts(World* w, uint64_t seed) {
  const DroneConfig& c = w->drone_config;
  std::vector<int> ids = drone_ids(c);
  std::mt19937_64 rng(seed);
  const Eigen::Vector3d lo = room_min(*w), hi = room_max(*w);
  // At least the body's radius from the walls, whatever clearance says (dynamics stops the centre
  // there: a start closer jumped to it on the first step).
  const double r = bounding_radius(DroneBody{});
  const double wall = std::max(c.clearance, r), separation = std::max(c.min_separation, 2 * r);
  if (hi.x() - lo.x() <= 2 * wall || hi.y() - lo.y() <= 2 * wall)
    return "room " + num(w->room_size.x()) + " x " + num(w->room_size.y()) + " m is too small for clearance " +
           num(wall) + " m";
  std::uniform_real_distribution<double> ux(lo.x() + wall, hi.x() - wall);
  std::uniform_real_distribution<double> uy(lo.y() + wall, hi.y() - wall);
  std::uniform_real_distribution<double> uyaw(-kPi, kPi);
  std::vector<DroneStart> placed;
  const int kTries = 20000;
  for (size_t i = 0; i < ids.size(); ++i) {
    bool ok = false;
    for (int t = 0; t < kTries && !ok; ++t) {
      // y, then x: the order x86-64 drew them in (constructor arguments have no fixed order;
      // GCC on aarch64 took x first, so the same seed placed other starts there).
      const double y = uy(rng);
      const double x = ux(rng);
      const Eigen::Vector3d p(x, y, 0.0);
      if (!spot_ok(*w, p, placed, separation)) continue;
      placed.push_back(DroneStart{ids[i], p, uyaw(rng)});
      ok = true;
    }
    if (!ok)
      return "could not place drone " + std::to_string(i + 1) + " of " + std::to_string(ids.size()) + " after " +
             std::to_string(kTries) + " tries: room too small for min_separation " + num(c.min_separation) +
             " m and clearance " + num(c.clearance) + " m";
  }
  w->starts = placed;
  return "";
}

std::string starts_error(const World& w) {
  std::set<int> seen;
  const Eigen::Vector3d lo = room_min(w), hi = room_max(w);
  const double r = bounding_radius(DroneBody{});  // the body must fit where it starts
  for (size_t i = 0; i < w.starts.size(); ++i) {
    const DroneStart& s = w.starts[i];
    const std::string where = "start " + std::to_string(i) + " (drone " + std::to_string(s.id) + ")";
    if (s.id < 0) return where + ": id " + std::to_string(s.id) + " is negative";
    if (!seen.insert(s.id).second) return where + ": id " + std::to_string(s.id) + " appears twice";
    if (!finite3(s.position) || !std::isfinite(s.yaw)) return where + ": position or yaw not finite";
    for (int k = 0; k < 3; ++k)
      if (s.position[k] < lo[k] || s.position[k] > hi[k])
        return where + ": position[" + std::to_string(k) + "] = " + num(s.position[k]) + " is outside the room [" +
               num(lo[k]) + ", " + num(hi[k]) + "]";
    // The body must fit where it starts: the drone's radius from the walls and the ceiling (where
    // dynamics stops its centre), clear of every obstacle and of the drones before it (two drones
    // on one spot, or one inside a box, flew without complaint).
    for (int k = 0; k < 3; ++k)
      if ((k < 2 && s.position[k] < lo[k] + r) || s.position[k] > hi[k] - r)
        return where + ": position[" + std::to_string(k) + "] = " + num(s.position[k]) + " is closer than the drone's radius " +
               num(r) + " m to the " + (k < 2 ? "wall" : "ceiling") + " (keep it within [" + num(k < 2 ? lo[k] + r : lo[k]) +
               ", " + num(hi[k] - r) + "])";
    for (size_t j = 0; j < w.obstacles.size(); ++j)
      if (distance(w.obstacles[j], s.position) < r)
        return where + ": position (" + num(s.position.x()) + ", " + num(s.position.y()) + ", " + num(s.position.z()) +
               ") is " + num(distance(w.obstacles[j], s.position)) + " m from obstacle " + std::to_string(j) +
               ", closer than the drone's radius " + num(r) + " m";
    for (size_t j = 0; j < i; ++j)
      if ((w.starts[j].position - s.position).norm() < 2 * r)
        return where + ": " + num((w.starts[j].position - s.position).norm()) + " m from start " + std::to_string(j) +
               " (drone " + std::to_string(w.starts[j].id) + "), closer than two drones' radii " + num(2 * r) + " m";
  }
  // Every drone's hover height, which counts from its takeoff spot, must fit under the ceiling,
  // whether the file gave the range or not (a start on a box put its hover height out of reach:
  // the drone sat at the ceiling and never counted as airborne; review, session 33).
  const DroneConfig& c = w.drone_config;
  for (size_t i = 0; i < w.starts.size(); ++i)
    if (w.starts[i].position.z() + c.height_max > w.room_size.z() - r)
      return "start " + std::to_string(i) + " (drone " + std::to_string(w.starts[i].id) + "): takeoff at z = " +
             num(w.starts[i].position.z()) + " m plus drones.height max " + num(c.height_max) +
             " m is above the ceiling " + num(w.room_size.z()) +
             " m less the drone's radius (set drones.height, a lower start or a higher room)";
  if (c.height_max > w.room_size.z() - r)  // (random starts, placed later on the floor)
    return "drones.height max " + num(c.height_max) + " m is above the ceiling " + num(w.room_size.z()) +
           " m less the drone's radius (set drones.height or a higher room)";
  return "";
}

World default_world(int drones, uint64_t seed) {
  World w;
  w.room_size = Eigen::Vector3d(10, 10, 4);
  w.obstacles.push_back(make_box(Eigen::Vector3d(2.0, 1.5, 0.75), Eigen::Vector3d(1.0, 0.6, 1.5), 0.4));
  w.obstacles.push_back(make_cylinder(Eigen::Vector3d(-2.0, 2.0, 0.0), 0.3, 2.5));
  std::string err;
  w.obstacles.push_back(make_polytope({{-2.5, -2.5, 0.0}, {-1.5, -2.5, 0.0}, {-1.5, -1.5, 0.0}, {-2.5, -1.5, 0.0},
                                       {-2.25, -2.25, 1.2}, {-1.75, -2.25, 1.2}, {-1.75, -1.75, 1.2}, {-2.25, -1.75, 1.2}},
                                      &err));
  w.drone_config.count = drones;
  w.drone_config.random_start = true;
  w.drone_config.seed = seed;
  w.drone_config.seed_given = false;
  place_random_starts(&w, seed);
  return w;
}

// ----------------------------------------------------------------------------------------------
// The drone body

std::vector<BodyPart> body_parts(const DroneBody& b) {
  std::vector<BodyPart> parts;
  BodyPart hub;
  hub.size = b.hub_size;
  parts.push_back(hub);
  for (int k = 0; k < 4; ++k) {
    const double ang = kPi / 4 + k * kPi / 2;  // 45°, 135°, 225°, 315°
    const Eigen::Vector3d dir(std::cos(ang), std::sin(ang), 0);
    BodyPart arm;
    arm.center = 0.5 * b.rotor_distance * dir + Eigen::Vector3d(0, 0, 0.5 * b.rotor_z);
    arm.size = Eigen::Vector3d(b.rotor_distance, b.arm_width, b.arm_height);
    arm.yaw = ang;
    parts.push_back(arm);
    BodyPart rotor;
    rotor.is_cylinder = true;
    rotor.center = b.rotor_distance * dir + Eigen::Vector3d(0, 0, b.rotor_z);
    rotor.radius = b.rotor_radius;
    rotor.height = b.rotor_height;
    parts.push_back(rotor);
  }
  return parts;
}

double bounding_radius(const DroneBody& b) {
  double r = 0;
  for (const auto& p : body_parts(b)) {
    if (p.is_cylinder) {
      r = std::max(r, std::hypot(p.center.head<2>().norm() + p.radius, std::abs(p.center.z()) + 0.5 * p.height));
    } else {
      for (const auto& c : box_corners(p.center, p.size, p.yaw)) r = std::max(r, c.norm());
    }
  }
  return r;
}

bool intersect_body(const std::vector<BodyPart>& parts, const Ray& ray_b, double t_min, double t_max, Hit* hit) {
  bool found = false;
  double best = t_max;
  for (const auto& p : parts) {
    Hit h;
    bool ok;
    if (p.is_cylinder) {
      Cylinder c{p.center - Eigen::Vector3d(0, 0, 0.5 * p.height), p.radius, p.height};
      ok = intersect_cylinder(c, ray_b, t_min, best, &h);
    } else {
      // Into the part's frame: rotate by −yaw about z, centre at the origin.
      const double cy = std::cos(p.yaw), sy = std::sin(p.yaw);
      Eigen::Vector3d o = ray_b.origin - p.center, d = ray_b.direction;
      Ray local{Eigen::Vector3d(cy * o.x() + sy * o.y(), -sy * o.x() + cy * o.y(), o.z()),
                Eigen::Vector3d(cy * d.x() + sy * d.y(), -sy * d.x() + cy * d.y(), d.z())};
      ok = intersect_aabb(0.5 * p.size, local, t_min, best, &h);
      if (ok) h.normal = Eigen::Vector3d(cy * h.normal.x() - sy * h.normal.y(), sy * h.normal.x() + cy * h.normal.y(), h.normal.z());
    }
    if (ok) {
      best = h.t;
      *hit = h;
      found = true;
    }
  }
  return found;
}

}  // namespace fact::sim
