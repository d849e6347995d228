// JSON encodings fact-rounds-v1, fact-result-v1 and fact-truth-v1 (see fact/json_io.h).
//
// Decoders read through a small set of checked accessors (need, number, integer, vec3, …) that
// carry the JSON path of the value they read, so every error names the path and the value.
// Encoders use nlohmann's ordered_json, which keeps keys in the order written (timing_us is an
// ordered list of stages) and prints doubles with the shortest text that parses back to the
// same bits.
#include "fact/json_io.h"
#include "fact/file_read.h"

#include "io/json_read.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <charconv>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace fact {
namespace {

using namespace json_read;

constexpr const char* kRoundsFormat = "fact-rounds-v1";
constexpr const char* kResultFormat = "fact-result-v1";
constexpr const char* kTruthFormat = "fact-truth-v1";

// Drone ids are non-negative: −1 means "none" elsewhere (EstimateOptions::reference, truth targets).
int drone_id(const Json& value, const std::string& path) {
  const int id = integer(value, path);
  if (id < 0) fail(path, "expected a drone id >= 0, got " + describe(value));
  return id;
}

// An object key naming a drone: its id in canonical decimal ("7", not "07", "+7" or " 7"), so
// that two keys can never name the same drone.
int drone_key(const std::string& key, const std::string& path) {
  const bool digits = !key.empty() && key.size() <= 10 &&
                      std::all_of(key.begin(), key.end(), [](char c) { return c >= '0' && c <= '9'; });
  const bool canonical = digits && (key == "0" || key[0] != '0');
  if (!canonical || std::stoll(key) > INT_MAX)
    fail(path, "expected a drone id in decimal as the key, got " + Json(key).dump());
  return static_cast<int>(std::stoll(key));
}

// Every key of a round's "drones" object must be a listed id.
void check_drone_keys(const Json& drones, const std::string& path, const std::set<int>& ids) {
  for (const auto& item : drones.items()) {
    const std::string drone_path = drone_member(path, item.key());
    const int id = drone_key(item.key(), drone_path);
    if (!ids.count(id)) fail(drone_path, "drone " + std::to_string(id) + " is not listed in \"drones\"");
  }
}

// Records that entry `index` of the list at `list_path` has drone id `id` (read at `id_path`);
// an id seen before is an error naming both entries. `seen` maps id → index of first entry.
void note_unique(std::map<int, std::size_t>& seen, int id, const std::string& list_path, std::size_t index,
                 const std::string& id_path) {
  const auto [it, fresh] = seen.emplace(id, index);
  if (!fresh)
    fail(id_path, "duplicate id " + std::to_string(id) + " (also at " + element(list_path, it->second) + ")");
}

// A list of unique drone ids, in the order given.
std::vector<int> id_list(const Json& value, const std::string& path) {
  expect_array(value, path);
  std::vector<int> ids;
  std::map<int, std::size_t> seen;
  for (std::size_t i = 0; i < value.size(); ++i) {
    ids.push_back(drone_id(value[i], element(path, i)));
    note_unique(seen, ids.back(), path, i, element(path, i));
  }
  return ids;
}

// Parses the text and checks that it is an object of the given format. Unknown top-level keys
// are accepted, so producers may add metadata (a generator's options, a comment) without a new
// format version; every nested object is closed (see allow_only).
Json parse_document(const std::string& text_in, const char* format) {
  Json doc = parse_text(text_in);
  expect_object(doc, "");
  const std::string found = text(need(doc, "", "format"), "format");
  if (found != format) fail("format", "expected \"" + std::string(format) + "\", got " + Json(found).dump());
  return doc;
}

// ---------------------------------------------------------------------------------------------
// Writing

[[noreturn]] void fail_encode(const std::string& path, const std::string& what) {
  throw FormatError("cannot encode " + path + ": " + what);
}

Json finite(double x, const std::string& path) {
  if (!std::isfinite(x)) fail_encode(path, "it is " + describe(x) + "; the format holds finite numbers only");
  return x;
}

Json finite3(const Eigen::Vector3d& v, const std::string& path) {
  return Json::array({finite(v[0], element(path, 0)), finite(v[1], element(path, 1)),
                      finite(v[2], element(path, 2))});
}

Json finite_or_null(double x) { return std::isfinite(x) ? Json(x) : Json(nullptr); }

Json finite_or_null3(const Eigen::Vector3d& v) {
  return Json::array({finite_or_null(v[0]), finite_or_null(v[1]), finite_or_null(v[2])});
}

void check_unique_ids(const std::vector<int>& ids, const std::string& path) {
  std::set<int> seen;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (ids[i] < 0) fail_encode(element(path, i), "drone id " + std::to_string(ids[i]) + " is negative");
    if (!seen.insert(ids[i]).second) fail_encode(element(path, i), "duplicate id " + std::to_string(ids[i]));
  }
}

