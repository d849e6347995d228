// One sample message of every top-level fact LCM type, with distinctive values in every field
// (arrays non-empty, strings non-empty), for the message tests and fact-lcm-publish-sample.
#pragma once

#include "fact/app_status_t.hpp"
#include "fact/detections_t.hpp"
#include "fact/fc_state_t.hpp"
#include "fact/frame_t.hpp"
#include "fact/gossip_packet_t.hpp"
#include "fact/gossip_challenge_t.hpp"
#include "fact/gossip_request_t.hpp"
#include "fact/gossip_summary_t.hpp"
#include "fact/odometry_t.hpp"
#include "fact/round_packet_t.hpp"
#include "fact/setpoint_t.hpp"
#include "fact/sim_clock_t.hpp"
#include "fact/swarm_result_t.hpp"
#include "fact/swarm_rounds_t.hpp"
#include "fact/truth_t.hpp"

#include <cmath>
#include <cstdint>
#include <vector>

namespace fact::samples {

inline fact::odometry_t odometry(int64_t utime, int id) {
  fact::odometry_t m;
  m.utime = utime;
  m.drone_id = id;
  m.seq = 41;
  m.position[0] = 1.25; m.position[1] = -2.5; m.position[2] = 1.5;
  m.velocity[0] = 0.1; m.velocity[1] = -0.2; m.velocity[2] = 0.05;
  m.yaw = 3.5;  // unwrapped: beyond π on purpose
  m.roll = 0.01;
  m.pitch = -0.02;
  return m;
}

inline fact::setpoint_t setpoint(int64_t utime, int id) {
  fact::setpoint_t m;
  m.utime = utime;
  m.drone_id = id;
  for (int k = 0; k < 3; ++k) {
    m.position[k] = 1.0 + k;
    m.velocity[k] = 0.5 - k;
    m.acceleration[k] = -0.25 * k;
  }
  m.yaw = -1.0;
  m.yaw_rate = 0.3;
  return m;
}

inline fact::fc_state_t fc_state(int64_t utime, int id) {
  fact::fc_state_t m;
  m.utime = utime;
  m.drone_id = id;
  m.connected = true;
  m.armed = true;
  m.offboard = false;
  m.custom_mode = 6 << 16;
  m.base_mode = 129;
  m.system_status = 4;
  m.heartbeat_age_ms = 120;
  m.position_valid = true;
  m.position_age_ms = 30;
  m.position[0] = 1.0; m.position[1] = -2.0; m.position[2] = 1.5;
  m.velocity[0] = 0.1; m.velocity[1] = 0.0; m.velocity[2] = -0.05;
  m.attitude_valid = true;
  m.attitude_age_ms = 10;
  m.roll = 0.01; m.pitch = -0.02; m.yaw = 1.25;
  m.streaming = true;
  m.reason = "setpoints fresh";
  m.setpoints_sent = 4200;
  m.odometry_sent = 8400;
  return m;
}

inline fact::sim_clock_t sim_clock(int64_t utime) {
  fact::sim_clock_t m;
  m.utime = utime;
  m.rate = 2.5;
  return m;
}

inline fact::observation_t observation(double s) {
  fact::observation_t o;
  o.odom_position[0] = s; o.odom_position[1] = -s; o.odom_position[2] = 1.5;
  o.odom_yaw = 0.25 * s;
  o.vector[0] = 2.0 + s; o.vector[1] = -1.0; o.vector[2] = 0.125;
  return o;
}

inline fact::round_packet_t round_packet(int64_t utime, int id, int round) {
  fact::round_packet_t m;
  m.utime = utime;
  m.drone_id = id;
  m.round = round;
  m.position[0] = 0.5 * id; m.position[1] = 0.25 * round; m.position[2] = 1.0;
  m.yaw = 0.1 * id - 0.05 * round;
  m.observations = {observation(id + 0.5), observation(id + round + 1.5)};
  m.count = static_cast<int32_t>(m.observations.size());
  return m;
}

inline fact::swarm_rounds_t swarm_rounds(int64_t utime, int id) {
  fact::swarm_rounds_t m;
  m.utime = utime;
  m.drone_id = id;
  m.complete_rounds = 2;
  m.drone_ids = {1, 2, 4};
  m.num_drones = 3;
  for (int k = 0; k < 2; ++k)
    for (int d : m.drone_ids) m.packets.push_back(round_packet(utime - 1000, d, k));
  m.num_packets = static_cast<int32_t>(m.packets.size());
  return m;
}

inline fact::swarm_result_t swarm_result(int64_t utime, int id) {
  fact::swarm_result_t m;
  m.utime = utime;
  m.drone_id = id;
  m.mode = "associated";
  m.status = "ambiguous";  // (drone 4 is unresolved: a certified result resolves every drone)
  m.reason = "drone 4 unresolved";
  m.reference = 1;
  m.rounds_used = 2;
  for (int d : {1, 2, 4}) {
    fact::drone_pose_t p;
    p.id = d;
    p.yaw = 0.3 * d;
    p.position[0] = d; p.position[1] = -d; p.position[2] = 0.1 * d;
    p.resolved = d != 4;
    m.drones.push_back(p);
  }
  m.num_drones = static_cast<int32_t>(m.drones.size());
  m.objective = 1.5e-6;
  m.dual_objective = 1.4e-6;
  m.gap = 1e-10;
  m.min_eig = -2e-12;
  m.rank = 2;
  m.solve_us = 1234.5;
  return m;
}

inline fact::detections_t detections(int64_t utime, int id) {
  fact::detections_t m;
  m.utime = utime;
  m.drone_id = id;
  m.frame_seq = 77;
  for (int t = 0; t < 2; ++t) {
    fact::detection_t d;
    d.track_id = 10 + t;
    d.vector[0] = 3.0 - t; d.vector[1] = 0.5 * t; d.vector[2] = -0.25;
    d.box[0] = 100.0f + t; d.box[1] = 80.0f; d.box[2] = 32.0f; d.box[3] = 24.0f;
    d.confidence = 0.75f;
    d.range = std::sqrt(d.vector[0] * d.vector[0] + d.vector[1] * d.vector[1] + d.vector[2] * d.vector[2]);
    m.detections.push_back(d);
  }
  m.count = static_cast<int32_t>(m.detections.size());
  return m;
}

inline fact::frame_t frame(int64_t utime, int id) {
  fact::frame_t m;
  m.utime = utime;
  m.drone_id = id;
  m.seq = 9;
  m.width = 8;
  m.height = 4;
  m.fx = 386.0; m.fy = 386.5; m.cx = 3.5; m.cy = 1.5;
  m.gray_size = m.width * m.height;
  m.depth_size = m.width * m.height;
  for (int i = 0; i < m.gray_size; ++i) {
    m.gray.push_back(static_cast<uint8_t>(i * 7));
    m.depth_mm.push_back(static_cast<int16_t>(i == 3 ? 0 : 500 + 10 * i));
  }
  return m;
}

inline fact::gossip_packet_t gossip_packet(int64_t utime, int id) {
  fact::gossip_packet_t m;
  m.utime = utime;
  m.sender_id = id;
  m.seq = 5;
  m.kind = fact::gossip_packet_t::ROUND;
  fact::round_packet_t inner = round_packet(utime, id, 0);
  m.payload.resize(inner.getEncodedSize());
  inner.encode(m.payload.data(), 0, static_cast<int>(m.payload.size()));
  m.payload_size = static_cast<int32_t>(m.payload.size());
  for (int i = 0; i < 32; ++i) m.mac[i] = static_cast<uint8_t>(0xA0 + i);
  return m;
}

inline fact::gossip_request_t gossip_request(int64_t utime, int id) {
  fact::gossip_request_t m;
  m.utime = utime;
  m.drone_id = id;
  m.origin = 4;
  m.rounds = {0, 2, 3};
  m.count = static_cast<int32_t>(m.rounds.size());
  return m;
}

inline fact::gossip_challenge_t gossip_challenge(int64_t utime, int id) {
  fact::gossip_challenge_t m;
  m.utime = utime;
  m.peer_id = id;
  for (int k = 0; k < 16; ++k) m.nonce[k] = static_cast<uint8_t>(17 * k + 3);
  return m;
}

inline fact::gossip_summary_t gossip_summary(int64_t utime, int id) {
  fact::gossip_summary_t m;
  m.utime = utime;
  m.drone_id = id;
  m.origins = {1, 2, 4};
  m.rounds_held = {3, 2, 0};
  m.digests = {int64_t{0x0123456789abcdef}, -5, 0};
  m.count = 3;
  return m;
}

inline fact::app_status_t app_status(int64_t utime, int id) {
  fact::app_status_t m;
  m.utime = utime;
  m.drone_id = id;
  m.app = "fact-lcm-publish-sample";
  m.state = "running";
  m.counter_names = {"published", "undecodable"};
  m.counter_values = {12, 0};
  m.num_counters = 2;
  m.message = "sample";
  return m;
}

inline fact::truth_t truth(int64_t utime) {
  fact::truth_t m;
  m.utime = utime;
  m.drone_ids = {1, 2, 4};
  m.num_drones = 3;
  for (int i = 0; i < 3; ++i) {
    m.frame_yaw.push_back(0.4 * i - 0.2);
    m.frame_origin.push_back({1.0 * i, 2.0 - i, 0.0});
    m.position.push_back({1.0 * i + 0.5, 2.5 - i, 1.5});
    m.yaw.push_back(0.1 * i);
  }
  return m;
}

}  // namespace fact::samples
