// The simulated world: the fact-world-v1 parser (valid files and each kind of bad input, with the
// JSON path and value in the message), obstacle geometry (ray hits, distances, polytope hulls),
// random drone placement, the committed world files and the drone body model.
#include "fact/sim_world.h"
#include "fact/world_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace {

using fact::sim::Obstacle;
using fact::sim::ObstacleKind;
using fact::sim::World;

const char* kValid = R"({
  "format": "fact-world-v1",
  "room": {"size": [8, 6, 3]},
  "obstacles": [
    {"type": "box", "center": [1, 1, 0.5], "size": [1, 0.5, 1], "yaw": 0.3},
    {"type": "cylinder", "base": [-2, 1, 0], "radius": 0.25, "height": 2},
    {"type": "polytope", "vertices": [[0,0,0],[1,0,0],[0,1,0],[0,0,1],[0.2,0.2,0.2]]}
  ],
  "drones": {"ids": [4, 7], "start": [{"position": [-3, -2, 0], "yaw": 0.5}, {"position": [3, -2, 0]}],
             "height": [1.2, 2.0]},
  "vio": {"drift_position": 0.02, "drift_yaw": 0.001}
})";

// The FormatError message for a document, or "" if it parses.
std::string error_of(const std::string& text) {
  try {
    fact::world_from_json(text);
  } catch (const fact::FormatError& e) {
    return e.what();
  }
  return "";
}

// kValid with one substring replaced.
std::string with(const std::string& from, const std::string& to) {
  std::string s = kValid;
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return s.replace(at, from.size(), to);
}

TEST(SimWorldParse, ValidDocument) {
  const World w = fact::world_from_json(kValid);
  EXPECT_EQ(w.room_size, Eigen::Vector3d(8, 6, 3));
  ASSERT_EQ(w.obstacles.size(), 3u);
  EXPECT_EQ(w.obstacles[0].kind, ObstacleKind::box);
  EXPECT_DOUBLE_EQ(w.obstacles[0].yaw, 0.3);
  EXPECT_EQ(w.obstacles[1].kind, ObstacleKind::cylinder);
  EXPECT_DOUBLE_EQ(w.obstacles[1].cylinder.radius, 0.25);
  EXPECT_EQ(w.obstacles[2].kind, ObstacleKind::polytope);
  EXPECT_EQ(w.obstacles[2].solid.planes.size(), 4u);  // the interior point is not a face
  EXPECT_FALSE(w.drone_config.random_start);
  ASSERT_EQ(w.starts.size(), 2u);
  EXPECT_EQ(w.starts[0].id, 4);
  EXPECT_EQ(w.starts[1].id, 7);
  EXPECT_DOUBLE_EQ(w.starts[0].yaw, 0.5);
  EXPECT_DOUBLE_EQ(w.starts[1].yaw, 0.0);
  EXPECT_EQ(w.starts[1].position, Eigen::Vector3d(3, -2, 0));
  EXPECT_DOUBLE_EQ(w.drone_config.height_min, 1.2);
  EXPECT_DOUBLE_EQ(w.vio.position, 0.02);
  EXPECT_DOUBLE_EQ(w.vio.yaw, 0.001);
  EXPECT_EQ(fact::sim::starts_error(w), "");
}

TEST(SimWorldParse, MinimalDocumentDefaults) {
  World w = fact::world_from_json(R"({"format": "fact-world-v1", "room": {"size": [5, 5, 3]}})");
  EXPECT_TRUE(w.obstacles.empty());
  EXPECT_TRUE(w.drone_config.random_start);
  EXPECT_EQ(w.drone_config.count, 4);
  EXPECT_TRUE(w.starts.empty());
  ASSERT_EQ(fact::sim::place_random_starts(&w, 3), "");
  EXPECT_EQ(w.starts.size(), 4u);
}

struct BadCase {
  std::string text;
  std::string expect1, expect2;  // substrings of the message (the path, the value)
};

