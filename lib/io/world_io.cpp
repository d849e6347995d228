// fact-world-v1 (see fact/world_io.h). Reads through checked accessors that carry the JSON path of
// the value they read, so every error names the path and the value (as lib/io/json_io.cpp does).
#include "fact/world_io.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <set>
#include <sstream>

namespace fact {
namespace {

using Json = nlohmann::ordered_json;
constexpr const char* kWorldFormat = "fact-world-v1";

std::string member(const std::string& path, const std::string& key) {
  bool ident = !key.empty() && !std::isdigit(static_cast<unsigned char>(key[0])) &&
               std::all_of(key.begin(), key.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
  if (!ident) return path + "[" + Json(key).dump() + "]";
  return path.empty() ? key : path + "." + key;
}

std::string element(const std::string& path, std::size_t i) { return path + "[" + std::to_string(i) + "]"; }

std::string describe(const Json& value) {
  std::string text = value.dump();
  if (text.size() <= 60) return text;
  std::size_t cut = 60;
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
  return text.substr(0, cut) + "...";
}

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw FormatError((path.empty() ? std::string("top level") : path) + ": " + what);
}

// Tracks the path during parsing so a repeated key is an error naming it, and a syntax error is
// reported near where it happened.
class PathTracker {
 public:
  bool on_event(Json::parse_event_t event, const Json& parsed) {
    using Event = Json::parse_event_t;
    switch (event) {
      case Event::object_start: levels_.push_back({false, 0, "", {}}); break;
      case Event::array_start: levels_.push_back({true, 0, "", {}}); break;
      case Event::key: {
        Level& l = levels_.back();
        l.key = parsed.get<std::string>();
        if (!l.keys.insert(l.key).second) fail(path(), "duplicate key " + Json(l.key).dump());
        break;
      }
      case Event::value: next(); break;
      case Event::object_end:
      case Event::array_end:
        levels_.pop_back();
        next();
        break;
    }
    return true;
  }
  std::string path() const {
    std::string p;
    for (const Level& l : levels_) p = l.array ? element(p, l.index) : member(p, l.key);
    return p;
  }

