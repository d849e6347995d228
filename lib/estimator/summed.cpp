// The paper's formulation (mode paper) and its tight U(1) form (mode complex):
//   1. per drone and round, the sum of its anonymous detections rotated into f_i;
//   2. rotations from the SDP on Q = Σ_k s_k s_kᵀ (paper) or Q̃ = Q + KᵀQK (complex);
//   3. identities: per round, each drone's detections matched by the Hungarian algorithm to the
//      other drones' detections in the common frame (a mutual pair sums to about zero);
//   4. translations by least squares over the matched pairs (the observation graph).
#include "fact/hungarian.h"
#include "fact/rotation_cost.h"
#include "internal.h"

#include <chrono>
#include <algorithm>
#include <cmath>
#include <sstream>

namespace fact::estimator {
namespace {

using Clock = std::chrono::steady_clock;
double micros(Clock::time_point a) { return std::chrono::duration<double, std::micro>(Clock::now() - a).count(); }

// sums[k][i] = s_ik: horizontal part of Σ_a R(ψ_a) v_a in f_i (m); zero for an absent drone.
std::vector<std::vector<Eigen::Vector2d>> detection_sums(const Problem& p) {
  std::vector<std::vector<Eigen::Vector2d>> sums(p.rounds(), std::vector<Eigen::Vector2d>(p.drones()));
  for (int k = 0; k < p.rounds(); ++k)
    for (int i = 0; i < p.drones(); ++i) {
      Eigen::Vector3d s = Eigen::Vector3d::Zero();
      for (const Detection& d : p.views[k][i].detections) s += d.direction;
      sums[k][i] = s.head<2>();
    }
  return sums;
}

// A detection named by (drone, index) within one round.
struct Ref {
  int drone, index;
};

// Mutual Hungarian matches in one round: pairs (a of i, b of j) that each drone's own matching
// chose, with the world-frame vectors summing to about zero.
std::vector<std::pair<Ref, Ref>> match_round(const Problem& p, int k, const std::vector<Eigen::Matrix3d>& R) {
  std::vector<Ref> all;
  std::vector<Eigen::Vector3d> world;  // detection vectors in f_ref axes
  for (int i = 0; i < p.drones(); ++i)
    for (size_t a = 0; a < p.views[k][i].detections.size(); ++a) {
      all.push_back({i, static_cast<int>(a)});
      world.push_back(R[i] * p.views[k][i].detections[a].direction);
    }
  const int n = static_cast<int>(all.size());
  const double gate2 = p.noise.gate * p.noise.gate;
  std::vector<int> choice(n, -1);  // choice[x] = detection matched to x by x's owner
  for (int i = 0; i < p.drones(); ++i) {
    std::vector<int> rows;
    for (int x = 0; x < n; ++x)
      if (all[x].drone == i) rows.push_back(x);
    if (rows.empty()) continue;
    // cost(r, y): normalised squared sum ‖w_r + w_y‖² / (σ_r² + σ_y²); own detections excluded.
    Eigen::MatrixXd cost(rows.size(), n);
    for (size_t r = 0; r < rows.size(); ++r)
      for (int y = 0; y < n; ++y) {
        const Detection& a = p.views[k][i].detections[all[rows[r]].index];
        const Detection& b = p.views[k][all[y].drone].detections[all[y].index];
        cost(r, y) = all[y].drone == i ? INFINITY
                                       : (world[rows[r]] + world[y]).squaredNorm() /
                                             (a.sigma * a.sigma + b.sigma * b.sigma);
        if (!(cost(r, y) <= gate2)) cost(r, y) = INFINITY;  // beyond the gate: never matched
      }
    const Assignment assignment = solve_assignment(cost, gate2);
    for (size_t r = 0; r < rows.size(); ++r) choice[rows[r]] = assignment.row_to_col[r];
  }
  std::vector<std::pair<Ref, Ref>> pairs;
  for (int x = 0; x < n; ++x)
    if (choice[x] > x && choice[choice[x]] == x) pairs.push_back({all[x], all[choice[x]]});
  return pairs;
}

// Each matched pair gives two correspondences: i's detection of j ↔ j's position, and i's
// position ↔ j's detection of i (positions: the observers' odometry at detection).
void add_pair(const Problem& p, int k, const Ref& a, const Ref& b, std::vector<Correspondence>* out) {
  const Detection& da = p.views[k][a.drone].detections[a.index];
  const Detection& db = p.views[k][b.drone].detections[b.index];
  const Eigen::Matrix3d own = std::pow(p.odometry_sd[k], 2) * Eigen::Matrix3d::Identity();
  out->push_back({a.drone, b.drone, da.target, db.observer, da.sigma, da.cov, own});
  out->push_back({a.drone, b.drone, da.observer, db.target, db.sigma, own, db.cov});
}

// ⟨C, X⟩ at the rounded rotations: X_ij = R_iᵀ R_j, i.e. X = V Vᵀ with block i of V (2N × 2)
// equal to R(yaw_i)ᵀ.
double rounded_cost(const Eigen::MatrixXd& C, const std::vector<double>& yaw) {
  Eigen::MatrixXd V(2 * yaw.size(), 2);
  for (size_t i = 0; i < yaw.size(); ++i) V.block<2, 2>(2 * i, 0) = Eigen::Rotation2Dd(-yaw[i]).toRotationMatrix();
  return (V.transpose() * C * V).trace();
}

// "" when the SDP's rotations are the certified unique optimum of the summed cost, else why not:
// too few rounds, a non-unique or uncertified optimum, or a relaxation that is not tight (its
// optimum is not a set of rotations, e.g. a reflected block, so rounding loses optimality).
std::string rotation_problem(const Problem& p, const sdp::Result& sdp, const Eigen::MatrixXd& C,
                             const std::vector<double>& yaw) {
  if (p.rounds() < p.drones() - 1)  // each round is one complex equation in the N − 1 unknown yaws
    return "the summed cost needs at least N - 1 = " + std::to_string(p.drones() - 1) + " rounds to fix every yaw; " +
           std::to_string(p.rounds()) + " given";
  if (sdp.status != sdp::Status::certified_unique)
    return std::string("rotation SDP ") + sdp::to_string(sdp.status) + ": " + sdp.reason +
           (sdp.status == sdp::Status::certified_not_unique ? " (too few rounds for the summed cost)" : "");
  const double rounded = rounded_cost(C, yaw);
  const double slack = 1e-6 * std::max({1.0, std::abs(sdp.objective), sdp.scale});
  if (rounded - sdp.objective > slack) {
    std::ostringstream s;
    s << "the relaxation is not tight: rounded rotations cost " << rounded << " > SDP optimum " << sdp.objective
      << " (its optimum is not a set of rotations, e.g. a reflected drone)";
    return s.str();
  }
  return "";
}

}  // namespace

Estimate estimate_summed(const Problem& p, bool complex, const sdp::Options& sdp_options) {
  Estimate out;
  out.mode = complex ? Mode::complex : Mode::paper;
  out.status = EstimateStatus::ambiguous;
  for (int id : p.ids) out.drones.push_back(DronePose{id, 0.0, Eigen::Vector3d::Zero(), false});
  auto t = Clock::now();
  const Eigen::MatrixXd Q = paper_cost(detection_sums(p));  // 2N × 2N, PSD, rank ≤ K
  if (Q.norm() < 1e-12) {
    out.reason = "no detections: the summed cost is zero";
    return out;
  }
  const Eigen::MatrixXd C = complex ? sdp::complex_form(Q) : Q;
  const sdp::Result sdp = sdp::solve(C, 2, sdp_options);
  out.timing_us.emplace_back("rotation", micros(t));
  out.certificate = certificate_of(sdp);
  if (sdp.Y.cols() < 2) {
    out.reason = std::string("rotation SDP ") + sdp::to_string(sdp.status) + ": " + sdp.reason;
    return out;
  }
  // Not unique or not certified: the rounded poses are still reported (as the paper does), but
  // no drone counts as resolved.
  const std::vector<double> yaw = yaws_from_sdp(sdp, p.reference);
  const std::string sdp_problem = rotation_problem(p, sdp, C, yaw);
  const bool unique = sdp_problem.empty();
  std::vector<Eigen::Matrix3d> R;
  for (double y : yaw) R.push_back(yaw_rotation(y));
  t = Clock::now();
  std::vector<Correspondence> cs;
  for (int k = 0; k < p.rounds(); ++k)
    for (const auto& [a, b] : match_round(p, k, R)) add_pair(p, k, a, b, &cs);
  out.timing_us.emplace_back("matching", micros(t));
  t = Clock::now();
  const TranslationSolution ts = solve_translations(p.drones(), p.reference, yaw, cs);
  out.timing_us.emplace_back("translation", micros(t));
  std::string missing;
  for (int i = 0; i < p.drones(); ++i) {
    out.drones[i] = DronePose{p.ids[i], yaw[i], ts.t[i], ts.connected[i] && (unique || i == p.reference)};
    if (!ts.connected[i]) missing += (missing.empty() ? "" : ", ") + std::to_string(p.ids[i]);
  }
  if (!unique) {
    out.reason = sdp_problem;
    return out;
  }
  // The residual and precision checks run whether or not every drone is connected: a connected
  // drone counts as resolved only when they pass (returning at a missing drone first left wrong
  // poses of the connected ones resolved, metres and radians off).
  std::vector<std::string> problems;
  if (!missing.empty()) problems.push_back("no matched detections connect drone(s) " + missing + " to the reference");
  if (ts.max_normalised_residual > p.noise.gate) {
    problems.push_back("matched detections disagree with the poses: residual " +
                       std::to_string(ts.max_normalised_residual) + " sigma > gate " + std::to_string(p.noise.gate));
    for (DronePose& d : out.drones) d.resolved = false;
    out.drones[p.reference].resolved = true;
  } else {
    const std::vector<PoseSigma> sigma = pose_uncertainty(p.drones(), p.reference, yaw, ts.t, ts.connected, cs);
    if (std::string e = precision_problem(p, sigma); !e.empty()) {
      problems.push_back(e);
      for (int i = 0; i < p.drones(); ++i)
        if (!precise(p, sigma[i])) out.drones[i].resolved = false;
    }
  }
  // Two connected drones in one place: the poses contradict themselves (a wrong match), so none
  // but the reference is resolved.
  std::vector<int> connected;
  for (int i = 0; i < p.drones(); ++i)
    if (ts.connected[i]) connected.push_back(i);
  if (std::string e = overlap_problem(p, connected, yaw, ts.t); !e.empty()) {
    problems.push_back(e + " (closer than min_separation " + std::to_string(p.min_separation) + " m)");
    for (DronePose& d : out.drones) d.resolved = false;
    out.drones[p.reference].resolved = true;
  }
  if (!problems.empty()) {
    for (size_t i = 0; i < problems.size(); ++i) out.reason += (i ? "; " : "") + problems[i];
    return out;
  }
  out.status = EstimateStatus::certified;
  out.reason = "rotation SDP certified unique; every drone matched, consistent and precise";
  return out;
}

}  // namespace fact::estimator