TEST(SimWorldParse, EachBadInputNamesPathAndValue) {
  const std::vector<BadCase> cases = {
      {"{", "invalid JSON", ""},
      {R"({"room": {"size": [1,1,1]}})", "format", "missing"},
      {with("fact-world-v1", "fact-world-v2"), "format", "fact-world-v2"},
      {with("\"vio\"", "\"vioo\""), "vioo", "unknown key"},
      {with("\"size\": [8, 6, 3]", "\"size\": [8, 6]"), "room.size", "[8,6]"},
      {with("\"size\": [8, 6, 3]", "\"size\": [8, -6, 3]"), "room.size[1]", "-6"},
      {with("\"size\": [8, 6, 3]", "\"size\": [8, 1e999, 3]"), "room.size", "number"},
      {with("\"radius\": 0.25", "\"radius\": -0.3"), "obstacles[1].radius", "-0.3"},
      {with("\"type\": \"box\"", "\"type\": \"sphere\""), "obstacles[0].type", "sphere"},
      {with("\"center\": [1, 1, 0.5]", "\"center\": [9, 1, 0.5]"), "obstacles[0].center[0]", "outside the room"},
      {with("\"yaw\": 0.3", "\"yaw\": \"x\""), "obstacles[0].yaw", "\"x\""},
      {with("[0.2,0.2,0.2]", "[0.2,0.2,0.2], [0.1, 0.1]"), "obstacles[2].vertices[5]", "[0.1,0.1]"},
      {with("[[0,0,0],[1,0,0],[0,1,0],[0,0,1],[0.2,0.2,0.2]]", "[[0,0,0],[1,0,0],[0,1,0],[1,1,0]]"),
       "obstacles[2].vertices", "no volume"},
      {with("\"ids\": [4, 7]", "\"ids\": [4, 4]"), "drones.ids[1]", "duplicate id 4"},
      {with("\"ids\": [4, 7]", "\"ids\": [4]"), "drones.ids", "1 ids"},
      {with("\"ids\": [4, 7]", "\"ids\": [4, -1]"), "drones.ids[1]", "-1"},
      {with("\"ids\": [4, 7]", "\"count\": 3"), "drones.start", "count is 3"},
      {with("\"position\": [3, -2, 0]", "\"position\": [3, -2, 7]"), "drones.start[1].position[2]", "7"},
      {with("\"position\": [3, -2, 0]", "\"pos\": [3, -2, 0]"), "drones.start[1].pos", "unknown key"},
      {with("\"height\": [1.2, 2.0]", "\"height\": [2.0, 1.2]"), "drones.height", "max < min"},
      {with("\"height\": [1.2, 2.0]", "\"height\": [1.2, 5.0]"), "drones.height[1]", "ceiling"},
      {with("\"drift_yaw\": 0.001", "\"drift_yaw\": -0.001"), "vio.drift_yaw", "-0.001"},
      {with("\"drift_yaw\": 0.001", "\"drift_yaw\": 50"), "vio.drift_yaw", "at most 1 rad per √s, got 50"},
      {with("\"drift_yaw\": 0.001", "\"drift_yaw\": 0.001, \"drift_yaw\": 0.002"), "vio", "duplicate key"},
      {with("\"ids\": [4, 7], \"start\": [{\"position\": [-3, -2, 0], \"yaw\": 0.5}, {\"position\": [3, -2, 0]}]",
            "\"start\": \"grid\""),
       "drones.start", "\"grid\""},
  };
  for (const BadCase& c : cases) {
    const std::string msg = error_of(c.text);
    SCOPED_TRACE(c.text.substr(0, 200));
    ASSERT_FALSE(msg.empty()) << "parsed but should not";
    EXPECT_NE(msg.find(c.expect1), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.expect2), std::string::npos) << msg;
  }
}

TEST(SimWorldParse, UnreadableFileNamesThePath) {
  try {
    fact::read_world_file("/nonexistent/world.json");
    FAIL() << "no error";
  } catch (const fact::FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/world.json"), std::string::npos) << e.what();
  }
}