// Text layout: 2-space indentation, except that a "flat" value (an array of scalars, or an
// object whose values are scalars or arrays of scalars) stays on one line, so that a vector, an
// observation or a drone's pose reads as one line. The document itself is always expanded.
bool is_scalar_array(const Json& j) {
  return j.is_array() && std::none_of(j.begin(), j.end(), [](const Json& e) { return e.is_structured(); });
}

bool is_flat(const Json& j) {
  if (j.is_array()) return is_scalar_array(j);
  return std::all_of(j.begin(), j.end(), [](const Json& v) { return !v.is_structured() || is_scalar_array(v); });
}

void write_inline(const Json& j, std::string& out) {
  if (!j.is_structured()) {
    out += j.dump();
    return;
  }
  out += j.is_array() ? '[' : '{';
  bool first = true;
  for (const auto& item : j.items()) {
    if (!first) out += ", ";
    first = false;
    if (j.is_object()) out += Json(item.key()).dump() + ": ";
    write_inline(item.value(), out);
  }
  out += j.is_array() ? ']' : '}';
}

void write_pretty(const Json& j, int depth, std::string& out) {
  if (depth > 0 && (!j.is_structured() || j.empty() || is_flat(j))) {
    write_inline(j, out);
    return;
  }
  out += j.is_array() ? "[\n" : "{\n";
  std::size_t left = j.size();
  for (const auto& item : j.items()) {
    out.append(2 * (depth + 1), ' ');
    if (j.is_object()) out += Json(item.key()).dump() + ": ";
    write_pretty(item.value(), depth + 1, out);
    out += --left > 0 ? ",\n" : "\n";
  }
  out.append(2 * depth, ' ');
  out += j.is_array() ? ']' : '}';
}

std::string dump(const Json& doc) {
  std::string out;
  write_pretty(doc, 0, out);
  return out + "\n";
}

// ---------------------------------------------------------------------------------------------
// fact-rounds-v1

Observation read_observation(const Json& value, const std::string& path) {
  expect_object(value, path);
  allow_only(value, path, {"odom_position", "odom_yaw", "vector"});
  Observation o;
  o.odom_position = vec3(need(value, path, "odom_position"), member(path, "odom_position"));
  o.odom_yaw = number(need(value, path, "odom_yaw"), member(path, "odom_yaw"));
  o.vector = vec3(need(value, path, "vector"), member(path, "vector"));
  return o;
}

DroneRound read_drone_round(const Json& value, const std::string& path) {
  expect_object(value, path);
  allow_only(value, path, {"position", "yaw", "observations"});
  DroneRound d;
  d.position = vec3(need(value, path, "position"), member(path, "position"));
  d.yaw = number(need(value, path, "yaw"), member(path, "yaw"));
  const std::string list_path = member(path, "observations");
  const Json& list = need(value, path, "observations");
  expect_array(list, list_path);
  for (std::size_t i = 0; i < list.size(); ++i)
    d.observations.push_back(read_observation(list[i], element(list_path, i)));
  return d;
}

Round read_round(const Json& value, const std::string& path, const std::set<int>& listed) {
  expect_object(value, path);
  allow_only(value, path, {"index", "drones"});
  Round round;
  round.index = integer(need(value, path, "index"), member(path, "index"));
  const std::string drones_path = member(path, "drones");
  const Json& drones = need(value, path, "drones");
  expect_object(drones, drones_path);
  check_drone_keys(drones, drones_path, listed);
  for (const auto& item : drones.items())
    round.drones[std::stoi(item.key())] = read_drone_round(item.value(), drone_member(drones_path, item.key()));
  return round;
}

Json write_observation(const Observation& o, const std::string& path) {
  Json j;
  j["odom_position"] = finite3(o.odom_position, member(path, "odom_position"));
  j["odom_yaw"] = finite(o.odom_yaw, member(path, "odom_yaw"));
  j["vector"] = finite3(o.vector, member(path, "vector"));
  return j;
}

