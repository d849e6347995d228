// Checks on observation rounds, and selecting the first K of them.
#include "fact/rounds.h"

#include <cmath>
#include <set>
#include <sstream>

namespace fact {
namespace {

std::string number(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

// "" if every component is finite, else "<field>[c] is <value>".
std::string check_vector(const Eigen::Vector3d& v, const std::string& field) {
  for (int c = 0; c < 3; ++c)
    if (!std::isfinite(v[c])) return field + "[" + std::to_string(c) + "] is " + number(v[c]);
  return "";
}

std::string check_scalar(double v, const std::string& field) {
  return std::isfinite(v) ? "" : field + " is " + number(v);
}

bool finite(const Eigen::Vector3d& v) { return v.allFinite(); }

// Larger distances (m) are not a drone swarm's and would overflow the estimator's arithmetic.
constexpr double kMaxMetres = 1e4;

// Names the first bad field of one observation ("" if none). Strings are built only on error.
std::string check_observation(const Observation& obs, size_t o) {
  if (finite(obs.odom_position) && std::isfinite(obs.odom_yaw) && finite(obs.vector) && obs.vector.norm() >= 1e-6 &&
      obs.vector.norm() <= kMaxMetres && obs.odom_position.norm() <= kMaxMetres)
    return "";
  const std::string at = "observations[" + std::to_string(o) + "].";
  std::string e = check_vector(obs.odom_position, at + "odom_position");
  if (e.empty()) e = check_scalar(obs.odom_yaw, at + "odom_yaw");
  if (e.empty()) e = check_vector(obs.vector, at + "vector");
  if (e.empty() && obs.odom_position.norm() > kMaxMetres)
    e = at + "odom_position is " + number(obs.odom_position.stableNorm()) + " m from the origin (more than " +
        number(kMaxMetres) + " m)";
  if (e.empty() && obs.vector.norm() > kMaxMetres)
    e = at + "vector has length " + number(obs.vector.stableNorm()) + " m (more than " + number(kMaxMetres) + " m)";
  if (e.empty()) e = at + "vector has length " + number(obs.vector.stableNorm()) + " m (a detection must point somewhere)";
  return e;
}

std::string check_drone(const DroneRound& d) {
  std::string e = check_vector(d.position, "position");
  if (e.empty() && d.position.norm() > kMaxMetres)
    e = "position is " + number(d.position.stableNorm()) + " m from the origin (more than " + number(kMaxMetres) + " m)";
  if (e.empty()) e = check_scalar(d.yaw, "yaw");
  for (size_t o = 0; e.empty() && o < d.observations.size(); ++o) e = check_observation(d.observations[o], o);
  return e;
}

}  // namespace

std::string validate_rounds(const Rounds& rounds) {
  std::set<int> ids;
  for (size_t i = 0; i < rounds.drones.size(); ++i) {
    if (!ids.insert(rounds.drones[i]).second)
      return "drones[" + std::to_string(i) + "]: id " + std::to_string(rounds.drones[i]) + " is listed twice";
  }
  if (ids.size() < 2) return "drones: " + std::to_string(ids.size()) + " drone(s) listed, at least 2 are needed";
  if (ids.size() > static_cast<size_t>(kMaxDrones))
    return "drones: " + std::to_string(ids.size()) + " drones listed, at most " + std::to_string(kMaxDrones) +
           " are supported";
  if (rounds.rounds.empty()) return "rounds: no rounds";
  for (size_t k = 1; k < rounds.rounds.size(); ++k)
    if (rounds.rounds[k].index <= rounds.rounds[k - 1].index)
      return "round " + std::to_string(k) + ": index " + std::to_string(rounds.rounds[k].index) +
             " is not above round " + std::to_string(k - 1) + "'s index " + std::to_string(rounds.rounds[k - 1].index) +
             " (rounds must be listed in the order they were observed)";
  for (size_t k = 0; k < rounds.rounds.size(); ++k) {
    const Round& round = rounds.rounds[k];
    const auto at = [&] { return "round " + std::to_string(k) + " (index " + std::to_string(round.index) + "): "; };
    for (const auto& [id, drone] : round.drones) {
      if (!ids.count(id)) return at() + "drone " + std::to_string(id) + " is not in the swarm's drone list";
      if (drone.observations.size() > static_cast<size_t>(kMaxObservations))
        return at() + "drone " + std::to_string(id) + ": " + std::to_string(drone.observations.size()) +
               " observations, at most " + std::to_string(kMaxObservations) + " per drone and round";
      const std::string e = check_drone(drone);
      if (!e.empty()) return at() + "drone " + std::to_string(id) + ": " + e;
    }
  }
  return "";
}

namespace {

// Rounds [begin, begin + count) of `rounds`, with the swarm's ids.
Rounds slice(const Rounds& rounds, size_t begin, size_t count) {
  Rounds out;
  out.drones = rounds.drones;
  out.rounds.assign(rounds.rounds.begin() + begin, rounds.rounds.begin() + begin + count);
  return out;
}

// How many of the rounds a request for `count` takes: all of them when count <= 0 or too large.
size_t taken(const Rounds& rounds, int count) {
  const size_t all = rounds.rounds.size();
  return (count <= 0 || static_cast<size_t>(count) > all) ? all : static_cast<size_t>(count);
}

}  // namespace

Rounds first_rounds(const Rounds& rounds, int count) { return slice(rounds, 0, taken(rounds, count)); }

Rounds last_rounds(const Rounds& rounds, int count) {
  const size_t n = taken(rounds, count);
  return slice(rounds, rounds.rounds.size() - n, n);
}

}  // namespace fact
