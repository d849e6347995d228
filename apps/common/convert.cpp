#include "common/convert.h"

#include "fact/camera.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <utility>

namespace fact::app {
namespace {

std::string num(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// "" when finite, else "<field> is <value>".
std::string finite(double v, const std::string& field) {
  return std::isfinite(v) ? std::string() : field + " is " + num(v);
}

std::string finite3(const double* v, const std::string& field) {
  for (int k = 0; k < 3; ++k) {
    std::string e = finite(v[k], field + "[" + std::to_string(k) + "]");
    if (!e.empty()) return e;
  }
  return "";
}

std::string packet_prefix(const fact::round_packet_t& m) {
  return "round_packet drone " + std::to_string(m.drone_id) + " round " + std::to_string(m.round) + ": ";
}

}  // namespace

fact::round_packet_t to_message(int drone_id, int round, const DroneRound& r, int64_t utime) {
  fact::round_packet_t m;
  m.utime = utime;
  m.drone_id = drone_id;
  m.round = round;
  for (int k = 0; k < 3; ++k) m.position[k] = r.position[k];
  m.yaw = r.yaw;
  m.count = static_cast<int32_t>(r.observations.size());
  m.observations.reserve(r.observations.size());
  for (const Observation& o : r.observations) {
    fact::observation_t mo;
    for (int k = 0; k < 3; ++k) {
      mo.odom_position[k] = o.odom_position[k];
      mo.vector[k] = o.vector[k];
    }
    mo.odom_yaw = o.odom_yaw;
    m.observations.push_back(mo);
  }
  return m;
}

std::string from_message(const fact::round_packet_t& m, DroneRound* out) {
  const std::string at = packet_prefix(m);
  if (m.drone_id < 0) return at + "drone_id is " + std::to_string(m.drone_id) + " (must be >= 0)";
  if (m.round < 0) return at + "round is " + std::to_string(m.round) + " (must be >= 0)";
  if (m.count < 0 || static_cast<size_t>(m.count) != m.observations.size())
    return at + "count is " + std::to_string(m.count) + " but observations has " +
           std::to_string(m.observations.size());
  std::string e = finite3(m.position, "position");
  if (e.empty()) e = finite(m.yaw, "yaw");
  for (size_t i = 0; e.empty() && i < m.observations.size(); ++i) {
    const fact::observation_t& o = m.observations[i];
    const std::string f = "observations[" + std::to_string(i) + "].";
    e = finite3(o.odom_position, f + "odom_position");
    if (e.empty()) e = finite(o.odom_yaw, f + "odom_yaw");
    if (e.empty()) e = finite3(o.vector, f + "vector");
  }
  if (!e.empty()) return at + e;

  DroneRound r;
  r.position = Eigen::Vector3d(m.position[0], m.position[1], m.position[2]);
  r.yaw = m.yaw;
  r.observations.reserve(m.observations.size());
  for (const fact::observation_t& o : m.observations) {
    Observation ob;
    ob.odom_position = Eigen::Vector3d(o.odom_position[0], o.odom_position[1], o.odom_position[2]);
    ob.odom_yaw = o.odom_yaw;
    ob.vector = Eigen::Vector3d(o.vector[0], o.vector[1], o.vector[2]);
    r.observations.push_back(std::move(ob));
  }
  *out = std::move(r);
  return "";
}

std::string rounds_from_message(const fact::swarm_rounds_t& m, Rounds* out) {
  const std::string at = "swarm_rounds from drone " + std::to_string(m.drone_id) + ": ";
  if (m.num_drones < 0 || static_cast<size_t>(m.num_drones) != m.drone_ids.size())
    return at + "num_drones is " + std::to_string(m.num_drones) + " but drone_ids has " +
           std::to_string(m.drone_ids.size());
  if (m.num_packets < 0 || static_cast<size_t>(m.num_packets) != m.packets.size())
    return at + "num_packets is " + std::to_string(m.num_packets) + " but packets has " +
           std::to_string(m.packets.size());
  if (m.complete_rounds < 0)
    return at + "complete_rounds is " + std::to_string(m.complete_rounds) + " (must be >= 0)";
  std::set<int> ids;
  for (size_t i = 0; i < m.drone_ids.size(); ++i) {
    int id = m.drone_ids[i];
    if (id < 0) return at + "drone_ids[" + std::to_string(i) + "] is " + std::to_string(id) + " (must be >= 0)";
    if (!ids.insert(id).second) return at + "drone_ids[" + std::to_string(i) + "] is " + std::to_string(id) + ", listed twice";
  }
  if (ids.empty() && m.complete_rounds > 0)
    return at + "complete_rounds is " + std::to_string(m.complete_rounds) + " but drone_ids is empty";

  // Rounds are keyed sparsely while reading: complete_rounds and the round numbers come from the
  // wire, and nothing may be allocated per round before every packet has been checked.
  std::map<int, std::map<int, DroneRound>> by_round;
  for (size_t i = 0; i < m.packets.size(); ++i) {
    const fact::round_packet_t& p = m.packets[i];
    const std::string pat = at + "packets[" + std::to_string(i) + "] (drone " + std::to_string(p.drone_id) +
                            ", round " + std::to_string(p.round) + "): ";
    if (!ids.count(p.drone_id))
      return pat + "unknown drone id " + std::to_string(p.drone_id) + " (not in drone_ids)";
    if (p.round < 0 || p.round >= m.complete_rounds)
      return pat + "round " + std::to_string(p.round) + " outside 0 .. complete_rounds - 1 = " +
             std::to_string(m.complete_rounds - 1);
    DroneRound r;
    std::string e = from_message(p, &r);
    if (!e.empty()) return at + "packets[" + std::to_string(i) + "]: " + e;
    if (!by_round[p.round].emplace(p.drone_id, std::move(r)).second)
      return pat + "duplicate packet: drone " + std::to_string(p.drone_id) + " round " +
             std::to_string(p.round) + " appears twice";
  }
  // No duplicates and all in range, so exactly complete_rounds × |drones| packets means every drone
  // in every round. Otherwise the first gap is within the first packets / |drones| + 1 rounds.
  const int64_t expected = static_cast<int64_t>(m.complete_rounds) * static_cast<int64_t>(ids.size());
  if (static_cast<int64_t>(m.packets.size()) != expected) {
    for (int k = 0; k < m.complete_rounds; ++k) {
      auto it = by_round.find(k);
      for (int id : ids)
        if (it == by_round.end() || !it->second.count(id))
          return at + "round " + std::to_string(k) + " has no packet from drone " + std::to_string(id) +
                 " (complete_rounds is " + std::to_string(m.complete_rounds) + ")";
    }
  }

  Rounds rounds;
  rounds.drones.assign(ids.begin(), ids.end());
  rounds.rounds.resize(static_cast<size_t>(m.complete_rounds));
  for (auto& [k, drones] : by_round) {
    rounds.rounds[k].index = k;
    rounds.rounds[k].drones = std::move(drones);
  }
  *out = std::move(rounds);
  return "";
}

fact::swarm_rounds_t rounds_to_message(const Rounds& rounds, int drone_id, int64_t utime) {
  fact::swarm_rounds_t m;
  m.utime = utime;
  m.drone_id = drone_id;
  m.complete_rounds = static_cast<int32_t>(rounds.rounds.size());
  m.drone_ids.assign(rounds.drones.begin(), rounds.drones.end());
  m.num_drones = static_cast<int32_t>(m.drone_ids.size());
  for (size_t k = 0; k < rounds.rounds.size(); ++k)
    for (const auto& [id, r] : rounds.rounds[k].drones)
      m.packets.push_back(to_message(id, static_cast<int>(k), r, utime));
  m.num_packets = static_cast<int32_t>(m.packets.size());
  return m;
}

fact::swarm_result_t result_to_message(const Estimate& e, int drone_id, int64_t utime) {
  fact::swarm_result_t m;
  m.utime = utime;
  m.drone_id = drone_id;
  m.mode = to_string(e.mode);
  m.status = to_string(e.status);
  m.reason = e.reason;
  m.reference = e.reference;
  m.rounds_used = e.rounds_used;
  m.num_drones = static_cast<int32_t>(e.drones.size());
  for (const DronePose& p : e.drones) {
    fact::drone_pose_t mp;
    mp.id = p.id;
    mp.yaw = p.yaw;
    for (int k = 0; k < 3; ++k) mp.position[k] = p.position[k];
    mp.resolved = p.resolved;
    m.drones.push_back(mp);
  }
  m.objective = e.certificate.objective;
  m.dual_objective = e.certificate.dual_objective;
  m.gap = e.certificate.gap;
  m.min_eig = e.certificate.min_eig;
  m.rank = e.certificate.rank;
  m.solve_us = 0;
  for (const auto& [stage, us] : e.timing_us)
    if (stage == "total") m.solve_us = us;
  return m;
}

std::string result_from_message(const fact::swarm_result_t& m, Estimate* out) {
  const std::string at = "swarm_result from drone " + std::to_string(m.drone_id) + ": ";
  if (m.num_drones < 0 || static_cast<size_t>(m.num_drones) != m.drones.size())
    return at + "num_drones is " + std::to_string(m.num_drones) + " but drones has " +
           std::to_string(m.drones.size());
  Estimate e;
  if (!parse_mode(m.mode, &e.mode))  // "auto" only on an invalid_input result (no mode ran)
    return at + "mode is \"" + m.mode + "\" (expected paper, complex, associated or auto)";
  if (m.status == to_string(EstimateStatus::certified)) e.status = EstimateStatus::certified;
  else if (m.status == to_string(EstimateStatus::ambiguous)) e.status = EstimateStatus::ambiguous;
  else if (m.status == to_string(EstimateStatus::invalid_input)) e.status = EstimateStatus::invalid_input;
  else return at + "status is \"" + m.status + "\" (expected certified, ambiguous or invalid_input)";
  e.reason = m.reason;
  e.reference = m.reference;
  e.rounds_used = m.rounds_used;
  std::set<int> ids;
  for (size_t i = 0; i < m.drones.size(); ++i) {
    const fact::drone_pose_t& p = m.drones[i];
    const std::string f = "drones[" + std::to_string(i) + "]";
    if (p.id < 0) return at + f + ".id is " + std::to_string(p.id) + " (must be >= 0)";
    if (!ids.insert(p.id).second) return at + f + ".id is " + std::to_string(p.id) + ", listed twice";
    if (p.resolved) {
      std::string err = finite(p.yaw, f + ".yaw");
      if (err.empty()) err = finite3(p.position, f + ".position");
      if (!err.empty()) return at + err + " but resolved is true";
    }
    DronePose d;
    d.id = p.id;
    d.yaw = p.yaw;
    d.position = Eigen::Vector3d(p.position[0], p.position[1], p.position[2]);
    d.resolved = p.resolved;
    if (!d.resolved) e.unresolved.push_back(d.id);
    e.drones.push_back(d);
  }
  // A certified result certifies something: a mode that ran (not auto), every drone resolved, the
  // reference among them. A "certified" message with no drones, reference −7 and auto passed, and
  // the planner holds on any certified result (review, session 33).
  if (e.status == EstimateStatus::certified) {
    if (m.mode == "auto") return at + "status is certified but mode is \"auto\" (the mode that certified it)";
    if (m.drones.empty()) return at + "status is certified but drones is empty";
    if (!e.unresolved.empty())
      return at + "status is certified but drone " + std::to_string(e.unresolved.front()) + " is not resolved";
    if (!ids.count(m.reference))
      return at + "status is certified but the reference " + std::to_string(m.reference) + " is not among its drones";
  }
  if (!(m.solve_us >= 0) || !std::isfinite(m.solve_us))
    return at + "solve_us is " + std::to_string(m.solve_us) + " (must be a finite time >= 0)";
  e.certificate.objective = m.objective;
  e.certificate.dual_objective = m.dual_objective;
  e.certificate.gap = m.gap;
  e.certificate.min_eig = m.min_eig;
  e.certificate.rank = m.rank;
  e.certificate.bound_error = std::numeric_limits<double>::quiet_NaN();  // not in the message
  e.timing_us = {{"total", m.solve_us}};
  *out = std::move(e);
  return "";
}

std::string frame_message_error(const fact::frame_t& m, int drone_id, std::string* counter) {
  auto fail = [&](const char* c, const std::string& why) {
    *counter = c;
    return "frame seq " + std::to_string(m.seq) + ": " + why;
  };
  if (m.drone_id != drone_id)
    return fail("wrong_drone_id", "drone_id = " + std::to_string(m.drone_id) + ", expected " + std::to_string(drone_id));
  if (m.width <= 0 || m.width > 8192 || m.height <= 0 || m.height > 8192)
    return fail("bad_frame", "width × height = " + std::to_string(m.width) + " × " + std::to_string(m.height) +
                                 " (each must be 1 … 8192)");
  if (m.gray_size != m.depth_size)
    return fail("size_mismatch", "gray_size = " + std::to_string(m.gray_size) + " but depth_size = " +
                                     std::to_string(m.depth_size) + " (depth and gray of different sizes)");
  const int64_t n = int64_t(m.width) * m.height;
  if (m.gray_size != n)
    return fail("bad_frame", "gray_size = " + std::to_string(m.gray_size) + ", expected width × height = " +
                                 std::to_string(n));
  CameraIntrinsics k{m.width, m.height, m.fx, m.fy, m.cx, m.cy};
  if (std::string e = intrinsics_error(k); !e.empty()) return fail("bad_intrinsics", "intrinsics: " + e);
  return "";
}

}  // namespace fact::app
