// Shared pieces of the estimator modes (not part of the public API).
#pragma once

#include "fact/estimator.h"

#include <Eigen/Core>
#include <string>
#include <vector>

namespace fact::estimator {

// 3-D rotation about z by yaw (rad).
Eigen::Matrix3d yaw_rotation(double yaw);
// Wraps an angle into (−π, π].
double wrap_angle(double a);

// One detection, ready for the modes. Index conventions: drones by their position in
// Rounds::drones (0 … N−1), rounds 0 … K−1.
struct Detection {
  Eigen::Vector3d observer = Eigen::Vector3d::Zero();  // observer centre in f_i at detection (m)
  Eigen::Vector3d direction = Eigen::Vector3d::Zero(); // detection vector rotated into f_i axes (m)
  Eigen::Vector3d target = Eigen::Vector3d::Zero();    // detected centre in f_i = observer + direction
  Eigen::Vector3d body = Eigen::Vector3d::Zero();      // the raw body-frame vector (m)
  double range = 0;                                    // |body| (m)
  double sigma = 0;                                    // largest position σ of target (m), sensor + odometry
  // Covariance of target in f_i (m², 3 × 3): σ_along² along the ray, σ_across² across it.
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
};

// What drone i reported in round k.
struct DroneView {
  bool present = false;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // odometry position in f_i (m)
  std::vector<Detection> detections;
};

// The rounds as indexed arrays: views[k][i].
struct Problem {
  std::vector<int> ids;                        // N drone ids, ascending
  int reference = 0;                           // index of the reference drone
  std::vector<std::vector<DroneView>> views;   // K × N
  NoiseModel noise;
  // VIO error of round k's odometry against the frames of the latest round, grown by the
  // random walk over the rounds between (see NoiseModel): σ in m and rad, K each.
  std::vector<double> odometry_sd, odometry_yaw_sd;
  double min_separation = 0.3;                 // m, see EstimateOptions
  double max_yaw_sigma = 0.025;                // rad, see EstimateOptions
  double max_position_sigma = 0.08;            // m, see EstimateOptions
  int drones() const { return static_cast<int>(ids.size()); }
  int rounds() const { return static_cast<int>(views.size()); }
};

Problem make_problem(const Rounds& rounds, int reference_index, const NoiseModel& noise);

// A point correspondence between two drones' frames: R_i x_i + t_i ≈ R_j x_j + t_j in f_ref,
// where x_i is in f_i and x_j in f_j.
struct Correspondence {
  int i = 0, j = 0;                                   // drone indices
  Eigen::Vector3d x_i = Eigen::Vector3d::Zero();      // m, in f_i
  Eigen::Vector3d x_j = Eigen::Vector3d::Zero();      // m, in f_j
  double sigma = 0;                                   // largest σ of the difference (m)
  // Covariances of x_i (f_i axes) and x_j (f_j axes), m², 3 × 3. The difference R_i x_i − R_j x_j
  // then has R_i cov_i R_iᵀ + R_j cov_j R_jᵀ.
  Eigen::Matrix3d cov_i = Eigen::Matrix3d::Zero(), cov_j = Eigen::Matrix3d::Zero();
};

// Translations by weighted least squares with the rotations fixed (yaw[i]: f_i in f_ref).
// t[reference] = 0; drones not connected to the reference through correspondences get
// connected[i] = false and t = 0.
struct TranslationSolution {
  std::vector<Eigen::Vector3d> t;   // origin of f_i in f_ref (m), N
  std::vector<bool> connected;      // N
  double max_normalised_residual = 0;  // max over correspondences of sqrt(rᵀ Σ⁻¹ r)
  int worst = -1;                   // index of that correspondence
};
TranslationSolution solve_translations(int drones, int reference, const std::vector<double>& yaw,
                                       const std::vector<Correspondence>& correspondences);

// 1-σ uncertainty of a drone's pose relative to the reference (rad, m: largest axis).
struct PoseSigma {
  double yaw = 0;
  double position = 0;
  // The Gauss–Newton step from the estimate to the poses that best fit the correspondences
  // (rad, m). A large step means the estimate disagrees with its own matched detections.
  double yaw_step = 0;
  double position_step = 0;
};
// From the correspondences' information at the solution (yaw[i], t[i]: pose of f_i in f_ref).
// Unconnected drones and the reference get 0.
std::vector<PoseSigma> pose_uncertainty(int drones, int reference, const std::vector<double>& yaw,
                                        const std::vector<Eigen::Vector3d>& t, const std::vector<bool>& connected,
                                        const std::vector<Correspondence>& correspondences);

// True when one drone's pose is precise enough and agrees with its detections.
bool precise(const Problem& p, const PoseSigma& s);
// "" when every connected drone's pose is precise enough to certify, else which is not and why.
std::string precision_problem(const Problem& p, const std::vector<PoseSigma>& sigma);
// Two of `members` (indices into p.ids) closer than p.min_separation in some round, given the
// yaws (rad, N) and origins (m, N) of their frames in f_ref: "" if none, else which and where.
std::string overlap_problem(const Problem& p, const std::vector<int>& members, const std::vector<double>& yaw,
                            const std::vector<Eigen::Vector3d>& t);

// Fills the certificate fields of an estimate from an SDP result.
Certificate certificate_of(const sdp::Result& r);

// Yaw-only SDP result → yaw of each drone's frame in f_ref (rad). Requires a d = 2 factor.
std::vector<double> yaws_from_sdp(const sdp::Result& r, int reference);

// The summed-anonymous-cost modes (paper: plain relaxation; complex: tight U(1) form).
Estimate estimate_summed(const Problem& problem, bool complex_form, const sdp::Options& sdp_options);

// Yaw-invariant association of mutual pairs, certified synchronisation, least-squares translation.
// When `ambiguous` is given it receives the drones (indices) left unresolved that have a pair which
// several poses explain about equally well (an ambiguous edge: a symmetric formation, say).
Estimate estimate_associated(const Problem& problem, const sdp::Options& sdp_options,
                             std::vector<int>* ambiguous = nullptr);

}  // namespace fact::estimator