TEST(SimWorldParse, CommittedWorldsParseAndDefaultMatchesBuiltIn) {
  for (const char* name : {"default.json", "small.json"}) {
    World w = fact::read_world_file(std::string(FACT_WORLDS_DIR) + "/" + name);
    ASSERT_EQ(fact::sim::place_random_starts(&w, w.drone_config.seed), "") << name;
    EXPECT_EQ(fact::sim::starts_error(w), "") << name;
  }
  World file = fact::read_world_file(std::string(FACT_WORLDS_DIR) + "/default.json");
  ASSERT_EQ(fact::sim::place_random_starts(&file, 9), "");
  const World built = fact::sim::default_world(4, 9);
  EXPECT_EQ(file.room_size, built.room_size);
  ASSERT_EQ(file.obstacles.size(), built.obstacles.size());
  for (size_t i = 0; i < built.obstacles.size(); ++i) {
    Eigen::Vector3d a0, a1, b0, b1;
    fact::sim::obstacle_bounds(file.obstacles[i], &a0, &a1);
    fact::sim::obstacle_bounds(built.obstacles[i], &b0, &b1);
    EXPECT_LT((a0 - b0).norm() + (a1 - b1).norm(), 1e-12) << i;
  }
  ASSERT_EQ(file.starts.size(), built.starts.size());
  for (size_t i = 0; i < built.starts.size(); ++i) EXPECT_EQ(file.starts[i].position, built.starts[i].position);
}

// ----------------------------------------------------------------------------------------------
// Geometry

TEST(SimWorldGeometry, RayHitsBoxCylinderPolytope) {
  using fact::sim::Hit;
  using fact::sim::Ray;
  Hit h;
  // Box 1 × 0.5 × 1 at (3, 0, 1), yaw 0: a ray along +x from the origin at z = 1 meets x = 2.5.
  Obstacle box = fact::sim::make_box({3, 0, 1}, {1, 0.5, 1}, 0);
  ASSERT_TRUE(fact::sim::intersect(box, Ray{{0, 0, 1}, {1, 0, 0}}, 0, 100, &h));
  EXPECT_NEAR(h.t, 2.5, 1e-12);
  EXPECT_NEAR((h.normal - Eigen::Vector3d(-1, 0, 0)).norm(), 0, 1e-12);
  EXPECT_FALSE(fact::sim::intersect(box, Ray{{0, 0, 1}, {1, 0, 0}}, 0, 2.4, &h));  // beyond t_max
  EXPECT_FALSE(fact::sim::intersect(box, Ray{{0, 0, 2.6}, {1, 0, 0}}, 0, 100, &h));
  // Yawed 90°: the 0.5 side faces the ray, so the face is at x = 2.75.
  Obstacle box90 = fact::sim::make_box({3, 0, 1}, {1, 0.5, 1}, M_PI / 2);
  ASSERT_TRUE(fact::sim::intersect(box90, Ray{{0, 0, 1}, {2, 0, 0}}, 0, 100, &h));
  EXPECT_NEAR(h.t, 2.75 / 2, 1e-12);  // t scales with the direction's length
  // Cylinder r = 0.5 at (3, 0), 0 … 2 m: side at x = 2.5; the top cap from above.
  Obstacle cyl = fact::sim::make_cylinder({3, 0, 0}, 0.5, 2);
  ASSERT_TRUE(fact::sim::intersect(cyl, Ray{{0, 0, 1}, {1, 0, 0}}, 0, 100, &h));
  EXPECT_NEAR(h.t, 2.5, 1e-12);
  ASSERT_TRUE(fact::sim::intersect(cyl, Ray{{3.1, 0, 3}, {0, 0, -1}}, 0, 100, &h));
  EXPECT_NEAR(h.t, 1.0, 1e-12);
  EXPECT_NEAR(h.normal.z(), 1.0, 1e-12);
  EXPECT_FALSE(fact::sim::intersect(cyl, Ray{{0, 0.6, 1}, {1, 0, 0}}, 0, 100, &h));
  // Tetrahedron (0,0,0), (1,0,0), (0,1,0), (0,0,1): ray along −x at y = z = 0.25 enters x + y + z = 1 at x = 0.5.
  std::string err;
  Obstacle tet = fact::sim::make_polytope({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, &err);
  ASSERT_EQ(err, "");
  ASSERT_TRUE(fact::sim::intersect(tet, Ray{{2, 0.25, 0.25}, {-1, 0, 0}}, 0, 100, &h));
  EXPECT_NEAR(h.t, 1.5, 1e-12);
  EXPECT_NEAR((h.normal - Eigen::Vector3d(1, 1, 1).normalized()).norm(), 0, 1e-12);
  EXPECT_FALSE(fact::sim::intersect(tet, Ray{{2, 0.6, 0.6}, {-1, 0, 0}}, 0, 100, &h));
}

TEST(SimWorldGeometry, Distances) {
  Obstacle box = fact::sim::make_box({0, 0, 1}, {2, 2, 2}, 0.7);
  EXPECT_DOUBLE_EQ(fact::sim::distance(box, {0, 0, 1}), 0.0);
  EXPECT_NEAR(fact::sim::distance(box, {0, 0, 3.5}), 1.5, 1e-12);
  Obstacle cyl = fact::sim::make_cylinder({0, 0, 0}, 1, 2);
  EXPECT_NEAR(fact::sim::distance(cyl, {3, 0, 1}), 2.0, 1e-12);
  EXPECT_NEAR(fact::sim::distance(cyl, {4, 0, 6}), 5.0, 1e-12);  // 3-4-5 to the top rim
  std::string err;
  Obstacle cube = fact::sim::make_polytope({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}}, &err);
  ASSERT_EQ(err, "");
  EXPECT_EQ(cube.solid.planes.size(), 6u);
  EXPECT_NEAR(fact::sim::distance(cube, {0.5, 0.5, 1.7}), 0.7, 1e-12);
}

