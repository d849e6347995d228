// fact-simgen: generate a simulated swarm's observation rounds (fact-rounds-v1) and, optionally,
// its ground truth (fact-truth-v1), deterministic by seed. The model is fact::generate_scenario's
// (fact/simgen.h). Exit status: 0 written, 2 bad options or unwritable/unreadable files.
#include "common/cli_checks.h"
#include "fact/file_write.h"
#include "fact/json_io.h"
#include "fact/simgen.h"

#include <CLI/CLI.hpp>

#include <charconv>
#include <fstream>
#include <iostream>
#include <map>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace {

// A problem the user can fix: bad options, a file that cannot be read or written (exit 2).
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Command {
  fact::SimOptions sim;
  std::string formation = "random";
  std::string noise = "none";
  std::string ids;             // comma-separated ids; empty = 0 … N−1
  std::string positions_file;  // JSON array of [x, y, z] (world, m)
  std::string obstacles_file;  // JSON array of {"center": [x, y, z], "radius": r, "height": h} (world, m)
  std::string output;          // rounds; empty = stdout
  std::string truth;           // truth; empty = not written
};

void add_swarm_options(CLI::App& app, Command& c) {
  fact::SimOptions& s = c.sim;
  app.add_option("--drones", s.drones, "number of drones N (>= 2)")->check(fact::app::decimal_integer());
  app.add_option("--rounds", s.rounds, "number of observation rounds K (>= 1)")->check(fact::app::decimal_integer());
  app.add_option("--ids", c.ids, "drone ids, comma separated, N unique non-negative integers (default 0..N-1)")
      ->type_name("ID,...");
  app.add_option("--formation", c.formation,
                 "round-0 layout: random (uniform in the room, >= min-separation apart), polygon (regular, "
                 "side = spacing), grid, line (step = spacing), given (--positions); all centred on the origin")
      ->check(CLI::IsMember({"random", "polygon", "grid", "line", "given"}));
  app.add_option("--positions", c.positions_file,
                 "JSON file: array of N [x, y, z] world positions in metres (x, y = takeoff spot, z = height), "
                 "in the order of --ids; implies --formation given")
      ->type_name("FILE");
  app.add_option("--room", s.room, "side of the square room centred on the world origin (m)");
  app.add_option("--spacing", s.spacing, "polygon side, grid and line step (m)");
  app.add_option("--height-min", s.height_min, "lowest hover height (m)");
  app.add_option("--height-max", s.height_max, "highest hover height (m); heights are uniform in [min, max]");
  app.add_flag("--equal-heights", s.equal_heights, "every drone hovers at (height-min + height-max) / 2");
  app.add_option("--min-separation", s.min_separation,
                 "least 3-D distance between drones, kept at takeoff and after every move (m)");
  app.add_option("--move", s.move, "largest horizontal move of a drone between rounds (m); 0 = hover");
}

void add_sensor_options(CLI::App& app, Command& c) {
  fact::SimOptions& s = c.sim;
  app.add_option("--noise", c.noise,
                 "detection noise: none, paper (per-axis sigma = paper-sigma * range), depth (range sigma = "
                 "depth-c * range^2, bearing sigma = depth-b)")
      ->check(CLI::IsMember({"none", "paper", "depth"}));
  app.add_option("--paper-sigma", s.paper_sigma, "paper noise: per-axis sigma per metre of range (dimensionless)");
  app.add_option("--depth-c", s.depth_c, "depth noise: range sigma = depth-c * range^2 (1/m)");
  app.add_option("--depth-b", s.depth_b, "depth noise: azimuth and elevation sigma (rad)");
  app.add_option("--range-limit", s.range_limit, "farthest detectable drone (m); 0 = unlimited");
  app.add_option("--fov", s.fov_horizontal,
                 "horizontal field of view (rad): a detection sits uniformly within +-fov/2 of the heading");
  app.add_option("--obstacles", s.obstacles, "number of random vertical cylinders, 3 m tall")
      ->check(fact::app::decimal_integer());
  app.add_option("--obstacle-radius", s.obstacle_radius, "radius of the random cylinders (m)");
  app.add_option("--given-obstacles", c.obstacles_file,
                 "JSON file: array of vertical cylinders {\"center\": [x, y, z], \"radius\": r, \"height\": h}, "
                 "world metres, center = centre of the base; placed in addition to --obstacles")
      ->type_name("FILE");
  app.add_option("--miss-rate", s.miss_rate, "probability that a visible drone is not detected, in [0, 1]");
  app.add_option("--false-positives", s.false_positives, "mean spurious detections per drone per round (Poisson)");
  app.add_option("--drift-yaw", s.drift_yaw, "VIO yaw random walk: sigma per round (rad)");
  app.add_option("--drift-position", s.drift_position, "VIO position random walk: sigma per round and axis (m)");
  app.add_option("--seed", s.seed, "random seed; the same seed and options give the same files")
      ->check(fact::app::uint64_text());
}

