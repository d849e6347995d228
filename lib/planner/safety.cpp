// Obstacle safety: inflated pieces, libccd GJK + EPA penetration, push-out, trajectory checks
// (fact/planner.h).
#include "fact/planner.h"

#include <ccd/ccd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace fact {

namespace {

// The rounded box box ⊕ sphere(radius) as libccd sees it.
struct RoundedBox {
  Eigen::Vector3d center;  // m, f_i
  Eigen::Vector3d half;    // m, half edge lengths of the (uninflated) box
  double radius;           // m, the inflation
};

struct PointShape {
  Eigen::Vector3d p;
};

// Support of a rounded box in direction d: the box's farthest corner plus radius · d/|d|.
void support_rounded_box(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
  const RoundedBox* b = static_cast<const RoundedBox*>(obj);
  const Eigen::Vector3d d(ccdVec3X(dir), ccdVec3Y(dir), ccdVec3Z(dir));
  Eigen::Vector3d s = b->center;
  for (int k = 0; k < 3; ++k) s[k] += d[k] >= 0 ? b->half[k] : -b->half[k];
  const double n = d.norm();
  if (n > 0) s += b->radius * d / n;
  ccdVec3Set(out, s.x(), s.y(), s.z());
}

void support_point(const void* obj, const ccd_vec3_t* /*dir*/, ccd_vec3_t* out) {
  const PointShape* p = static_cast<const PointShape*>(obj);
  ccdVec3Set(out, p->p.x(), p->p.y(), p->p.z());
}

std::string fmt_point(const Eigen::Vector3d& p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.2f, %.2f, %.2f)", p.x(), p.y(), p.z());
  return buf;
}

}  // namespace

double obstacle_inflation(const PlannerParams& p) { return p.drone_radius + p.obstacle_margin; }

bool inside_inflated(const ObstacleBox& box, double inflation, const Eigen::Vector3d& p) {
  return box_distance(box, p) < inflation;
}

namespace {

// One libccd GJK + EPA run: point q against the rounded box. rc 0: *depth, *dir set.
int ccd_penetration(const RoundedBox& rb, const Eigen::Vector3d& q, double* depth, Eigen::Vector3d* dir) {
  PointShape pt{q};
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = support_rounded_box;
  ccd.support2 = support_point;
  ccd.max_iterations = 500;
  ccd.epa_tolerance = 1e-6;
  ccd_real_t d = 0;
  ccd_vec3_t v, pos;
  // Penetration of obj2 (the point) into obj1 (the inflated piece): moving the point by d·v
  // brings it onto the surface.
  const int rc = ccdGJKPenetration(&rb, &pt, &ccd, &d, &v, &pos);
  if (rc != 0) return rc;
  const Eigen::Vector3d n(ccdVec3X(&v), ccdVec3Y(&v), ccdVec3Z(&v));
  if (!(n.norm() > 0) || !std::isfinite(d)) return -3;
  *depth = d;
  *dir = n / n.norm();
  return 0;
}

}  // namespace

bool penetration(const ObstacleBox& box, double inflation, const Eigen::Vector3d& p, double* depth,
                 Eigen::Vector3d* direction) {
  if (!inside_inflated(box, inflation, p)) return false;
  const RoundedBox rb{0.5 * (box.lo + box.hi), 0.5 * (box.hi - box.lo), inflation};
  // libccd's GJK can stop on a degenerate simplex when the point lies on a symmetry plane of the
  // box (it then reports a zero depth); the result is accepted only when p + depth·dir lands on the
  // inflated surface (within 2 mm), else it is re-run with the point nudged by 1 µm off the
  // symmetry planes. If that also fails, the exact nearest exit (through the nearest face for a
  // point inside the box, away from the nearest box point otherwise) is used.
  const Eigen::Vector3d nudges[] = {Eigen::Vector3d::Zero(), Eigen::Vector3d(0.57e-6, 0.81e-6, 0.13e-6),
                                    Eigen::Vector3d(-0.31e-6, 0.22e-6, -0.92e-6)};
  for (const Eigen::Vector3d& nudge : nudges) {
    double d = 0;
    Eigen::Vector3d n;
    if (ccd_penetration(rb, p + nudge, &d, &n) != 0) continue;
    if (std::abs(box_distance(box, p + d * n) - inflation) > 2e-3) continue;
    *depth = d;
    *direction = n;
    return true;
  }
  const Eigen::Vector3d c = rb.center, h = rb.half;
  const Eigen::Vector3d nearest = p.cwiseMax(box.lo).cwiseMin(box.hi);
  if ((p - nearest).norm() > 1e-9) {
    *direction = (p - nearest).normalized();
    *depth = inflation - (p - nearest).norm();
  } else {
    int axis = 0;
    (h.array() - (p - c).cwiseAbs().array()).minCoeff(&axis);
    *direction = Eigen::Vector3d::Zero();
    (*direction)[axis] = p[axis] >= c[axis] ? 1.0 : -1.0;
    *depth = h[axis] - std::abs(p[axis] - c[axis]) + inflation;
  }
  return true;
}

