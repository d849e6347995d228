// The swarm pose estimator: observation rounds in, the relative poses of every drone's odometry
// frame out, with an honest statement of certainty. Plain functions over plain data; no I/O.
//
// Modes (see ../shared/docs/mission.md):
//   paper       the paper's summed anonymous cost, its real 2N×2N SDP (d = 2), rounding, Hungarian
//               matching of detections in the common frame, translations over the observation graph.
//   complex     the same summed data in the tight U(1) form Q̃ = Q + KᵀQK (exact with N−1 rounds).
//   associated  yaw-invariant association of mutual pairs (|v_ij| ≈ |v_ji|, v_ij,z ≈ −v_ji,z),
//               each pair a relative-pose hypothesis verified against the detections both drones
//               share, then certified rotation synchronisation and least-squares translation.
//   automatic   associated, then complex, then paper: the first that certifies (the summed modes
//               are not tried when the association finds an ambiguous drone, below).
// The summed data know less than the detections they add up: paper and complex never certify when
// the association leaves a drone unresolved with a pair that several poses explain about equally
// well (a symmetric formation, where noise alone picks the summed SDP's optimum; automatic mode then
// does not try them), nor resolve poses that contradict the association's resolved ones. Explicit
// paper and complex run the association to check (stage "rival_check" of timing_us).
#pragma once

#include "fact/rounds.h"
#include "fact/sdp.h"

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

namespace fact {

enum class Mode { paper, complex, associated, automatic };
const char* to_string(Mode m);         // "paper", "complex", "associated", "auto"
bool parse_mode(const std::string& text, Mode* mode);  // accepts the names above

enum class EstimateStatus {
  certified,      // globally optimal, unique, every drone resolved and consistent (summed modes:
                  // and the association finds no rival, see above)
  ambiguous,      // too few rounds, disconnected graph, symmetric formation, … (reason says which)
  invalid_input,  // reason names the round, the drone, the field and the value
};
const char* to_string(EstimateStatus s);  // "certified", "ambiguous", "invalid_input"

// The sensor's noise. A detected centre at range d, seen a rounds before the latest round used (by
// round index: missing rounds count too), has covariance σ_along² along the ray and σ_across²
// across it (both axes), in the observer's frame:
//   σ_along²  = floor² + (linear·d + quadratic·d²)² + odom(a)²
//   σ_across² = floor² + (bearing·d)² + odom(a)² + (odom_yaw(a)·d)²
//   odom(a)²     = odometry²     + a·odometry_walk²       (VIO position error, m²)
//   odom_yaw(a)² = odometry_yaw² + a·odometry_yaw_walk²   (VIO yaw error, rad²)
// The VIO frames drift, so the estimate is of the frames during the latest round: an older
// detection is further from them by a random walk per round, and weighs less.
// It is a calibration of the camera and the VIO, not knowledge of the scene. Defaults: a
// D430-class depth camera with a VIO that drifts about 2 cm and 0.01 rad within a round and
// walks about 3 cm and 0.006 rad per √round (a round, a spin and a move, takes about 10 s).
// sigma(d) is the isotropic summary sqrt(floor² + along_sensor² + across_sensor²).
struct NoiseModel {
  double floor = 0.03;        // m, detector centring error at any range
  double linear = 0.0;        // range σ per metre of range (the paper's model: 0.05 per axis)
  double quadratic = 0.008;   // range σ per metre² (stereo depth: c·d²)
  double bearing = 0.005;     // rad, bearing σ
  double odometry = 0.02;     // m, VIO position error within a round
  double odometry_yaw = 0.01; // rad, VIO yaw error within a round
  double odometry_walk = 0.03;       // m per √round, VIO position random walk between rounds
  double odometry_yaw_walk = 0.006;  // rad per √round, VIO yaw random walk between rounds
  double gate = 4.0;          // a residual within gate·σ counts as consistent
  double sigma(double range) const;
  double odometry_at(int age) const;      // odom(a), m
  double odometry_yaw_at(int age) const;  // odom_yaw(a), rad
};

struct EstimateOptions {
  Mode mode = Mode::automatic;
  int max_rounds = 0;   // use only the first K rounds (0 = all)
  int window = 0;       // of those, use only the latest W (0 = all): bounds the drift they span
  int reference = -1;   // id of the reference drone (−1 = lowest id)
  NoiseModel noise;
  // Two drones are never closer than this (m, centre to centre). A pose that would put two drones
  // in one place contradicts itself; this is how a wrong association is caught.
  double min_separation = 0.3;
  // A result is certified only when every pose is this precise (1 σ, from the information of the
  // matched detections): a globally optimal answer to noisy data can still be too uncertain to use.
  double max_yaw_sigma = 0.025;     // rad
  double max_position_sigma = 0.08; // m
  sdp::Options sdp;
};

struct DronePose {
  int id = 0;
  double yaw = 0;                                      // yaw of f_i in f_ref, (−π, π]
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // origin of f_i in f_ref (m)
  bool resolved = false;                               // pose determined and consistent
};

// The rotation SDP's certificate, unscaled.
struct Certificate {
  double objective = 0;       // primal optimum ⟨C, X⟩ (paper mode: the paper's SDP)
  double dual_objective = 0;  // rigorous dual bound
  double gap = 0;             // relative duality gap
  double min_eig = 0;         // λ_min of the dual slack S (scaled problem)
  int rank = 0;               // numerical rank of X
  double bound_error = 0;     // what floating point can have raised dual_objective by
                              // (sdp::Result::bound_error): every feasible X has
                              // ⟨C, X⟩ ≥ dual_objective − bound_error; NaN when not known (a
                              // result from a fact_swarm_result_t message, which does not carry it)
};

struct Estimate {
  Mode mode = Mode::automatic;   // the mode that produced this result (never automatic)
  EstimateStatus status = EstimateStatus::invalid_input;
  std::string reason;
  int reference = -1;
  int rounds_used = 0;
  std::vector<DronePose> drones;  // one per id in Rounds::drones, ascending by id
  std::vector<int> unresolved;    // ids with resolved == false
  Certificate certificate;
  std::vector<std::pair<std::string, double>> timing_us;  // named stages, then "total"
  bool certified() const { return status == EstimateStatus::certified; }
};

// "" or what is wrong with the noise model (a term negative, not finite or above 1e6, floor and
// odometry both below 1e-6 m, a zero gate), naming the field and the value.
std::string check_noise(const NoiseModel& n);

// Estimates the pose of every drone's odometry frame in the reference drone's frame.
// Never throws on bad input: returns EstimateStatus::invalid_input with the reason.
Estimate estimate_poses(const Rounds& rounds, const EstimateOptions& options = {});

}  // namespace fact