void add_file_options(CLI::App& app, Command& c) {
  app.add_option("--output", c.output, "rounds file to write, fact-rounds-v1 JSON (default: stdout)")
      ->type_name("FILE");
  app.add_option("--truth", c.truth, "ground-truth file to write, fact-truth-v1 JSON (default: none)")
      ->type_name("FILE");
}

std::string read_text(const std::string& path, const std::string& option) {
  std::ifstream in(path);
  if (!in) throw UsageError(option + " " + path + ": cannot open for reading");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The file `path` given to `option`, read by `parse` (fact/json_io.h: the JSON path and value of
// whatever is wrong, a repeated key, nesting deeper than 64 levels, a number beyond a double).
template <class Parse>
auto read_json_file(const std::string& path, const std::string& option, Parse parse) {
  try {
    return parse(read_text(path, option));
  } catch (const fact::FormatError& e) {
    throw UsageError(option + " " + path + ": " + e.what());
  }
}

// A JSON array of [x, y, z] arrays (world, m).
std::vector<Eigen::Vector3d> read_positions(const std::string& path) {
  return read_json_file(path, "--positions", fact::positions_from_json);
}

// A JSON array of {"center": [x, y, z], "radius": r, "height": h} (world, m).
std::vector<fact::Obstacle> read_obstacles(const std::string& path) {
  return read_json_file(path, "--given-obstacles", fact::obstacles_from_json);
}

// "3,5,9" → {3, 5, 9}; every item must be a whole integer.
std::vector<int> parse_ids(const std::string& text) {
  std::vector<int> ids;
  std::stringstream items(text);
  std::string item;
  while (std::getline(items, item, ',')) {
    int id = 0;
    const char* end = item.data() + item.size();
    const auto [stop, error] = std::from_chars(item.data(), end, id);
    if (item.empty() || error != std::errc() || stop != end)
      throw UsageError("--ids " + text + ": '" + item + "' is not an integer");
    ids.push_back(id);
  }
  if (!text.empty() && text.back() == ',') throw UsageError("--ids " + text + ": empty item after the last comma");
  return ids;
}

// Turns the parsed command line into complete SimOptions.
fact::SimOptions sim_options(const Command& c, bool formation_given_explicitly) {
  fact::SimOptions s = c.sim;
  if (!fact::parse_formation(c.formation, &s.formation)) throw UsageError("--formation " + c.formation + ": unknown");
  if (!fact::parse_noise(c.noise, &s.noise)) throw UsageError("--noise " + c.noise + ": unknown");
  s.ids = parse_ids(c.ids);
  if (!c.positions_file.empty()) {
    s.positions = read_positions(c.positions_file);
    if (!formation_given_explicitly) s.formation = fact::Formation::given;
  }
  if (!c.obstacles_file.empty()) s.given_obstacles = read_obstacles(c.obstacles_file);
  return s;
}

// Whole or not at all (fact::write_file_atomically): a failed write leaves an earlier file as it was.
void write_file(const std::string& path, const std::string& text, const std::string& option) {
  if (const std::string e = fact::write_file_atomically(path, text + "\n"); !e.empty()) throw UsageError(option + " " + e);
}

int count_detections(const fact::Rounds& rounds) {
  int n = 0;
  for (const fact::Round& r : rounds.rounds)
    for (const auto& entry : r.drones) n += static_cast<int>(entry.second.observations.size());
  return n;
}

int count_false_positives(const fact::Truth& truth) {
  int n = 0;
  for (const auto& round : truth.targets)
    for (const auto& drone : round)
      for (int target : drone) n += target < 0;
  return n;
}

// generate_scenario's messages name SimOptions fields ("miss_rate = 2: ..."); say the flag the
// user typed instead ("--miss-rate = 2: ..."). Only a field name directly followed by " = " (or
// "[i] = ", "[i].field = ") is rewritten, so words such as "drones" in the prose stay.
std::string with_flag_names(const std::string& message) {
  static const std::map<std::string, std::string> flags = {
      {"drones", "--drones"}, {"rounds", "--rounds"}, {"ids", "--ids"}, {"positions", "--positions"},
      {"room", "--room"}, {"spacing", "--spacing"}, {"height_min", "--height-min"},
      {"height_max", "--height-max"}, {"min_separation", "--min-separation"}, {"move", "--move"},
      {"paper_sigma", "--paper-sigma"}, {"depth_c", "--depth-c"}, {"depth_b", "--depth-b"},
      {"range_limit", "--range-limit"}, {"fov_horizontal", "--fov"}, {"obstacles", "--obstacles"},
      {"obstacle_radius", "--obstacle-radius"}, {"miss_rate", "--miss-rate"},
      {"false_positives", "--false-positives"}, {"drift_yaw", "--drift-yaw"},
      {"drift_position", "--drift-position"}, {"given_obstacles", "--given-obstacles"}};
  static const std::regex reference(R"(\b([a-z_]+)((\[\d+\])?(\.[a-z]+)? = ))");
  std::string out;
  std::size_t copied = 0;
  for (auto it = std::sregex_iterator(message.begin(), message.end(), reference); it != std::sregex_iterator(); ++it) {
    const auto flag = flags.find((*it)[1].str());
    if (flag == flags.end()) continue;
    out += message.substr(copied, it->position(1) - copied) + flag->second;
    copied = it->position(1) + it->length(1);
  }
  return out + message.substr(copied);
}

// Generates and writes each file whole (the rounds, then the truth).
void run(const Command& c, bool formation_given_explicitly) {
  if (!c.output.empty() && !c.truth.empty() && fact::same_file(c.output, c.truth))
    throw UsageError("--truth " + c.truth + ": the same file as --output " + c.output);
  const fact::SimOptions options = sim_options(c, formation_given_explicitly);
  fact::Scenario scenario;
  try {
    scenario = fact::generate_scenario(options);
  } catch (const std::invalid_argument& e) {
    throw UsageError(with_flag_names(e.what()));
  }
  if (c.output.empty()) {
    std::cout << fact::rounds_to_json(scenario.rounds) << '\n' << std::flush;
    if (!std::cout) throw UsageError("stdout: write failed");
  } else {
    write_file(c.output, fact::rounds_to_json(scenario.rounds), "--output");
  }
  // (again now that the rounds file exists: a dangling link named as --output made it --truth's file)
  if (!c.output.empty() && !c.truth.empty() && fact::same_file(c.output, c.truth))
    throw UsageError("--truth " + c.truth + ": the same file as --output " + c.output);
  if (!c.truth.empty()) write_file(c.truth, fact::truth_to_json(scenario.truth), "--truth");
  std::cerr << "fact-simgen: wrote N = " << options.drones << " drones, K = " << options.rounds << " rounds, "
            << count_detections(scenario.rounds) << " detections (false positives: "
            << count_false_positives(scenario.truth) << "), formation " << fact::to_string(options.formation) << ", noise "
            << fact::to_string(options.noise) << ", seed " << options.seed << " to "
            << (c.output.empty() ? "stdout" : c.output) << (c.truth.empty() ? "" : "; truth to " + c.truth)
            << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "fact-simgen: a simulated drone swarm observed over rounds, as fact-rounds-v1 JSON, with its ground truth "
      "(fact-truth-v1) on request. World frame FLU (z up); metres and radians. Deterministic by --seed."};
  app.option_defaults()->always_capture_default();
  app.get_formatter()->column_width(34);
  Command command;
  add_swarm_options(app, command);
  add_sensor_options(app, command);
  add_file_options(app, command);
  try {
    fact::app::refuse_empty_values(app);
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "fact-simgen: " << e.what() << " (see --help)\n";
    return 2;
  }
  try {
    run(command, app.count("--formation") > 0);
  } catch (const UsageError& e) {
    std::cerr << "fact-simgen: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {  // a fault of this program, not of the options
    std::cerr << "fact-simgen: internal error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
