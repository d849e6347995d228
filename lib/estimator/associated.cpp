// Mode associated: yaw-invariant association of mutual pairs.
//
// 1. Hypotheses. For drones i, j and a round, a detection a of i and b of j may be the mutual pair
//    "i sees j, j sees i" only if |v_a| ≈ |v_b| and v_a,z ≈ −v_b,z (neither depends on yaw; each
//    gated with its own σ from the detections' covariances). Each such pair fixes the pose of f_j
//    in f_i: x_i = R(θ) x_j + t.
// 2. Verification. Under a hypothesis, j's points (its positions and detections, every round) are
//    mapped into f_i and matched to i's points by mutual nearest neighbour in Mahalanobis distance
//    within the gate; each match scores its log-likelihood ratio against clutter. The pose is
//    refined by weighted Procrustes on the matches and they are scored again. A pair of drones
//    becomes an edge when its best hypothesis has ≥ kMinEvidence matches, a score ≥ kMinScore and
//    beats every distinct hypothesis (one sharing under half its matches) by ≥ kMinScoreMargin;
//    otherwise it is weak or ambiguous (a rotation-symmetric formation explains several poses
//    equally well).
// 3. Assembly. Edges join clusters strongest first; an edge that would put two drones closer than
//    min_separation in some round is dropped (one of its detections belongs to another drone).
//    A drone whose every pair is too weak joins a cluster when one pose of it explains its points
//    against all the members at once, with the pair's thresholds (join_weak).
// 4. Rotations by certified synchronisation (the SO(2) connection-Laplacian SDP, d = 2, which has
//    the complex form's structure) over the edges connected to the reference, weighted by each
//    edge's yaw information; edges that disagree with the synchronised yaws are dropped.
// 5. Translations by least squares over every verified correspondence of every round, then the
//    checks: no two drones in one place, every pose precise enough and in agreement with its
//    detections (estimate.cpp: precision_problem).
#include "internal.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

