// fact-solve: observation rounds (fact-rounds-v1) in, the swarm's relative poses with their
// certificate (fact-result-v1) out, through the same fact::estimate_poses the apps use.
//
// Exit codes: 0 certified; 3 not certified (the result is still written); 2 invalid input (bad
// flags, unreadable or malformed input, or an invalid_input result, which is still written);
// 1 the output could not be written, or an internal error.
#include "common/cli_checks.h"
#include "fact/file_write.h"
#include "fact/estimator.h"
#include "fact/json_io.h"
#include "common/estimator_flags.h"

#include <CLI/CLI.hpp>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>

namespace {

// Bad flags or bad input: exit code 2.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The output could not be written: exit code 1.
struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Flags {
  std::string input = "-";
  std::string output = "-";
  fact::app::EstimatorFlags estimator;
};

void add_flags(CLI::App& app, Flags& f) {
  app.add_option("--input", f.input, "fact-rounds-v1 file to read; - for stdin")->type_name("FILE")->capture_default_str();
  app.add_option("--output", f.output, "File to write the fact-result-v1 JSON to; - for stdout")
      ->type_name("FILE")
      ->capture_default_str();
  fact::app::add_estimator_flags(app, f.estimator);
  app.footer(
      "Noise model, for a detected centre at range d metres seen a rounds before the latest round\n"
      "used: along the ray sigma^2 = floor^2 + (linear*d + quadratic*d^2)^2 + odom^2; across it\n"
      "sigma^2 = floor^2 + (bearing*d)^2 + odom^2 + (odom_yaw*d)^2, where odom^2 = odometry^2 +\n"
      "a*odometry_walk^2 and odom_yaw^2 = odometry_yaw^2 + a*odometry_yaw_walk^2. Poses are the yaw\n"
      "(rad) and origin (m) of each drone's odometry frame in the reference drone's frame, as\n"
      "during the latest round used.\n"
      "Exit codes: 0 certified; 3 not certified (result written); 2 invalid input: bad flag,\n"
      "unreadable or malformed input, or an invalid_input result (result written); 1 output not\n"
      "written or internal error. One log line goes to stderr.");
}

fact::EstimateOptions options_from(const Flags& f) {
  try {
    return fact::app::estimator_options(f.estimator);
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
}

// The whole stream; `what` names it in errors (a directory, an I/O error).
std::string read_all(std::istream& in, const std::string& what) {
  try {
    std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    if (in.bad()) throw InputError(what + ": read failed");
    return text;
  } catch (const std::ios_base::failure& e) {
    throw InputError(what + ": read failed: " + e.what());
  }
}

std::string read_input(const std::string& name) {
  if (name == "-") return read_all(std::cin, "stdin");
  std::ifstream file(name, std::ios::binary);
  if (!file) throw InputError("--input " + name + ": cannot open: " + std::strerror(errno));
  return read_all(file, "--input " + name);
}

fact::Rounds decode_input(const std::string& name) {
  const std::string text = read_input(name);
  try {
    return fact::rounds_from_json(text);
  } catch (const fact::FormatError& e) {
    throw InputError((name == "-" ? std::string("stdin") : name) + ": " + e.what());
  }
}

void check_reference(int reference, const fact::Rounds& rounds) {
  if (reference < 0) return;
  for (int id : rounds.drones)
    if (id == reference) return;
  std::string ids;
  for (int id : rounds.drones) ids += (ids.empty() ? "" : ", ") + std::to_string(id);
  throw InputError("--reference: drone " + std::to_string(reference) + " is not in the input's drones [" + ids + "]");
}

void write_output(const std::string& name, const std::string& text) {
  if (name == "-") {
    std::cout << text << std::flush;
    if (!std::cout) throw OutputError("stdout: write failed");
    return;
  }
  // Whole or not at all: a full disk used to leave half a result in place of the previous one.
  if (const std::string e = fact::write_file_atomically(name, text); !e.empty()) throw OutputError("--output " + e);
}

int exit_code(fact::EstimateStatus status) {
  switch (status) {
    case fact::EstimateStatus::certified: return 0;
    case fact::EstimateStatus::ambiguous: return 3;
    case fact::EstimateStatus::invalid_input: return 2;
  }
  return 1;
}

void log_run(const fact::Estimate& e, std::size_t drones, double ms) {
  std::ostringstream s;
  s << "fact-solve: mode=" << fact::to_string(e.mode) << " status=" << fact::to_string(e.status)
    << " rounds_used=" << e.rounds_used << " N=" << drones << " time_ms=" << ms;
  if (!e.certified()) s << " reason: " << e.reason;
  std::cerr << s.str() << '\n';
}

int run(const Flags& flags) {
  const fact::EstimateOptions options = options_from(flags);
  const fact::Rounds rounds = decode_input(flags.input);
  check_reference(options.reference, rounds);
  const auto start = std::chrono::steady_clock::now();
  const fact::Estimate estimate = fact::estimate_poses(rounds, options);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  write_output(flags.output, fact::estimate_to_json(estimate));
  log_run(estimate, rounds.drones.size(), ms);
  return exit_code(estimate.status);
}

}  // namespace

int main(int argc, char** argv) {
  Flags flags;
  CLI::App app{"Estimates the relative pose of every drone's odometry frame from observation rounds\n"
               "(fact-rounds-v1 JSON) and writes the result with its certificate (fact-result-v1 JSON).",
               "fact-solve"};
  add_flags(app, flags);
  app.get_formatter()->column_width(32);
  try {
    fact::app::refuse_empty_values(app);
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    std::cerr << "fact-solve: error: " << e.what() << " (see --help)\n";
    return 2;
  }
  try {
    return run(flags);
  } catch (const InputError& e) {
    std::cerr << "fact-solve: error: " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "fact-solve: error: " << e.what() << '\n';
    return 1;
  }
}
