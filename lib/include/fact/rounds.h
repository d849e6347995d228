// Observation rounds: the estimator's input, as plain data.
//
// Frames (see ../shared/docs/design.md): drone i's odometry frame f_i is where its VIO started,
// gravity-aligned with an arbitrary yaw. Units are metres and radians; axes are FLU.
// The same content travels as the fact-rounds-v1 JSON format and, later, as LCM messages.
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

namespace fact {

// One anonymous detection made by a drone.
struct Observation {
  Eigen::Vector3d odom_position = Eigen::Vector3d::Zero();  // observer position in f_i at detection (m)
  double odom_yaw = 0;                                       // observer yaw in f_i at detection (rad)
  // From the observer's centre to the detected drone's centre, in the observer's
  // gravity-aligned body frame at detection time (x along its heading, z up), metres.
  Eigen::Vector3d vector = Eigen::Vector3d::Zero();
};

// What one drone reports for one round.
struct DroneRound {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // odometry position in f_i at the round's start (m)
  double yaw = 0;                                      // odometry yaw in f_i at the round's start (rad)
  std::vector<Observation> observations;               // may be empty
};

// One round: every drone that reported, by id.
struct Round {
  int index = 0;
  std::map<int, DroneRound> drones;
};

// A whole session of rounds for a swarm.
struct Rounds {
  std::vector<int> drones;    // the swarm's ids, ascending and unique
  std::vector<Round> rounds;  // in order
};

// The most drones one estimate takes (the gossip tracks 32; beyond a few hundred the association
// search and the SDP grow past any flight's budget, and a file listing 200 000 ids took 20 GB
// before failing: review, session 32).
constexpr int kMaxDrones = 256;
// The most observations one drone reports in one round, as the gossip passes on (GossipOptions::
// max_observations): the association pairs every detection of one drone with every one of
// another's, and 200 detections each took 16 s, 400 over 5 min (review, session 34).
constexpr int kMaxObservations = 64;

// Checks the data a decoder produced: ids unique and known, every number finite, 2 … kMaxDrones
// drones, at most kMaxObservations observations per drone and round, round indexes strictly
// increasing (the last round is the latest). Returns "" when usable, otherwise one line naming the
// round, the drone, the field and the value, e.g. "round 2 (index 2): drone 5: observations[1].vector[0]
// is nan".
std::string validate_rounds(const Rounds& rounds);

// The first `count` rounds (all of them when count <= 0 or count exceeds the number).
Rounds first_rounds(const Rounds& rounds, int count);
// The latest `count` rounds (all of them when count <= 0 or count exceeds the number).
Rounds last_rounds(const Rounds& rounds, int count);

}  // namespace fact