namespace fact::estimator {
namespace {

using Clock = std::chrono::steady_clock;
double micros(Clock::time_point a) { return std::chrono::duration<double, std::micro>(Clock::now() - a).count(); }

constexpr int kMinEvidence = 4;   // matched points an edge needs: its defining pair and 2 more
constexpr double kMinHorizontal = 0.1;  // m: shorter horizontal vectors say nothing about yaw
constexpr double kMinScoreMargin = 15;  // log-likelihood ratio by which the best pose must beat any other
// Log-likelihood ratio of the best pose against clutter. 30 until 2026-11-25; 20 certifies in
// fewer rounds (field model, N = 4: 1.12 rounds instead of 1.92) with no wrong result in 2500
// heavy-clutter sessions (3 false positives per drone per round); at 10 the first wrong one
// appears (test Estimator.HeavyClutterNeverCertifiesWrongAsRoundsAccumulate).
constexpr double kMinScore = 20;
// Density of points no hypothesis explains (clutter): one per this many m³. A match at normalised
// distance d² with combined σ scores log(V) − 1.5 log(2πσ²) − d²/2 against clutter.
constexpr double kClutterVolume = 10;

// Pose of f_j in f_i: x_i = R(yaw) x_j + t.
struct RelativePose {
  double yaw = 0;
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Vector3d map(const Eigen::Vector3d& x) const { return yaw_rotation(yaw) * x + t; }
};

// A point drone i knows in round k, in f_i: its own position (det = −1) or a detected centre.
struct Point {
  Eigen::Vector3d x;
  Eigen::Matrix3d cov;  // m², in the drone's frame
  double sigma;         // largest σ (m)
  int det;
};

// points[k][i]: the points of drone i in round k (empty when it did not report).
using PointSets = std::vector<std::vector<std::vector<Point>>>;

std::vector<Point> points_of(const DroneView& v, double odometry_sigma) {
  const double own = std::max(odometry_sigma, 1e-3);
  std::vector<Point> out{{v.position, own * own * Eigen::Matrix3d::Identity(), own, -1}};
  for (size_t a = 0; a < v.detections.size(); ++a)
    out.push_back({v.detections[a].target, v.detections[a].cov, v.detections[a].sigma, static_cast<int>(a)});
  return out;
}

// Which two points a match joins: round k, point of i, point of j (−1 = the drone's own position).
// Its log-likelihood ratio (inlier against clutter) rides along; equality is the points only.
struct Link {
  int round, det_i, det_j;
  double score = 0;
  bool operator==(const Link& o) const { return round == o.round && det_i == o.det_i && det_j == o.det_j; }
};

struct Hypothesis {
  int round = 0, a = 0, b = 0;            // defining pair: detection a of i, b of j
  RelativePose pose;
  double yaw_sigma = 0;                   // rad, σ of pose.yaw
  std::vector<Link> links;                // verified matches, all rounds: which points each joins
  double score = 0;                       // Σ log-likelihood ratio of the matches (inlier vs clutter)
  int evidence() const { return static_cast<int>(links.size()); }
};

// Mutual-nearest-neighbour matches of j's points (mapped by pose) to i's points, every round.
// spread(x) adds the pose's own uncertainty (m) at a mapped point x.
template <class Spread>
void verify(const Problem& p, const PointSets& points, int i, int j, const RelativePose& pose, Spread spread,
            Hypothesis* h) {
  h->links.clear();
  h->score = 0;
  const double gate2 = p.noise.gate * p.noise.gate;
  for (int k = 0; k < p.rounds(); ++k) {
    const DroneView &vi = p.views[k][i], &vj = p.views[k][j];
    if (!vi.present || !vj.present) continue;
    const std::vector<Point>&A = points[k][i], &B = points[k][j];
    const Eigen::Matrix3d R = yaw_rotation(pose.yaw);
    thread_local std::vector<Eigen::Vector3d> mapped;
    thread_local std::vector<Eigen::Matrix3d> mapped_cov;  // j's covariances in f_i axes, made when first needed
    thread_local std::vector<char> have_cov;
    thread_local std::vector<double> spread2;  // spread(mapped[b])², once per point of j (not per pairing)
    mapped.clear();
    spread2.clear();
    for (const Point& b : B) {
      mapped.push_back(R * b.x + pose.t);
      const double s = spread(mapped.back());
      spread2.push_back(s * s);
    }
    mapped_cov.resize(B.size());
    have_cov.assign(B.size(), 0);
    // Normalised squared distance and log-likelihood ratio (inlier against clutter) of every
    // admissible pairing; own position ↔ own position is not a pairing.
    const size_t nb = B.size();
    // r Σ⁻¹ r ≥ |r|² / λ_max(Σ): most pairs fail the gate on this bound alone. The bound is
    // tested first for every pairing, over plain arrays of j's mapped points.
    thread_local std::vector<double> mx, my, mz, b_var;
    thread_local std::vector<unsigned char> near;
    mx.resize(nb), my.resize(nb), mz.resize(nb), b_var.resize(nb), near.resize(A.size() * nb);
    for (size_t b = 0; b < nb; ++b)
      mx[b] = mapped[b].x(), my[b] = mapped[b].y(), mz[b] = mapped[b].z(), b_var[b] = B[b].sigma * B[b].sigma;
    for (size_t a = 0; a < A.size(); ++a) {
      const double ax = A[a].x.x(), ay = A[a].x.y(), az = A[a].x.z(), a_var = A[a].sigma * A[a].sigma;
      unsigned char* row = near.data() + a * nb;
      for (size_t b = 0; b < nb; ++b) {
        const double dx = ax - mx[b], dy = ay - my[b], dz = az - mz[b];
        row[b] = dx * dx + dy * dy + dz * dz <= gate2 * (a_var + b_var[b] + spread2[b]);
      }
    }
    // Mutual nearest neighbours by d²: each point's nearest admissible partner, updated as the
    // pairings are scored (in the order a, then b: ties go to the first).
    thread_local std::vector<int> best_b, best_a;
    thread_local std::vector<double> cost_b, cost_a, det_b;  // det_b[a]: det(S) of a's nearest pairing
    best_b.assign(A.size(), -1), best_a.assign(B.size(), -1);
    cost_b.assign(A.size(), INFINITY), cost_a.assign(B.size(), INFINITY), det_b.resize(A.size());
    for (size_t a = 0; a < A.size(); ++a)
      for (size_t b = 0; b < nb; ++b) {
        if (!near[a * nb + b] || (A[a].det < 0 && B[b].det < 0)) continue;
        const Eigen::Vector3d r = A[a].x - mapped[b];
        if (!have_cov[b]) mapped_cov[b] = R * B[b].cov * R.transpose(), have_cov[b] = 1;
        const Eigen::Matrix3d S = A[a].cov + mapped_cov[b] + spread2[b] * Eigen::Matrix3d::Identity();
        // S⁻¹ = adj(S) / det(S) by cofactors (S symmetric positive definite, 3 × 3).
        const double c00 = S(1, 1) * S(2, 2) - S(1, 2) * S(1, 2), c01 = S(0, 2) * S(1, 2) - S(0, 1) * S(2, 2),
                     c02 = S(0, 1) * S(1, 2) - S(0, 2) * S(1, 1), c11 = S(0, 0) * S(2, 2) - S(0, 2) * S(0, 2),
                     c12 = S(0, 1) * S(0, 2) - S(0, 0) * S(1, 2), c22 = S(0, 0) * S(1, 1) - S(0, 1) * S(0, 1);
        const double det = S(0, 0) * c00 + S(0, 1) * c01 + S(0, 2) * c02;
        const double q = r.x() * (c00 * r.x() + 2 * (c01 * r.y() + c02 * r.z())) +
                         r.y() * (c11 * r.y() + 2 * c12 * r.z()) + r.z() * c22 * r.z();
        const double c = q / det;
        if (c < cost_b[a]) cost_b[a] = c, best_b[a] = static_cast<int>(b), det_b[a] = det;
        if (c < cost_a[b]) cost_a[b] = c, best_a[b] = static_cast<int>(a);
      }
    for (size_t a = 0; a < A.size(); ++a) {
      const int b = best_b[a];
      if (b < 0 || best_a[b] != static_cast<int>(a) || cost_b[a] > gate2) continue;
      // log-likelihood ratio of inlier against clutter: log V − ½ log det(2πS) − ½ d²
      const double evidence = std::log(kClutterVolume) - 1.5 * std::log(2 * M_PI) -
                              0.5 * std::log(det_b[a]) - 0.5 * cost_b[a];
      if (evidence <= 0) continue;
      h->score += evidence;
      h->links.push_back({k, A[a].det, B[b].det, evidence});
    }
  }
}

// The point pairs that links join: x_i in f_i, x_j in f_j, with their covariances.
std::vector<Correspondence> correspondences(const PointSets& points, int i, int j, const std::vector<Link>& links) {
  std::vector<Correspondence> out;
  out.reserve(links.size());
  for (const Link& l : links) {
    const Point& a = points[l.round][i][l.det_i + 1];  // index 0 is the own position (det −1)
    const Point& b = points[l.round][j][l.det_j + 1];
    out.push_back({i, j, a.x, b.x, std::hypot(a.sigma, b.sigma), a.cov, b.cov});
  }
  return out;
}

// Weighted Procrustes for a yaw and a 3-D translation: min Σ w ‖x_i − R(θ) x_j − t‖².
// Also returns σ of θ from its information Σ w |q_xy|² (q: x_j about its weighted centroid) and,
// if asked, that centroid mapped into f_i (the point the yaw error turns about).
RelativePose procrustes(const std::vector<Correspondence>& cs, double* yaw_sigma, Eigen::Vector3d* pivot = nullptr) {
  Eigen::Vector3d mi = Eigen::Vector3d::Zero(), mj = Eigen::Vector3d::Zero();
  double wsum = 0;
  for (const Correspondence& c : cs) {
    const double w = 1.0 / (c.sigma * c.sigma);
    mi += w * c.x_i, mj += w * c.x_j, wsum += w;
  }
  mi /= wsum, mj /= wsum;
  double dot = 0, cross = 0, info = 0;
  for (const Correspondence& c : cs) {
    const double w = 1.0 / (c.sigma * c.sigma);
    const Eigen::Vector2d pi = (c.x_i - mi).head<2>(), qj = (c.x_j - mj).head<2>();
    dot += w * qj.dot(pi);
    cross += w * (qj.x() * pi.y() - qj.y() * pi.x());
    info += w * qj.squaredNorm();
  }
  RelativePose pose;
  pose.yaw = std::atan2(cross, dot);
  pose.t = mi - yaw_rotation(pose.yaw) * mj;
  *yaw_sigma = info > 0 ? 1.0 / std::sqrt(info) : INFINITY;
  if (pivot) *pivot = mi;
  return pose;
}

// The pose a candidate mutual pair implies, or false when the gates reject it.
bool pair_pose(const Problem& p, const Detection& da, const Detection& db, RelativePose* pose, double* yaw_sigma) {
  // σ of the range (along the ray) and of the height difference (z), from each covariance.
  const Eigen::Vector3d ua3 = da.direction / da.range, ub3 = db.direction / db.range;
  const double range_sd = std::sqrt(ua3.dot(da.cov * ua3) + ub3.dot(db.cov * ub3));
  const double z_sd = std::sqrt(da.cov(2, 2) + db.cov(2, 2));
  if (std::abs(da.range - db.range) > p.noise.gate * range_sd) return false;
  if (std::abs(da.body.z() + db.body.z()) > p.noise.gate * z_sd) return false;
  // Yaw σ of the pair: the across-ray errors of both ends over the horizontal length.
  const double across = 0.5 * (da.cov.trace() - ua3.dot(da.cov * ua3) + db.cov.trace() - ub3.dot(db.cov * ub3));
  const double s = std::sqrt(across);
  const Eigen::Vector2d ua = da.direction.head<2>(), ub = db.direction.head<2>();
  if (ua.norm() < kMinHorizontal || ub.norm() < kMinHorizontal) return false;
  pose->yaw = wrap_angle(std::atan2(ua.y(), ua.x()) - std::atan2(-ub.y(), -ub.x()));
  const Eigen::Matrix3d R = yaw_rotation(pose->yaw);
  pose->t = 0.5 * ((da.target - R * db.observer) + (da.observer - R * db.target));
  *yaw_sigma = s / std::min(ua.norm(), ub.norm());
  return true;
}

// True when hypothesis g matched the mutual pair (detection a of i, b of j) of round k: i's
// detection a to j's position and i's position to j's detection b.
bool explains(const Hypothesis& g, int k, int a, int b) {
  const auto has = [&](const Link& l) { return std::find(g.links.begin(), g.links.end(), l) != g.links.end(); };
  return has(Link{k, a, -1}) && has(Link{k, -1, b});
}

// Every gated mutual pair of drones i and j, verified in two passes (loose, then refined).
// A pair that an already verified hypothesis explains would only find it again and is skipped.
std::vector<Hypothesis> hypotheses(const Problem& p, const PointSets& points, int i, int j) {
  std::vector<Hypothesis> out;
  for (int k = 0; k < p.rounds(); ++k) {
    const DroneView &vi = p.views[k][i], &vj = p.views[k][j];
    if (!vi.present || !vj.present) continue;
    for (size_t a = 0; a < vi.detections.size(); ++a)
      for (size_t b = 0; b < vj.detections.size(); ++b) {
        Hypothesis h;
        h.round = k, h.a = static_cast<int>(a), h.b = static_cast<int>(b);
        if (!pair_pose(p, vi.detections[a], vj.detections[b], &h.pose, &h.yaw_sigma)) continue;
        const auto known = [&](const Hypothesis& g) { return explains(g, k, h.a, h.b); };
        if (std::any_of(out.begin(), out.end(), known)) continue;
        const Eigen::Vector3d anchor = vi.detections[a].observer;
        // Two passes: loose around the pair's own pose, then around the refined one. Fewer than
        // kMinEvidence matches cannot make an edge; such a hypothesis stays as a possible rival.
        for (int pass = 0; pass < 2; ++pass) {
          const double ys = h.yaw_sigma;
          const RelativePose pose = h.pose;
          verify(p, points, i, j, pose, [&](const Eigen::Vector3d& x) { return ys * (x - anchor).norm(); }, &h);
          if (h.evidence() < kMinEvidence) break;
          h.pose = procrustes(correspondences(points, i, j, h.links), &h.yaw_sigma);
        }
        if (h.evidence() >= 2) out.push_back(std::move(h));
      }
  }
  return out;
}

// Two hypotheses are distinct poses when they share under half of the smaller one's matches.
bool distinct(const Hypothesis& x, const Hypothesis& y) {
  int shared = 0;
  for (const Link& l : y.links) shared += std::find(x.links.begin(), x.links.end(), l) != x.links.end();
  return 2 * shared < static_cast<int>(std::min(x.links.size(), y.links.size()));
}

enum class EdgeKind { none, weak, ambiguous, accepted };

struct Edge {
  int i = 0, j = 0;
  EdgeKind kind = EdgeKind::none;
  int evidence = 0, rival = 0;  // matches of the best and of the best distinct hypothesis
  double rival_score = 0;       // score of the best distinct hypothesis (0: none)
  Hypothesis best;
  std::vector<Hypothesis> hypotheses;  // every verified hypothesis of a weak or ambiguous pair, best first
  bool dropped = false;         // rejected by the global consistency checks
};

Edge judge_pair(const Problem& p, const PointSets& points, int i, int j) {
  Edge e;
  e.i = i, e.j = j;
  std::vector<Hypothesis> hs = hypotheses(p, points, i, j);
  if (hs.empty()) return e;
  std::sort(hs.begin(), hs.end(), [](const Hypothesis& x, const Hypothesis& y) {
    return x.score > y.score;
  });
  e.best = hs.front();
  e.evidence = e.best.evidence();
  for (const Hypothesis& h : hs)
    if (distinct(e.best, h)) {
      e.rival = h.evidence();
      e.rival_score = h.score;
      break;
    }
  if (e.evidence < kMinEvidence || e.best.score < kMinScore) e.kind = EdgeKind::weak;
  else if (e.best.score - e.rival_score < kMinScoreMargin) e.kind = EdgeKind::ambiguous;
  else e.kind = EdgeKind::accepted;
  if (e.kind != EdgeKind::accepted) e.hypotheses = std::move(hs);  // what join_weak may still use
  return e;
}

// --- greedy assembly: strongest edges first, never two drones in one place ------------------

RelativePose compose(const RelativePose& a, const RelativePose& b) {  // x = a(b(x'))
  return {wrap_angle(a.yaw + b.yaw), yaw_rotation(a.yaw) * b.t + a.t};
}

RelativePose inverse(const RelativePose& a) { return {-a.yaw, -(yaw_rotation(-a.yaw) * a.t)}; }

// Where a cluster has put drone i: its root, and the pose of f_i in the root's frame.
struct Placement {
  int root = 0;
  RelativePose pose;
};

// First pair (x of cluster a, y of cluster b) closer than min_separation in some round, with b's
// frame mapped into a's by b_to_a; {-1, -1} if none.
std::pair<int, int> overlap(const Problem& p, const std::vector<Placement>& place, const std::vector<int>& a,
                            const std::vector<int>& b, const RelativePose& b_to_a) {
  for (int k = 0; k < p.rounds(); ++k)
    for (int x : a) {
      if (!p.views[k][x].present) continue;
      const Eigen::Vector3d xa = place[x].pose.map(p.views[k][x].position);
      for (int y : b) {
        if (!p.views[k][y].present) continue;
        const Eigen::Vector3d yb = b_to_a.map(place[y].pose.map(p.views[k][y].position));
        if ((xa - yb).norm() < p.min_separation) return {x, y};
      }
    }
  return {-1, -1};
}

// Joins clusters along accepted edges, strongest first, and returns where each drone went. An
// edge that would put two drones in one place in some round is dropped: one of its detections
// belongs to another drone.
std::vector<Placement> assemble(const Problem& p, std::vector<Edge>* edges) {
  std::vector<Placement> place(p.drones());
  std::vector<std::vector<int>> members(p.drones());
  for (int i = 0; i < p.drones(); ++i) place[i].root = i, members[i] = {i};
  std::vector<Edge*> order;
  for (Edge& e : *edges)
    if (e.kind == EdgeKind::accepted && !e.dropped) order.push_back(&e);
  std::sort(order.begin(), order.end(), [](const Edge* x, const Edge* y) { return x->best.score > y->best.score; });
  for (Edge* e : order) {
    const int ri = place[e->i].root, rj = place[e->j].root;
    if (ri == rj) continue;  // a cycle: judged by the synchronisation
    // Pose of root j's frame in root i's frame: root_i ← i ← j ← root_j.
    const RelativePose b_to_a = compose(compose(place[e->i].pose, e->best.pose), inverse(place[e->j].pose));
    if (overlap(p, place, members[ri], members[rj], b_to_a).first >= 0) {
      e->dropped = true;
      continue;
    }
    for (int y : members[rj]) {
      place[y] = {ri, compose(b_to_a, place[y].pose)};
      members[ri].push_back(y);
    }
    members[rj].clear();
  }
  return place;
}

// --- a drone whose pairs are each too weak joins a cluster as a whole -------------------------
//
// A drone that several members of the cluster saw, but each too few times, can still join it:
// one pose of the drone must explain its points against every member at once, so the evidence
// of its pairs adds up. Each point of the drone counts once (its best match), so a detection of
// it that several members' points explain is not counted twice. The thresholds are the pair's:
// kMinEvidence matches, a score of kMinScore and a margin of kMinScoreMargin over every distinct
// pose of the drone that any of its pairs with the cluster proposed.

// A counted match of the joining drone: which member (index into the member list) and which points.
struct MemberLink {
  int member;
  Link link;
  bool operator==(const MemberLink& o) const { return member == o.member && link == o.link; }
};

// One pose of drone j in the cluster root's frame, verified against every member.
struct ClusterFit {
  RelativePose pose;               // f_j in the root's frame
  double yaw_sigma = 0;            // rad, σ of pose.yaw
  std::vector<MemberLink> matches; // j's matched points, each once (its best match)
  double score = 0;                // Σ of their scores
  int evidence() const { return static_cast<int>(matches.size()); }
};

// j's points matched against every member under pose (two passes: as given, then refined by
// Procrustes over the counted matches); pivot (root frame) is where the yaw error turns about.
ClusterFit fit_cluster(const Problem& p, const PointSets& points, const std::vector<Placement>& place,
                       const std::vector<int>& members, int j, RelativePose pose, double yaw_sigma,
                       Eigen::Vector3d pivot) {
  ClusterFit f;
  for (int pass = 0; pass < 2; ++pass) {
    f = ClusterFit{pose, yaw_sigma, {}, 0};
    for (size_t n = 0; n < members.size(); ++n) {
      const RelativePose to_m = inverse(place[members[n]].pose);
      const Eigen::Vector3d anchor = to_m.map(pivot);
      Hypothesis h;
      verify(p, points, members[n], j, compose(to_m, pose),
             [&](const Eigen::Vector3d& x) { return yaw_sigma * (x - anchor).norm(); }, &h);
      for (const Link& link : h.links) {
        auto same_point = [&](const MemberLink& m) {
          return m.link.round == link.round && m.link.det_j == link.det_j;
        };
        auto it = std::find_if(f.matches.begin(), f.matches.end(), same_point);
        if (it == f.matches.end()) f.matches.push_back({static_cast<int>(n), link});
        else if (link.score > it->link.score) *it = {static_cast<int>(n), link};
      }
    }
    for (const MemberLink& m : f.matches) f.score += m.link.score;
    if (f.evidence() < kMinEvidence || pass == 1) break;
    std::vector<Correspondence> cs;
    for (const MemberLink& m : f.matches) {
      const Point& a = points[m.link.round][members[m.member]][m.link.det_i + 1];
      const Point& b = points[m.link.round][j][m.link.det_j + 1];
      cs.push_back({0, j, place[members[m.member]].pose.map(a.x), b.x, std::hypot(a.sigma, b.sigma), a.cov, b.cov});
    }
    pose = procrustes(cs, &yaw_sigma, &pivot);
  }
  return f;
}

// Two fits are distinct poses when they share under half of the smaller one's matches.
bool distinct(const ClusterFit& x, const ClusterFit& y) {
  int shared = 0;
  for (const MemberLink& m : y.matches) shared += std::find(x.matches.begin(), x.matches.end(), m) != x.matches.end();
  return 2 * shared < std::min(x.evidence(), y.evidence());
}

// Every pose of j that a pair of j with a member proposed, fitted against the whole cluster.
std::vector<ClusterFit> cluster_fits(const Problem& p, const PointSets& points, const std::vector<Placement>& place,
                                     const std::vector<int>& members, const std::vector<Edge>& edges, int j) {
  std::vector<ClusterFit> fits;
  for (const Edge& e : edges) {
    const int m = e.i == j ? e.j : e.j == j ? e.i : -1;
    if (m < 0 || !std::count(members.begin(), members.end(), m)) continue;
    for (const Hypothesis& h : e.hypotheses) {
      const RelativePose j_in_m = e.i == m ? h.pose : inverse(h.pose);  // f_j in f_m
      const RelativePose j_in_root = compose(place[m].pose, j_in_m);
      // The yaw error turns about the defining pair: midway between the two drones.
      const Eigen::Vector3d pivot = 0.5 * (place[m].pose.map(p.views[h.round][m].position) +
                                           j_in_root.map(p.views[h.round][j].position));
      fits.push_back(fit_cluster(p, points, place, members, j, j_in_root, h.yaw_sigma, pivot));
    }
  }
  std::sort(fits.begin(), fits.end(), [](const ClusterFit& x, const ClusterFit& y) { return x.score > y.score; });
  return fits;
}

// The fit as accepted edges from j to every member it matched. The members share the fit's yaw
// information: each edge's σ is the fit's times √(edges), so together they weigh as the one fit.
void accept_fit(const std::vector<Placement>& place, const std::vector<int>& members, int j, const ClusterFit& fit,
                std::vector<Edge>* edges) {
  std::vector<std::vector<MemberLink>> by_member(members.size());
  for (const MemberLink& m : fit.matches) by_member[m.member].push_back(m);
  const int used = static_cast<int>(std::count_if(by_member.begin(), by_member.end(),
                                                  [](const std::vector<MemberLink>& v) { return !v.empty(); }));
  for (size_t n = 0; n < members.size(); ++n) {
    if (by_member[n].empty()) continue;
    const int m = members[n];
    auto e = std::find_if(edges->begin(), edges->end(), [&](const Edge& x) {
      return (x.i == m && x.j == j) || (x.i == j && x.j == m);
    });
    if (e == edges->end()) continue;  // every pair has an edge; kept for safety
    Hypothesis h;
    h.pose = compose(inverse(place[m].pose), fit.pose);
    h.yaw_sigma = fit.yaw_sigma * std::sqrt(static_cast<double>(used));
    for (const MemberLink& l : by_member[n]) h.links.push_back(l.link), h.score += l.link.score;
    e->i = m, e->j = j;
    e->kind = EdgeKind::accepted;
    e->evidence = h.evidence();
    e->best = std::move(h);
    e->dropped = false;
  }
}

// Joins to a cluster of two or more drones (the reference's first) the first drone alone in its
// own cluster that one pose fits against the whole cluster. Returns true when one joined:
// assemble again.
bool join_weak(const Problem& p, const PointSets& points, const std::vector<Placement>& place,
               std::vector<Edge>* edges) {
  const auto cluster = [&](int root) {
    std::vector<int> members;
    for (int i = 0; i < p.drones(); ++i)
      if (place[i].root == root) members.push_back(i);
    return members;
  };
  std::vector<int> roots{place[p.reference].root};
  for (int i = 0; i < p.drones(); ++i)
    if (place[i].root == i && i != roots.front()) roots.push_back(i);
  for (int root : roots) {
    const std::vector<int> members = cluster(root);
    if (members.size() < 2) continue;  // with one member the pair's own test is the cluster's
    for (int j = 0; j < p.drones(); ++j) {
      if (place[j].root != j || cluster(j).size() > 1) continue;
      const std::vector<ClusterFit> fits = cluster_fits(p, points, place, members, *edges, j);
      if (fits.empty()) continue;
      const ClusterFit& best = fits.front();
      double rival = 0;
      for (const ClusterFit& f : fits)
        if (distinct(best, f)) {
          rival = f.score;
          break;
        }
      if (best.evidence() < kMinEvidence || best.score < kMinScore || best.score - rival < kMinScoreMargin) continue;
      if (overlap(p, place, members, {j}, best.pose).first >= 0) continue;
      accept_fit(place, members, j, best, edges);
      return true;
    }
  }
  return false;
}

// Drones reachable from the reference over accepted, not dropped edges.
std::vector<int> component(int drones, int reference, const std::vector<Edge>& edges) {
  std::vector<int> index(drones, -1), order{reference};
  index[reference] = 0;
  for (size_t n = 0; n < order.size(); ++n)
    for (const Edge& e : edges) {
      if (e.kind != EdgeKind::accepted || e.dropped) continue;
      const int other = e.i == order[n] ? e.j : e.j == order[n] ? e.i : -1;
      if (other >= 0 && index[other] < 0) index[other] = static_cast<int>(order.size()), order.push_back(other);
    }
  return order;
}

// SO(2) synchronisation cost over the component (2m × 2m): Σ w ‖R_j − R_i R(θ_ij)‖², as
// ⟨C, X⟩ with X_ij = R_iᵀ R_j: C_ii = C_jj += w I, C_ij −= w R(θ_ij), C_ji −= w R(θ_ij)ᵀ.
Eigen::MatrixXd sync_cost(const std::vector<int>& members, const std::vector<Edge>& edges, double yaw_floor) {
  std::vector<int> at(1 + *std::max_element(members.begin(), members.end()), -1);
  for (size_t n = 0; n < members.size(); ++n) at[members[n]] = static_cast<int>(n);
  const int m = static_cast<int>(members.size());
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(2 * m, 2 * m);
  for (const Edge& e : edges) {
    if (e.kind != EdgeKind::accepted || e.dropped) continue;
    if (e.i >= static_cast<int>(at.size()) || e.j >= static_cast<int>(at.size())) continue;
    const int a = at[e.i], b = at[e.j];
    if (a < 0 || b < 0) continue;
    const double sigma2 = e.best.yaw_sigma * e.best.yaw_sigma + yaw_floor * yaw_floor;
    const double w = 1.0 / sigma2;
    const Eigen::Matrix2d Rij = Eigen::Rotation2Dd(e.best.pose.yaw).toRotationMatrix();
    C.block<2, 2>(2 * a, 2 * a) += w * Eigen::Matrix2d::Identity();
    C.block<2, 2>(2 * b, 2 * b) += w * Eigen::Matrix2d::Identity();
    C.block<2, 2>(2 * a, 2 * b) -= w * Rij;
    C.block<2, 2>(2 * b, 2 * a) -= w * Rij.transpose();
  }
  return C;
}

std::string id_list(const Problem& p, const std::vector<int>& indices) {
  std::string s;
  for (int i : indices) s += (s.empty() ? "" : ", ") + std::to_string(p.ids[i]);
  return s;
}

// Why the drones outside the component could not be joined, from the pairs that touch them.
std::string unresolved_reason(const Problem& p, const std::vector<int>& outside, const std::vector<Edge>& edges) {
  int unseen = 0, weak = 0, ambiguous = 0, dropped = 0;
  for (const Edge& e : edges) {
    const bool touches = std::count(outside.begin(), outside.end(), e.i) || std::count(outside.begin(), outside.end(), e.j);
    if (!touches) continue;
    unseen += e.kind == EdgeKind::none;
    weak += e.kind == EdgeKind::weak;
    ambiguous += e.kind == EdgeKind::ambiguous;
    dropped += e.kind == EdgeKind::accepted && e.dropped;
  }
  std::ostringstream s;
  s << "drone(s) " << id_list(p, outside) << " not resolved: " << ambiguous
    << " pair(s) ambiguous (several poses explain the detections equally well, e.g. a symmetric formation), "
    << weak << " pair(s) with too little evidence (< " << kMinEvidence << " matched points or log-likelihood ratio < "
    << kMinScore << "; more rounds needed), "
    << dropped << " pair(s) dropped as inconsistent, " << unseen
    << " pair(s) never seen as a mutual pair (the two did not detect each other in one round with matching "
       "ranges and heights)";
  return s.str();
}

struct Solution {
  sdp::Result sdp;
  std::vector<double> yaw;  // N (0 outside the component)
  TranslationSolution translation;
  std::vector<int> members;
  bool consistent = false;
  std::string conflict;  // why the poses contradict themselves, if they do
  std::vector<Correspondence> correspondences;  // those the translation used
};

// Yaws by certified synchronisation over the component; drops the worst edge that disagrees.
// Returns false when an edge was dropped (solve again).
bool synchronise(const Problem& p, std::vector<Edge>* edges, Solution* s, const sdp::Options& o) {
  const double yaw_floor = std::sqrt(2.0) * p.noise.odometry_yaw;
  s->sdp = sdp::solve(sync_cost(s->members, *edges, yaw_floor), 2, o);
  s->yaw.assign(p.drones(), 0.0);
  if (!s->sdp.certified() || s->sdp.Y.cols() < 2) return true;
  const std::vector<double> y = yaws_from_sdp(s->sdp, 0);  // members[0] is the reference
  for (size_t n = 0; n < s->members.size(); ++n) s->yaw[s->members[n]] = y[n];
  Edge* worst = nullptr;
  double worst_z = p.noise.gate;
  for (Edge& e : *edges) {
    if (e.kind != EdgeKind::accepted || e.dropped) continue;
    if (!std::count(s->members.begin(), s->members.end(), e.i)) continue;
    const double sigma = std::hypot(e.best.yaw_sigma, yaw_floor);
    const double z = std::abs(wrap_angle(s->yaw[e.j] - s->yaw[e.i] - e.best.pose.yaw)) / sigma;
    if (z > worst_z) worst_z = z, worst = &e;
  }
  if (worst) worst->dropped = true;
  return worst == nullptr;
}

// Translations over every verified correspondence; drops the edge of the worst residual.
bool translate(const Problem& p, const PointSets& points, std::vector<Edge>* edges, Solution* s) {
  std::vector<Correspondence> cs;
  std::vector<Edge*> owner;
  for (Edge& e : *edges) {
    if (e.kind != EdgeKind::accepted || e.dropped) continue;
    if (!std::count(s->members.begin(), s->members.end(), e.i)) continue;
    for (const Correspondence& c : correspondences(points, e.i, e.j, e.best.links)) cs.push_back(c), owner.push_back(&e);
  }
  s->translation = solve_translations(p.drones(), p.reference, s->yaw, cs);
  s->correspondences = cs;
  if (s->translation.max_normalised_residual <= p.noise.gate) return true;
  owner[s->translation.worst]->dropped = true;
  return false;
}

Solution solve_graph(const Problem& p, const PointSets& points, std::vector<Edge>* edges, const sdp::Options& o) {
  Solution s;
  // Each join takes one drone out of a cluster of its own: at most N − 1 of them.
  std::vector<Placement> place = assemble(p, edges);
  for (int joins = 1; joins < p.drones() && join_weak(p, points, place, edges); ++joins) place = assemble(p, edges);
  for (;;) {
    s.members = component(p.drones(), p.reference, *edges);
    if (s.members.size() < 2) return s;
    if (!synchronise(p, edges, &s, o)) continue;
    if (!s.sdp.certified() || s.sdp.Y.cols() < 2) return s;
    if (!translate(p, points, edges, &s)) continue;
    s.conflict = overlap_problem(p, s.members, s.yaw, s.translation.t);
    s.consistent = s.conflict.empty();
    return s;
  }
}

}  // namespace

Estimate estimate_associated(const Problem& p, const sdp::Options& sdp_options, std::vector<int>* ambiguous) {
  Estimate out;
  out.mode = Mode::associated;
  out.status = EstimateStatus::ambiguous;
  for (int id : p.ids) out.drones.push_back(DronePose{id, 0.0, Eigen::Vector3d::Zero(), false});
  auto t = Clock::now();
  PointSets points(p.rounds(), std::vector<std::vector<Point>>(p.drones()));
  for (int k = 0; k < p.rounds(); ++k)
    for (int i = 0; i < p.drones(); ++i)
      if (p.views[k][i].present) points[k][i] = points_of(p.views[k][i], p.odometry_sd[k]);
  std::vector<Edge> edges;
  for (int i = 0; i < p.drones(); ++i)
    for (int j = i + 1; j < p.drones(); ++j) edges.push_back(judge_pair(p, points, i, j));
  out.timing_us.emplace_back("association", micros(t));
  t = Clock::now();
  const Solution s = solve_graph(p, points, &edges, sdp_options);
  out.timing_us.emplace_back("synchronisation", micros(t));
  if (s.members.size() >= 2) out.certificate = certificate_of(s.sdp);
  std::vector<int> outside;
  for (int i = 0; i < p.drones(); ++i)
    if (!std::count(s.members.begin(), s.members.end(), i)) outside.push_back(i);
  if (ambiguous) {
    ambiguous->clear();
    for (int i : outside)
      for (const Edge& e : edges)
        if (e.kind == EdgeKind::ambiguous && (e.i == i || e.j == i)) {
          ambiguous->push_back(i);
          break;
        }
  }
  const bool sdp_unique =
      s.members.size() >= 2 && s.sdp.status == sdp::Status::certified_unique && s.sdp.Y.cols() >= 2;
  if (s.members.size() >= 2 && !sdp_unique) {
    out.reason = std::string("rotation synchronisation SDP ") + sdp::to_string(s.sdp.status) + ": " + s.sdp.reason;
    return out;
  }
  if (s.members.size() >= 2)
    for (int n : s.members) out.drones[n] = DronePose{p.ids[n], s.yaw[n], s.translation.t[n], s.consistent};
  out.drones[p.reference].resolved = true;
  if (!outside.empty()) {
    out.reason = unresolved_reason(p, outside, edges);
    return out;
  }
  if (!s.consistent) {
    out.reason = "the poses contradict themselves: " + s.conflict;
    for (DronePose& d : out.drones) d.resolved = d.id == p.ids[p.reference];
    return out;
  }
  const std::vector<PoseSigma> sigma =
      pose_uncertainty(p.drones(), p.reference, s.yaw, s.translation.t, s.translation.connected, s.correspondences);
  if (std::string e = precision_problem(p, sigma); !e.empty()) {
    out.reason = e;
    for (int i = 0; i < p.drones(); ++i)
      if (!precise(p, sigma[i])) out.drones[i].resolved = false;
    return out;
  }
  int used = 0, matched = 0;
  for (const Edge& e : edges)
    if (e.kind == EdgeKind::accepted && !e.dropped) ++used, matched += e.evidence;
  std::ostringstream r;
  r << "every drone resolved over " << used << " verified pair(s) with " << matched
    << " matched points; synchronisation SDP certified unique (gap " << s.sdp.rel_gap << ")";
  out.status = EstimateStatus::certified;
  out.reason = r.str();
  return out;
}

}  // namespace fact::estimator