TEST(SimWorldPlacement, RandomStartsKeepSeparationClearanceAndAreDeterministic) {
  World a = fact::sim::default_world(8, 42), b = fact::sim::default_world(8, 42), c = fact::sim::default_world(8, 43);
  ASSERT_EQ(a.starts.size(), 8u);
  for (size_t i = 0; i < a.starts.size(); ++i) {
    EXPECT_EQ(a.starts[i].position, b.starts[i].position);
    EXPECT_EQ(a.starts[i].yaw, b.starts[i].yaw);
    EXPECT_EQ(a.starts[i].id, static_cast<int>(i));
    EXPECT_EQ(a.starts[i].position.z(), 0.0);
    for (size_t j = 0; j < i; ++j)
      EXPECT_GE((a.starts[i].position - a.starts[j].position).head<2>().norm(), a.drone_config.min_separation);
    for (const auto& o : a.obstacles) {
      EXPECT_GE(fact::sim::distance(o, a.starts[i].position), a.drone_config.clearance);
      EXPECT_GE(fact::sim::distance(o, a.starts[i].position + Eigen::Vector3d(0, 0, 2.5)), a.drone_config.clearance);
    }
    EXPECT_LE(std::abs(a.starts[i].position.x()), 5 - a.drone_config.clearance);
  }
  EXPECT_NE(a.starts[0].position, c.starts[0].position);
  EXPECT_EQ(fact::sim::starts_error(a), "");
}

TEST(SimWorldPlacement, ImpossiblePlacementSaysWhy) {
  World w;
  w.room_size = {2, 2, 3};
  w.drone_config.count = 10;
  const std::string err = fact::sim::place_random_starts(&w, 1);
  EXPECT_NE(err.find("could not place drone"), std::string::npos) << err;
  EXPECT_NE(err.find("min_separation 1"), std::string::npos) << err;
}