Json write_drone_round(const DroneRound& d, const std::string& path) {
  Json j;
  j["position"] = finite3(d.position, member(path, "position"));
  j["yaw"] = finite(d.yaw, member(path, "yaw"));
  j["observations"] = Json::array();
  for (std::size_t i = 0; i < d.observations.size(); ++i)
    j["observations"].push_back(write_observation(d.observations[i], element(member(path, "observations"), i)));
  return j;
}

Json write_round(const Round& round, const std::string& path, const std::set<int>& listed) {
  Json j;
  j["index"] = round.index;
  j["drones"] = Json::object();
  for (const auto& [id, drone] : round.drones) {  // std::map: ascending ids
    const std::string drone_path = drone_member(member(path, "drones"), std::to_string(id));
    if (!listed.count(id)) fail_encode(drone_path, "drone " + std::to_string(id) + " is not in Rounds::drones");
    j["drones"][std::to_string(id)] = write_drone_round(drone, drone_path);
  }
  return j;
}

// ---------------------------------------------------------------------------------------------
// fact-result-v1

template <typename Enum>
Enum enum_from_text(const Json& value, const std::string& path, std::initializer_list<Enum> values) {
  const std::string name = text(value, path);
  std::string names;
  for (Enum e : values) {
    if (name == to_string(e)) return e;
    names += (names.empty() ? "" : ", ") + Json(to_string(e)).dump();
  }
  fail(path, "expected one of " + names + ", got " + Json(name).dump());
}

Mode read_mode(const Json& value, const std::string& path) {
  return enum_from_text(value, path, {Mode::paper, Mode::complex, Mode::associated, Mode::automatic});
}

EstimateStatus read_status(const Json& value, const std::string& path) {
  return enum_from_text(value, path, {EstimateStatus::certified, EstimateStatus::ambiguous,
                                      EstimateStatus::invalid_input});
}

// An unresolved drone may have no pose: its yaw and position components may be null (NaN).
DronePose read_pose(const Json& value, const std::string& path) {
  expect_object(value, path);
  allow_only(value, path, {"id", "yaw", "position", "resolved"});
  DronePose p;
  p.id = drone_id(need(value, path, "id"), member(path, "id"));
  p.resolved = boolean(need(value, path, "resolved"), member(path, "resolved"));
  const Json& yaw = need(value, path, "yaw");
  const Json& position = need(value, path, "position");
  p.yaw = p.resolved ? number(yaw, member(path, "yaw")) : number_or_null(yaw, member(path, "yaw"));
  p.position = p.resolved ? vec3(position, member(path, "position"))
                          : vec3_or_null(position, member(path, "position"));
  return p;
}

std::vector<DronePose> read_poses(const Json& value, const std::string& path) {
  expect_array(value, path);
  std::vector<DronePose> poses;
  std::map<int, std::size_t> seen;
  for (std::size_t i = 0; i < value.size(); ++i) {
    poses.push_back(read_pose(value[i], element(path, i)));
    note_unique(seen, poses.back().id, path, i, member(element(path, i), "id"));
  }
  return poses;
}

// Certificate values that do not exist (e.g. an invalid_input result) are null (NaN); so is a
// missing "bound_error" (files written before it was added).
Certificate read_certificate(const Json& value, const std::string& path) {
  expect_object(value, path);
  allow_only(value, path, {"objective", "dual_objective", "bound_error", "gap", "min_eig", "rank"});
  Certificate c;
  c.objective = number_or_null(need(value, path, "objective"), member(path, "objective"));
  c.dual_objective = number_or_null(need(value, path, "dual_objective"), member(path, "dual_objective"));
  c.gap = number_or_null(need(value, path, "gap"), member(path, "gap"));
  c.min_eig = number_or_null(need(value, path, "min_eig"), member(path, "min_eig"));
  c.rank = integer(need(value, path, "rank"), member(path, "rank"));
  c.bound_error = value.contains("bound_error")
                      ? number_or_null(value["bound_error"], member(path, "bound_error"))
                      : std::numeric_limits<double>::quiet_NaN();
  return c;
}