bool push_out(const Eigen::Vector3d& target, const std::vector<ObstacleBox>& pieces, const PlannerParams& p,
              Eigen::Vector3d* out, int* pushes) {
  const double infl = obstacle_inflation(p);
  // Working set: the pieces, where pieces that the point bounces between are replaced by their
  // bounding box. Two pieces whose inflations both hold the point after a push leave a gap too
  // narrow to fly through (< 2 inflations) around it, so treating them as one convex piece gives
  // up no usable space near the point and ends the ping-pong.
  std::vector<ObstacleBox> work = pieces;
  std::vector<int> pushed_from;  // indices into work, in push order
  Eigen::Vector3d q = target;
  int n = 0;
  const int max_pushes = std::max(1, p.push_tries) * 4;
  for (int k = 0; k < max_pushes; ++k) {
    int hit = -1;
    for (size_t i = 0; i < work.size(); ++i)
      if (inside_inflated(work[i], infl, q)) {
        hit = static_cast<int>(i);
        break;
      }
    if (hit < 0) break;
    // A piece pushed from before: merge it with every piece pushed from since then.
    const auto again = std::find(pushed_from.begin(), pushed_from.end(), hit);
    if (again != pushed_from.end()) {
      ObstacleBox m = work[hit];
      for (auto it = again; it != pushed_from.end(); ++it) {
        m.lo = m.lo.cwiseMin(work[*it].lo);
        m.hi = m.hi.cwiseMax(work[*it].hi);
      }
      work.push_back(m);
      hit = static_cast<int>(work.size()) - 1;
      pushed_from.clear();
    }
    const ObstacleBox& b = work[hit];
    double depth = 0;
    Eigen::Vector3d dir;
    if (!penetration(b, infl, q, &depth, &dir)) continue;
    q += (depth + p.push_epsilon) * dir;
    pushed_from.push_back(hit);
    ++n;
  }
  if (pushes) *pushes = n;
  for (const ObstacleBox& b : work)
    if (inside_inflated(b, infl, q)) return false;
  *out = q;
  return true;
}

std::string check_trajectory(const Trajectory& tr, const std::vector<ObstacleBox>& pieces,
                             const std::vector<Eigen::Vector3d>& drones, const Eigen::Vector3d& ball_center,
                             double ball_radius, const PlannerParams& p) {
  const std::vector<Eigen::Vector3d> pts = path_points(tr, p.check_spacing);
  const double infl = obstacle_inflation(p);
  // Only the pieces near the path's bounding box matter.
  Eigen::Vector3d lo = pts.front(), hi = pts.front();
  for (const Eigen::Vector3d& q : pts) {
    if (!q.allFinite()) return "path point is not finite";
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  lo.array() -= infl;
  hi.array() += infl;
  std::vector<int> near;
  for (size_t i = 0; i < pieces.size(); ++i)
    if ((pieces[i].lo.array() <= hi.array()).all() && (pieces[i].hi.array() >= lo.array()).all())
      near.push_back(static_cast<int>(i));
  // A path starting inside a piece's inflation (the map's voxels reach up to one voxel past a
  // surface, so a drone hovering near an obstacle can be) may leave it but never come closer to
  // that piece than it starts: the bound for piece i is min(inflation, its distance at the start).
  std::vector<double> bound(near.size());
  for (size_t n = 0; n < near.size(); ++n) bound[n] = std::min(infl, box_distance(pieces[near[n]], pts.front()) - 1e-9);
  for (size_t k = 0; k < pts.size(); ++k) {
    const Eigen::Vector3d& q = pts[k];
    if (std::isfinite(ball_radius) && (q - ball_center).norm() > ball_radius + 1e-3) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.2f m", (q - ball_center).norm());
      return "path point " + std::to_string(k) + " at " + fmt_point(q) + " leaves the max-move ball (" + buf +
             " from the start)";
    }
    for (size_t n = 0; n < near.size(); ++n) {
      const double dist = box_distance(pieces[near[n]], q);
      if (dist < bound[n]) {
        char buf[128];
        std::snprintf(buf, sizeof buf, " is %.2f m from obstacle piece %d (inflation %.2f m%s)", dist, near[n], infl,
                      bound[n] < infl ? ", started inside it" : "");
        return "path point " + std::to_string(k) + " at " + fmt_point(q) + buf;
      }
    }
    for (size_t j = 0; j < drones.size(); ++j) {
      const double dist = (drones[j] - q).norm();
      if (dist < p.min_separation) {
        char buf[96];
        std::snprintf(buf, sizeof buf, " is %.2f m from drone %zu (min_separation %.2f m)", dist, j, p.min_separation);
        return "path point " + std::to_string(k) + " at " + fmt_point(q) + buf;
      }
    }
  }
  return "";
}

}  // namespace fact