 private:
  struct Level {
    bool array;
    std::size_t index;
    std::string key;
    std::set<std::string> keys;
  };
  void next() {
    if (!levels_.empty() && levels_.back().array) ++levels_.back().index;
  }
  std::vector<Level> levels_;
};

Json parse_text(const std::string& text) {
  PathTracker tracker;
  Json::parser_callback_t cb = [&tracker](int, Json::parse_event_t e, Json& parsed) { return tracker.on_event(e, parsed); };
  try {
    return Json::parse(text, cb);
  } catch (const Json::exception& e) {
    std::string message = e.what();
    const std::size_t tag_end = message.find("] ");
    if (tag_end != std::string::npos) message = message.substr(tag_end + 2);
    const std::string near = tracker.path();
    throw FormatError("invalid JSON" + (near.empty() ? "" : " near " + near) + ": " + message);
  }
}

void expect_object(const Json& v, const std::string& path) {
  if (!v.is_object()) fail(path, "expected an object, got " + describe(v));
}

void allow_only(const Json& object, const std::string& path, std::initializer_list<const char*> keys) {
  for (const auto& item : object.items()) {
    if (std::any_of(keys.begin(), keys.end(), [&](const char* k) { return item.key() == k; })) continue;
    std::string list;
    for (const char* k : keys) list += (list.empty() ? "" : ", ") + Json(k).dump();
    fail(member(path, item.key()), "unknown key (allowed: " + list + ")");
  }
}

const Json& need(const Json& object, const std::string& path, const char* key) {
  const auto it = object.find(key);
  if (it == object.end()) fail(member(path, key), "required key is missing");
  return *it;
}

double number(const Json& v, const std::string& path) {
  if (!v.is_number()) fail(path, "expected a number, got " + describe(v));
  const double x = v.get<double>();
  if (!std::isfinite(x)) fail(path, "expected a finite number, got " + describe(v));
  return x;
}

double positive(const Json& v, const std::string& path) {
  const double x = number(v, path);
  if (!(x > 0)) fail(path, "expected a number > 0, got " + describe(v));
  return x;
}

double non_negative(const Json& v, const std::string& path) {
  const double x = number(v, path);
  if (x < 0) fail(path, "expected a number >= 0, got " + describe(v));
  return x;
}

int integer(const Json& v, const std::string& path) {
  if (!v.is_number_integer()) fail(path, "expected an integer, got " + describe(v));
  const bool fits = v.is_number_unsigned() ? v.get<std::uint64_t>() <= static_cast<std::uint64_t>(INT_MAX)
                                           : v.get<std::int64_t>() >= INT_MIN && v.get<std::int64_t>() <= INT_MAX;
  if (!fits) fail(path, "integer out of range, got " + describe(v));
  return v.get<int>();
}

Eigen::Vector3d vec3(const Json& v, const std::string& path) {
  if (!v.is_array() || v.size() != 3) fail(path, "expected 3 numbers, got " + describe(v));
  return {number(v[0], element(path, 0)), number(v[1], element(path, 1)), number(v[2], element(path, 2))};
}

Eigen::Vector3d positive3(const Json& v, const std::string& path) {
  const Eigen::Vector3d x = vec3(v, path);
  for (int k = 0; k < 3; ++k)
    if (!(x[k] > 0)) fail(element(path, static_cast<std::size_t>(k)), "expected a number > 0, got " + describe(v[static_cast<std::size_t>(k)]));
  return x;
}

std::string fmt(double x) { return Json(x).dump(); }

// A point that must lie inside the room (inclusive).
void inside_room(const sim::World& w, const Eigen::Vector3d& p, const std::string& path) {
  const Eigen::Vector3d lo = sim::room_min(w), hi = sim::room_max(w);
  for (int k = 0; k < 3; ++k)
    if (p[k] < lo[k] - 1e-9 || p[k] > hi[k] + 1e-9)
      fail(element(path, static_cast<std::size_t>(k)),
           fmt(p[k]) + " is outside the room [" + fmt(lo[k]) + ", " + fmt(hi[k]) + "]");
}

sim::Obstacle obstacle(const Json& o, const std::string& path, const sim::World& w) {
  expect_object(o, path);
  const Json& type_value = need(o, path, "type");
  if (!type_value.is_string()) fail(member(path, "type"), "expected a string, got " + describe(type_value));
  const std::string type = type_value.get<std::string>();
  if (type == "box") {
    allow_only(o, path, {"type", "center", "size", "yaw"});
    const Eigen::Vector3d c = vec3(need(o, path, "center"), member(path, "center"));
    inside_room(w, c, member(path, "center"));
    const Eigen::Vector3d s = positive3(need(o, path, "size"), member(path, "size"));
    const double yaw = o.contains("yaw") ? number(o.at("yaw"), member(path, "yaw")) : 0.0;
    return sim::make_box(c, s, yaw);
  }
  if (type == "cylinder") {
    allow_only(o, path, {"type", "base", "radius", "height"});
    const Eigen::Vector3d b = vec3(need(o, path, "base"), member(path, "base"));
    inside_room(w, b, member(path, "base"));
    const double r = positive(need(o, path, "radius"), member(path, "radius"));
    const double h = positive(need(o, path, "height"), member(path, "height"));
    return sim::make_cylinder(b, r, h);
  }
  if (type == "polytope") {
    allow_only(o, path, {"type", "vertices"});
    const std::string vpath = member(path, "vertices");
    const Json& vs = need(o, path, "vertices");
    if (!vs.is_array()) fail(vpath, "expected an array of [x, y, z], got " + describe(vs));
    std::vector<Eigen::Vector3d> pts;
    for (std::size_t i = 0; i < vs.size(); ++i) {
      pts.push_back(vec3(vs[i], element(vpath, i)));
      inside_room(w, pts.back(), element(vpath, i));
    }
    std::string err;
    sim::Obstacle p = sim::make_polytope(pts, &err);
    if (!err.empty()) fail(vpath, err);
    return p;
  }
  fail(member(path, "type"), "expected \"box\", \"cylinder\" or \"polytope\", got " + describe(type_value));
}

void drones(const Json& d, const std::string& path, sim::World* w) {
  expect_object(d, path);
  allow_only(d, path, {"count", "ids", "start", "seed", "height", "min_separation", "clearance"});
  sim::DroneConfig& c = w->drone_config;
  bool count_given = false;
  if (d.contains("count")) {
    c.count = integer(d.at("count"), member(path, "count"));
    if (c.count < 1 || c.count > 64) fail(member(path, "count"), "expected 1 ... 64, got " + describe(d.at("count")));
    count_given = true;
  }
  if (d.contains("seed")) {
    const Json& s = d.at("seed");
    if (!s.is_number_unsigned() && !(s.is_number_integer() && s.get<int64_t>() >= 0))
      fail(member(path, "seed"), "expected an integer >= 0, got " + describe(s));
    c.seed = s.get<uint64_t>();
    c.seed_given = true;
  }
  if (d.contains("height")) {
    const std::string hp = member(path, "height");
    const Json& h = d.at("height");
    if (!h.is_array() || h.size() != 2) fail(hp, "expected [min, max], got " + describe(h));
    c.height_min = positive(h[0], element(hp, 0));
    c.height_max = positive(h[1], element(hp, 1));
    if (c.height_max < c.height_min) fail(hp, "max < min: " + describe(h));
    if (c.height_max > w->room_size.z()) fail(element(hp, 1), fmt(c.height_max) + " is above the ceiling " + fmt(w->room_size.z()));
  }
  if (d.contains("min_separation")) c.min_separation = non_negative(d.at("min_separation"), member(path, "min_separation"));
  if (d.contains("clearance")) c.clearance = non_negative(d.at("clearance"), member(path, "clearance"));

  // Starts: "random" (default) or a list whose length is the count.
  std::vector<sim::DroneStart> starts;
  if (d.contains("start")) {
    const std::string sp = member(path, "start");
    const Json& s = d.at("start");
    if (s.is_string()) {
      if (s.get<std::string>() != "random") fail(sp, "expected \"random\" or a list of starts, got " + describe(s));
    } else if (s.is_array()) {
      if (s.empty()) fail(sp, "expected at least one start, got []");
      if (count_given && static_cast<int>(s.size()) != c.count)
        fail(sp, "lists " + std::to_string(s.size()) + " starts but count is " + std::to_string(c.count));
      c.count = static_cast<int>(s.size());
      c.random_start = false;
      for (std::size_t i = 0; i < s.size(); ++i) {
        const std::string ep = element(sp, i);
        expect_object(s[i], ep);
        allow_only(s[i], ep, {"position", "yaw"});
        sim::DroneStart st;
        st.position = vec3(need(s[i], ep, "position"), member(ep, "position"));
        inside_room(*w, st.position, member(ep, "position"));
        st.yaw = s[i].contains("yaw") ? number(s[i].at("yaw"), member(ep, "yaw")) : 0.0;
        starts.push_back(st);
      }
    } else {
      fail(sp, "expected \"random\" or a list of starts, got " + describe(s));
    }
  }
  if (d.contains("ids")) {
    const std::string ip = member(path, "ids");
    const Json& ids = d.at("ids");
    if (!ids.is_array()) fail(ip, "expected an array of drone ids, got " + describe(ids));
    if (static_cast<int>(ids.size()) != c.count)
      fail(ip, "lists " + std::to_string(ids.size()) + " ids but there are " + std::to_string(c.count) + " drones");
    std::set<int> seen;
    for (std::size_t i = 0; i < ids.size(); ++i) {
      const int id = integer(ids[i], element(ip, i));
      if (id < 0) fail(element(ip, i), "expected a drone id >= 0, got " + describe(ids[i]));
      if (!seen.insert(id).second) fail(element(ip, i), "duplicate id " + std::to_string(id));
      c.ids.push_back(id);
    }
  }
  const std::vector<int> ids = sim::drone_ids(c);
  for (std::size_t i = 0; i < starts.size(); ++i) starts[i].id = ids[i];
  w->starts = starts;
}

}  // namespace

sim::World world_from_json(const std::string& text_in) {
  const Json doc = parse_text(text_in);
  expect_object(doc, "");
  allow_only(doc, "", {"format", "room", "obstacles", "drones", "vio", "comment"});
  const Json& f = need(doc, "", "format");
  if (!f.is_string() || f.get<std::string>() != kWorldFormat)
    fail("format", "expected \"" + std::string(kWorldFormat) + "\", got " + describe(f));

  sim::World w;
  w.obstacles.clear();
  const Json& room = need(doc, "", "room");
  expect_object(room, "room");
  allow_only(room, "room", {"size"});
  w.room_size = positive3(need(room, "room", "size"), "room.size");

  if (doc.contains("obstacles")) {
    const Json& obs = doc.at("obstacles");
    if (!obs.is_array()) fail("obstacles", "expected an array, got " + describe(obs));
    for (std::size_t i = 0; i < obs.size(); ++i) w.obstacles.push_back(obstacle(obs[i], element("obstacles", i), w));
  }
  if (doc.contains("drones")) drones(doc.at("drones"), "drones", &w);
  if (doc.contains("vio")) {
    const Json& v = doc.at("vio");
    expect_object(v, "vio");
    allow_only(v, "vio", {"drift_position", "drift_yaw"});
    if (v.contains("drift_position")) w.vio.position = non_negative(v.at("drift_position"), "vio.drift_position");
    if (v.contains("drift_yaw")) w.vio.yaw = non_negative(v.at("drift_yaw"), "vio.drift_yaw");
  }
  return w;
}

sim::World read_world_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FormatError(path + ": cannot open the world file");
  std::ostringstream ss;
  ss << in.rdbuf();
  try {
    return world_from_json(ss.str());
  } catch (const FormatError& e) {
    throw FormatError(path + ": " + e.what());
  }
}

}  // namespace fact