std::vector<std::pair<std::string, double>> read_timing(const Json& value, const std::string& path) {
  expect_object(value, path);
  std::vector<std::pair<std::string, double>> timing;
  for (const auto& item : value.items())  // ordered_json: the order of the text
    timing.emplace_back(item.key(), number(item.value(), member(path, item.key())));
  return timing;
}

Json write_pose(const DronePose& p, const std::string& path) {
  Json j;
  j["id"] = p.id;
  j["yaw"] = p.resolved ? finite(p.yaw, member(path, "yaw")) : finite_or_null(p.yaw);
  j["position"] = p.resolved ? finite3(p.position, member(path, "position")) : finite_or_null3(p.position);
  j["resolved"] = p.resolved;
  return j;
}

Json write_certificate(const Certificate& c) {
  Json j;
  j["objective"] = finite_or_null(c.objective);
  j["dual_objective"] = finite_or_null(c.dual_objective);
  j["bound_error"] = finite_or_null(c.bound_error);
  j["gap"] = finite_or_null(c.gap);
  j["min_eig"] = finite_or_null(c.min_eig);
  j["rank"] = c.rank;
  return j;
}

Json write_timing(const std::vector<std::pair<std::string, double>>& timing) {
  Json j = Json::object();
  for (const auto& [name, us] : timing) {
    const std::string path = member("timing_us", name);
    if (j.contains(name)) fail_encode(path, "the stage name appears twice");
    j[name] = finite(us, path);
  }
  return j;
}

// ---------------------------------------------------------------------------------------------
// fact-truth-v1

struct TruthDrone {
  int id;
  double frame_yaw;
  Eigen::Vector3d frame_origin;
};

TruthDrone read_truth_drone(const Json& value, const std::string& path) {
  expect_object(value, path);
  allow_only(value, path, {"id", "frame_yaw", "frame_origin"});
  return {drone_id(need(value, path, "id"), member(path, "id")),
          number(need(value, path, "frame_yaw"), member(path, "frame_yaw")),
          vec3(need(value, path, "frame_origin"), member(path, "frame_origin"))};
}

void read_truth_drones(const Json& value, const std::string& path, Truth* truth) {
  expect_array(value, path);
  std::map<int, std::size_t> seen;
  for (std::size_t i = 0; i < value.size(); ++i) {
    const TruthDrone d = read_truth_drone(value[i], element(path, i));
    note_unique(seen, d.id, path, i, member(element(path, i), "id"));
    truth->ids.push_back(d.id);
    truth->frame_yaw.push_back(d.frame_yaw);
    truth->frame_origin.push_back(d.frame_origin);
  }
}

std::vector<int> read_targets(const Json& value, const std::string& path, const std::set<int>& ids) {
  expect_array(value, path);
  std::vector<int> targets;
  for (std::size_t i = 0; i < value.size(); ++i) {
    const int target = integer(value[i], element(path, i));
    if (target != -1 && !ids.count(target))
      fail(element(path, i), "expected a listed drone id or -1 (false positive), got " + std::to_string(target));
    targets.push_back(target);
  }
  return targets;
}

// One round of truth: every drone's world position and targets, appended in Truth::ids order, and
// its drifted frame (frame_yaw, frame_origin) when the round gives it, in truth->drifted_*; every
// drone of every round gives it, or none does (then drifted_* stay empty).
void read_truth_round(const Json& value, const std::string& path, Truth* truth) {
  expect_object(value, path);
  allow_only(value, path, {"drones"});
  const std::string drones_path = member(path, "drones");
  const Json& drones = need(value, path, "drones");
  expect_object(drones, drones_path);
  const std::set<int> ids(truth->ids.begin(), truth->ids.end());
  check_drone_keys(drones, drones_path, ids);
  truth->positions.emplace_back();
  truth->targets.emplace_back();
  // Whether this round's drones give their drifted frame: as the earlier rounds did, or for the
  // first round as its first drone does.
  std::optional<bool> drifted;
  if (truth->positions.size() > 1) drifted = !truth->drifted_yaw.empty();
  std::vector<double> drifted_yaw;
  std::vector<Eigen::Vector3d> drifted_origin;
  for (int id : truth->ids) {
    const std::string drone_path = drone_member(drones_path, std::to_string(id));
    const auto it = drones.find(std::to_string(id));
    if (it == drones.end())
      fail(drone_path, "drone " + std::to_string(id) + " is missing (truth has every drone in every round)");
    expect_object(*it, drone_path);
    allow_only(*it, drone_path, {"position", "targets", "frame_yaw", "frame_origin"});
    truth->positions.back().push_back(vec3(need(*it, drone_path, "position"), member(drone_path, "position")));
    truth->targets.back().push_back(read_targets(need(*it, drone_path, "targets"), member(drone_path, "targets"), ids));
    const bool has_yaw = it->contains("frame_yaw"), has_origin = it->contains("frame_origin");
    if (!drifted) drifted = has_yaw;
    if (has_yaw != *drifted || has_origin != *drifted)
      fail(drone_path, std::string("frame_yaw and frame_origin (the drifted frame in this round) must be given for every "
                                   "drone of every round or for none; ") + (*drifted ? "missing here" : "given here only"));
    if (!*drifted) continue;
    drifted_yaw.push_back(number((*it)["frame_yaw"], member(drone_path, "frame_yaw")));
    drifted_origin.push_back(vec3((*it)["frame_origin"], member(drone_path, "frame_origin")));
  }
  if (!drifted_yaw.empty()) {
    truth->drifted_yaw.push_back(std::move(drifted_yaw));
    truth->drifted_origin.push_back(std::move(drifted_origin));
  }
}

