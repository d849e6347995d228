// fact-world-v1 (see fact/world_io.h). Reads through checked accessors that carry the JSON path of
// the value they read, so every error names the path and the value (as lib/io/json_io.cpp does).
#include "fact/world_io.h"
#include "fact/file_read.h"

#include "io/json_read.h"

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

using namespace json_read;
constexpr const char* kWorldFormat = "fact-world-v1";

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
    // At most 1 m and 1 rad per √s: a VIO drifting more is no VIO (1000 was taken).
    if (v.contains("drift_position")) w.vio.position = non_negative(v.at("drift_position"), "vio.drift_position");
    if (v.contains("drift_yaw")) w.vio.yaw = non_negative(v.at("drift_yaw"), "vio.drift_yaw");
    if (w.vio.position > 1) fail("vio.drift_position", "expected at most 1 m per √s, got " + fmt(w.vio.position));
    if (w.vio.yaw > 1) fail("vio.drift_yaw", "expected at most 1 rad per √s, got " + fmt(w.vio.yaw));
  }
  return w;
}

sim::World read_world_file(const std::string& path) {
  std::string text;  // (a world file is a few kB; 16 MiB is far beyond any)
  if (std::string e = read_small_file(path, std::size_t{16} << 20, &text); !e.empty())
    throw FormatError(e + " (the world file)");
  try {
    return world_from_json(text);
  } catch (const FormatError& e) {
    throw FormatError(path + ": " + e.what());
  }
}

}  // namespace fact
