// Conversions between lib/'s plain data (fact/rounds.h, fact/estimator.h) and the LCM messages,
// with checks. Every from_* returns "" when the message is usable, otherwise one line naming the
// field and the value (e.g. "round_packet drone 3 round 1: observations[0].vector[2] is nan").
#pragma once

#include "fact/estimator.h"
#include "fact/frame_t.hpp"
#include "fact/rounds.h"
#include "fact/round_packet_t.hpp"
#include "fact/swarm_result_t.hpp"
#include "fact/swarm_rounds_t.hpp"

#include <cstdint>
#include <string>

namespace fact::app {

// One drone's round as a round packet (count = observations.size()).
fact::round_packet_t to_message(int drone_id, int round, const DroneRound& r, int64_t utime);

// A round packet's content; checks: drone_id ≥ 0, round ≥ 0, count == observations.size(),
// every number finite. On error *out is left unchanged.
std::string from_message(const fact::round_packet_t& m, DroneRound* out);

// A camera frame as fact-detector takes it: "" or the reason, naming the field and value (this
// drone's id, width and height 1 … 8192, gray_size = depth_size = width × height, usable
// intrinsics: fact::intrinsics_error), with the detector's counter for it in *counter
// (wrong_drone_id, bad_frame, size_mismatch, bad_intrinsics). fact-preflight checks the same.
std::string frame_message_error(const fact::frame_t& m, int drone_id, std::string* counter);

// The swarm's complete rounds → fact::Rounds: drones = drone_ids (sorted; unique, ≥ 0),
// rounds 0 … complete_rounds − 1 (Round::index = round number), each holding every packet of that
// round. Checks: counts equal array sizes, every packet valid (from_message), its drone id listed
// in drone_ids, its round in [0, complete_rounds), no (drone, round) twice, every listed drone
// present in every round. On error *out is left unchanged.
std::string rounds_from_message(const fact::swarm_rounds_t& m, Rounds* out);

// The inverse, for publishers and tests: every round's packets in ascending drone order.
fact::swarm_rounds_t rounds_to_message(const Rounds& rounds, int drone_id, int64_t utime);

// The inverse of result_to_message, for consumers (planner, evaluation): checks num_drones equals the
// array size, mode (paper, complex, associated; auto on an invalid_input result) and status are
// known names, ids are unique and ≥ 0, a resolved drone's pose is finite, solve_us is finite and
// ≥ 0, and a certified result names the mode that certified it, has drones, every one resolved,
// and its reference among them. Unresolved poses and the certificate may be NaN (they do not
// exist). timing_us gets {"total", solve_us}. On error *out is left unchanged.
std::string result_from_message(const fact::swarm_result_t& m, Estimate* out);

// An estimate as a swarm result (mode, status, reason, reference, rounds used, poses, certificate;
// solve_us is the "total" timing, or 0 when absent).
fact::swarm_result_t result_to_message(const Estimate& e, int drone_id, int64_t utime);

}  // namespace fact::app