Obstacle read_obstacle(const Json& value, const std::string& path) {
  expect_object(value, path);
  allow_only(value, path, {"center", "radius", "height"});
  Obstacle o;
  o.center = vec3(need(value, path, "center"), member(path, "center"));
  o.radius = number(need(value, path, "radius"), member(path, "radius"));
  o.height = number(need(value, path, "height"), member(path, "height"));
  return o;
}

// The sizes the encoder relies on: one entry per drone, per round.
void check_truth_shape(const Truth& truth) {
  const std::size_t n = truth.ids.size();
  const auto mismatch = [](const std::string& what, std::size_t got, std::size_t want) {
    fail_encode("Truth", what + " has " + std::to_string(got) + " entries, expected " + std::to_string(want));
  };
  if (truth.frame_yaw.size() != n) mismatch("frame_yaw", truth.frame_yaw.size(), n);
  if (truth.frame_origin.size() != n) mismatch("frame_origin", truth.frame_origin.size(), n);
  if (truth.targets.size() != truth.positions.size()) mismatch("targets", truth.targets.size(), truth.positions.size());
  for (std::size_t k = 0; k < truth.positions.size(); ++k) {
    if (truth.positions[k].size() != n) mismatch(element("positions", k), truth.positions[k].size(), n);
    if (truth.targets[k].size() != n) mismatch(element("targets", k), truth.targets[k].size(), n);
  }
  if (truth.drifted_yaw.empty() && truth.drifted_origin.empty()) return;  // no drifted frames: none written
  if (truth.drifted_yaw.size() != truth.positions.size())
    mismatch("drifted_yaw", truth.drifted_yaw.size(), truth.positions.size());
  if (truth.drifted_origin.size() != truth.positions.size())
    mismatch("drifted_origin", truth.drifted_origin.size(), truth.positions.size());
  for (std::size_t k = 0; k < truth.positions.size(); ++k) {
    if (truth.drifted_yaw[k].size() != n) mismatch(element("drifted_yaw", k), truth.drifted_yaw[k].size(), n);
    if (truth.drifted_origin[k].size() != n) mismatch(element("drifted_origin", k), truth.drifted_origin[k].size(), n);
  }
}

Json write_truth_round(const Truth& truth, std::size_t k, const std::string& path) {
  const std::set<int> ids(truth.ids.begin(), truth.ids.end());
  Json drones = Json::object();
  for (std::size_t i = 0; i < truth.ids.size(); ++i) {
    const std::string drone_path = drone_member(member(path, "drones"), std::to_string(truth.ids[i]));
    Json d;
    d["position"] = finite3(truth.positions[k][i], member(drone_path, "position"));
    if (!truth.drifted_yaw.empty()) {
      d["frame_yaw"] = finite(truth.drifted_yaw[k][i], member(drone_path, "frame_yaw"));
      d["frame_origin"] = finite3(truth.drifted_origin[k][i], member(drone_path, "frame_origin"));
    }
    d["targets"] = Json::array();
    for (std::size_t o = 0; o < truth.targets[k][i].size(); ++o) {
      const int target = truth.targets[k][i][o];
      if (target != -1 && !ids.count(target))
        fail_encode(element(member(drone_path, "targets"), o), "target " + std::to_string(target) + " is neither an id nor -1");
      d["targets"].push_back(target);
    }
    drones[std::to_string(truth.ids[i])] = d;
  }
  return Json{{"drones", drones}};
}