TEST(SimWorldStarts, BadStartsAreNamed) {
  World w;
  w.starts = {{0, {0, 0, 0}, 0}, {0, {1, 0, 0}, 0}};
  EXPECT_NE(fact::sim::starts_error(w).find("appears twice"), std::string::npos);
  w.starts = {{0, {0, 0, 0}, 0}, {1, {6, 0, 0}, 0}};
  EXPECT_NE(fact::sim::starts_error(w).find("position[0] = 6"), std::string::npos) << fact::sim::starts_error(w);
  // The body must fit (review, helper-22: these flew without complaint): two drones on one spot,
  // one inside a box, hover heights above a low ceiling.
  w.starts = {{0, {-1, 0, 0}, 0}, {1, {2, 2, 0}, 0}, {2, {-1, 0, 0}, 0}};
  EXPECT_NE(fact::sim::starts_error(w).find("start 2 (drone 2): 0 m from start 0"), std::string::npos)
      << fact::sim::starts_error(w);
  w.starts = {{0, {-1, 0, 0}, 0}, {1, {3, 0, 0.6}, 0}};  // inside the box (z 0.5 … 1.5)
  w.obstacles = {fact::sim::make_box({3, 0, 1}, {1, 0.5, 1}, 0)};
  EXPECT_NE(fact::sim::starts_error(w).find("from obstacle 0, closer than the drone's radius"), std::string::npos)
      << fact::sim::starts_error(w);
  w.obstacles.clear();
  EXPECT_EQ(fact::sim::starts_error(w), "");
  w.starts[1].position = {w.room_size.x() / 2 - 0.1, 0, 0};  // 0.1 m from the wall: it jumped 0.1 m at once
  EXPECT_NE(fact::sim::starts_error(w).find("is closer than the drone's radius 0.207"), std::string::npos)
      << fact::sim::starts_error(w);
  w.starts[1].position = {3, 0, 0};
  w.room_size.z() = 0.5;
  EXPECT_NE(fact::sim::starts_error(w).find("drones.height max 2.5 m is above the ceiling 0.5 m"), std::string::npos)
      << fact::sim::starts_error(w);
  // The hover height counts from the takeoff spot: a start on a box (review, session 33: the drone
  // sat at the ceiling, never airborne) must leave room for it.
  w.room_size.z() = 3;
  w.drone_config.height_min = 1.4, w.drone_config.height_max = 1.5;
  w.starts[1].position = {3, 0, 1.0};
  EXPECT_EQ(fact::sim::starts_error(w), "");
  w.starts[1].position = {3, 0, 1.75};
  EXPECT_NE(fact::sim::starts_error(w).find("start 1 (drone 1): takeoff at z = 1.75 m plus drones.height max 1.5 m is "
                                            "above the ceiling 3 m"),
            std::string::npos)
      << fact::sim::starts_error(w);
}

// Random starts keep the body's radius from the walls and two radii from each other, whatever
// smaller clearance and min_separation a world gives (they are then always valid starts).
TEST(SimWorldPlacement, RandomStartsFitTheBodyWhateverTheClearance) {
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    World w;
    w.room_size = {3, 3, 3};
    w.drone_config.count = 6;
    w.drone_config.clearance = 0.05;
    w.drone_config.min_separation = 0.1;
    ASSERT_EQ(fact::sim::place_random_starts(&w, seed), "") << seed;
    EXPECT_EQ(fact::sim::starts_error(w), "") << "seed " << seed;
  }
}

// ----------------------------------------------------------------------------------------------
// Drone body

TEST(SimBody, PartsAndBoundingRadius) {
  const fact::sim::DroneBody b;
  const auto parts = fact::sim::body_parts(b);
  ASSERT_EQ(parts.size(), 9u);
  int rotors = 0;
  for (const auto& p : parts) {
    if (!p.is_cylinder) continue;
    ++rotors;
    EXPECT_NEAR(p.center.head<2>().norm(), 0.14, 1e-12);
    EXPECT_NEAR(std::abs(p.center.x()), std::abs(p.center.y()), 1e-12);  // on the diagonals
  }
  EXPECT_EQ(rotors, 4);
  const double r = fact::sim::bounding_radius(b);
  EXPECT_NEAR(r, std::hypot(0.14 + 0.065, 0.02 + 0.01), 1e-9);
  EXPECT_GT(r, 0.20);
  EXPECT_LT(r, 0.22);
}

TEST(SimBody, RayHitsHubFrontAndRotorFromAbove) {
  using fact::sim::Hit;
  using fact::sim::Ray;
  const auto parts = fact::sim::body_parts(fact::sim::DroneBody{});
  Hit h;
  ASSERT_TRUE(fact::sim::intersect_body(parts, Ray{{2, 0, 0}, {-1, 0, 0}}, 0, 100, &h));
  EXPECT_NEAR(h.t, 2 - 0.06, 1e-12);  // hub front face at x = 0.06
  EXPECT_NEAR(h.normal.x(), 1.0, 1e-12);
  const double c = 0.14 / std::sqrt(2.0);
  ASSERT_TRUE(fact::sim::intersect_body(parts, Ray{{c, c, 1}, {0, 0, -1}}, 0, 100, &h));
  EXPECT_NEAR(h.t, 1 - 0.03, 1e-12);  // rotor top at z = 0.02 + 0.01
  // Between the arms (along +x, above the hub) nothing is hit.
  EXPECT_FALSE(fact::sim::intersect_body(parts, Ray{{0.12, 0, 1}, {0, 0, -1}}, 0, 100, &h));
}

}  // namespace