Json write_obstacle(const Obstacle& o, const std::string& path) {
  Json j;
  j["center"] = finite3(o.center, member(path, "center"));
  j["radius"] = finite(o.radius, member(path, "radius"));
  j["height"] = finite(o.height, member(path, "height"));
  return j;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

Rounds rounds_from_json(const std::string& text_in) {
  const Json doc = parse_document(text_in, kRoundsFormat);
  Rounds rounds;
  rounds.drones = id_list(need(doc, "", "drones"), "drones");
  std::sort(rounds.drones.begin(), rounds.drones.end());  // a set: its order carries no meaning
  const std::set<int> listed(rounds.drones.begin(), rounds.drones.end());
  const Json& list = need(doc, "", "rounds");
  expect_array(list, "rounds");
  for (std::size_t k = 0; k < list.size(); ++k)
    rounds.rounds.push_back(read_round(list[k], element("rounds", k), listed));
  return rounds;
}

std::string rounds_to_json(const Rounds& rounds) {
  check_unique_ids(rounds.drones, "drones");
  std::vector<int> ids = rounds.drones;
  std::sort(ids.begin(), ids.end());
  const std::set<int> listed(ids.begin(), ids.end());
  Json doc;
  doc["format"] = kRoundsFormat;
  doc["drones"] = ids;
  doc["rounds"] = Json::array();
  for (std::size_t k = 0; k < rounds.rounds.size(); ++k)
    doc["rounds"].push_back(write_round(rounds.rounds[k], element("rounds", k), listed));
  return dump(doc);
}

Estimate estimate_from_json(const std::string& text_in) {
  const Json doc = parse_document(text_in, kResultFormat);
  Estimate e;
  e.mode = read_mode(need(doc, "", "mode"), "mode");
  e.status = read_status(need(doc, "", "status"), "status");
  e.reason = text(need(doc, "", "reason"), "reason");
  e.reference = integer(need(doc, "", "reference"), "reference");
  if (e.reference < -1) fail("reference", "expected a drone id or -1, got " + std::to_string(e.reference));
  e.rounds_used = integer(need(doc, "", "rounds_used"), "rounds_used");
  if (e.rounds_used < 0) fail("rounds_used", "expected a count >= 0, got " + std::to_string(e.rounds_used));
  e.drones = read_poses(need(doc, "", "drones"), "drones");
  e.unresolved = id_list(need(doc, "", "unresolved"), "unresolved");
  e.certificate = read_certificate(need(doc, "", "certificate"), "certificate");
  e.timing_us = read_timing(need(doc, "", "timing_us"), "timing_us");
  return e;
}

// The parts of an Estimate its decoder checks beyond the numbers.
void check_estimate(const Estimate& e) {
  std::vector<int> ids;
  for (const DronePose& p : e.drones) ids.push_back(p.id);
  check_unique_ids(ids, "drones");
  check_unique_ids(e.unresolved, "unresolved");
  if (e.reference < -1) fail_encode("reference", "it is " + std::to_string(e.reference) + " (a drone id or -1)");
  if (e.rounds_used < 0) fail_encode("rounds_used", "it is " + std::to_string(e.rounds_used) + " (must be >= 0)");
}

std::string estimate_to_json(const Estimate& estimate) {
  check_estimate(estimate);
  Json doc;
  doc["format"] = kResultFormat;
  doc["mode"] = to_string(estimate.mode);
  doc["status"] = to_string(estimate.status);
  doc["reason"] = estimate.reason;
  doc["reference"] = estimate.reference;
  doc["rounds_used"] = estimate.rounds_used;
  doc["drones"] = Json::array();
  for (std::size_t i = 0; i < estimate.drones.size(); ++i)
    doc["drones"].push_back(write_pose(estimate.drones[i], element("drones", i)));
  doc["unresolved"] = estimate.unresolved;
  doc["certificate"] = write_certificate(estimate.certificate);
  doc["timing_us"] = write_timing(estimate.timing_us);
  return dump(doc);
}

Truth truth_from_json(const std::string& text_in) {
  const Json doc = parse_document(text_in, kTruthFormat);
  Truth truth;
  read_truth_drones(need(doc, "", "drones"), "drones", &truth);
  const Json& rounds = need(doc, "", "rounds");
  expect_array(rounds, "rounds");
  for (std::size_t k = 0; k < rounds.size(); ++k) read_truth_round(rounds[k], element("rounds", k), &truth);
  const Json& obstacles = need(doc, "", "obstacles");
  expect_array(obstacles, "obstacles");
  for (std::size_t i = 0; i < obstacles.size(); ++i)
    truth.obstacles.push_back(read_obstacle(obstacles[i], element("obstacles", i)));
  return truth;
}

std::string truth_to_json(const Truth& truth) {
  check_truth_shape(truth);
  check_unique_ids(truth.ids, "drones");
  Json doc;
  doc["format"] = kTruthFormat;
  doc["drones"] = Json::array();
  for (std::size_t i = 0; i < truth.ids.size(); ++i) {
    const std::string path = element("drones", i);
    Json d;
    d["id"] = truth.ids[i];
    d["frame_yaw"] = finite(truth.frame_yaw[i], member(path, "frame_yaw"));
    d["frame_origin"] = finite3(truth.frame_origin[i], member(path, "frame_origin"));
    doc["drones"].push_back(d);
  }
  doc["rounds"] = Json::array();
  for (std::size_t k = 0; k < truth.positions.size(); ++k)
    doc["rounds"].push_back(write_truth_round(truth, k, element("rounds", k)));
  doc["obstacles"] = Json::array();
  for (std::size_t i = 0; i < truth.obstacles.size(); ++i)
    doc["obstacles"].push_back(write_obstacle(truth.obstacles[i], element("obstacles", i)));
  return dump(doc);
}

std::vector<Eigen::Vector3d> positions_from_json(const std::string& text) {
  const Json doc = parse_text(text);
  expect_array(doc, "");
  std::vector<Eigen::Vector3d> out;
  for (std::size_t i = 0; i < doc.size(); ++i) out.push_back(vec3(doc[i], element("", i)));
  return out;
}

CameraIntrinsics intrinsics_from_json(const std::string& text) {
  const Json doc = parse_text(text);
  expect_object(doc, "");
  CameraIntrinsics k;
  for (auto [key, size] : {std::pair{"width", &k.width}, {"height", &k.height}}) {
    const Json& value = need(doc, "", key);
    *size = integer(value, member("", key));
    if (*size < 1 || *size > 8192) fail(member("", key), describe(value) + " is not a whole number 1 … 8192");
  }
  for (auto [key, focal] : {std::pair{"fx", &k.fx}, {"fy", &k.fy}, {"cx", &k.cx}, {"cy", &k.cy}})
    *focal = number(need(doc, "", key), member("", key));
  if (const std::string e = intrinsics_error(k); !e.empty()) throw FormatError(e);  // (it names the field)
  return k;
}

PngFrameName png_frame_name(const std::string& filename, std::string* stem, int64_t* utime) {
  const std::string suffix = "_gray.png";
  if (filename.size() <= suffix.size() ||
      filename.compare(filename.size() - suffix.size(), suffix.size(), suffix) != 0)
    return PngFrameName::other;
  *stem = filename.substr(0, filename.size() - suffix.size());
  if (stem->find_first_not_of("0123456789") != std::string::npos) return PngFrameName::other;
  const auto [end, error] = std::from_chars(stem->data(), stem->data() + stem->size(), *utime);
  return error == std::errc() && end == stem->data() + stem->size() ? PngFrameName::frame : PngFrameName::time_too_large;
}

CameraIntrinsics read_intrinsics_file(const std::string& path) {
  std::string text;
  if (std::string e = read_small_file(path, std::size_t{1} << 20, &text); !e.empty()) throw FormatError(e);
  try {
    return intrinsics_from_json(text);
  } catch (const FormatError& e) {
    throw FormatError(path + ": " + e.what());
  }
}

std::vector<Obstacle> obstacles_from_json(const std::string& text) {
  const Json doc = parse_text(text);
  expect_array(doc, "");
  std::vector<Obstacle> out;
  for (std::size_t i = 0; i < doc.size(); ++i) out.push_back(read_obstacle(doc[i], element("", i)));
  return out;
}

}  // namespace fact
