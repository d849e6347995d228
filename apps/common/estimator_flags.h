// The estimator's command-line flags, shared by fact-solve and fact-solver so both read the same
// options with the same names, units and checks. Header-only (needs CLI11).
#pragma once

#include "common/cli_checks.h"
#include "fact/estimator.h"

#include <CLI/CLI.hpp>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace fact::app {

// Flags as typed, before their checks.
struct EstimatorFlags {
  std::string mode = "auto";
  int rounds = 0;
  int window = 0;
  int reference = -1;
  EstimateOptions options;  // noise model and certification limits, filled in place
};

inline void add_estimator_flags(CLI::App& app, EstimatorFlags& f) {
  NoiseModel& n = f.options.noise;
  app.add_option("--mode", f.mode, "paper, complex, associated, or auto (the first that certifies)")
      ->type_name("MODE")
      ->capture_default_str();
  app.add_option("--rounds", f.rounds, "Use only the first K rounds (0 = all)")->type_name("K")->capture_default_str()
      ->check(fact::app::decimal_integer());
  app.add_option("--window", f.window, "Of those rounds, use only the latest W (0 = all); bounds the VIO drift they span")
      ->type_name("W")
      ->capture_default_str()->check(fact::app::decimal_integer());
  app.add_option("--reference", f.reference, "Id of the reference drone (-1 = lowest id)")
      ->type_name("ID")
      ->capture_default_str()->check(fact::app::decimal_integer());
  app.add_option("--noise-floor", n.floor, "Detector centring error at any range, sigma in m")
      ->type_name("M")
      ->capture_default_str();
  app.add_option("--noise-linear", n.linear, "Range sigma per metre of range (m/m)")->type_name("M/M")->capture_default_str();
  app.add_option("--noise-quadratic", n.quadratic, "Range sigma per square metre of range, stereo depth (1/m)")
      ->type_name("1/M")
      ->capture_default_str();
  app.add_option("--noise-bearing", n.bearing, "Bearing sigma (rad)")->type_name("RAD")->capture_default_str();
  app.add_option("--noise-odometry", n.odometry, "VIO position error within a round, sigma in m")
      ->type_name("M")
      ->capture_default_str();
  app.add_option("--noise-odometry-yaw", n.odometry_yaw, "VIO yaw error within a round, sigma in rad")
      ->type_name("RAD")
      ->capture_default_str();
  app.add_option("--noise-odometry-walk", n.odometry_walk,
                 "VIO position random walk between rounds, sigma in m per sqrt(round)")
      ->type_name("M")
      ->capture_default_str();
  app.add_option("--noise-odometry-yaw-walk", n.odometry_yaw_walk,
                 "VIO yaw random walk between rounds, sigma in rad per sqrt(round)")
      ->type_name("RAD")
      ->capture_default_str();
  app.add_option("--gate", n.gate, "A residual within gate x sigma counts as consistent (sigmas, > 0)")
      ->type_name("X")
      ->capture_default_str();
  app.add_option("--max-yaw-sigma", f.options.max_yaw_sigma, "Certify only when every yaw's 1-sigma is at most this (rad)")
      ->type_name("RAD")
      ->capture_default_str();
  app.add_option("--max-position-sigma", f.options.max_position_sigma,
                 "Certify only when every position's 1-sigma is at most this (m)")
      ->type_name("M")
      ->capture_default_str();
  app.add_option("--min-separation", f.options.min_separation,
                 "Two drones are never closer than this, centre to centre (m)")
      ->type_name("M")
      ->capture_default_str();
}

// Checks the flags and returns the estimator's options; throws std::invalid_argument naming
// the flag and the value.
inline EstimateOptions estimator_options(const EstimatorFlags& f) {
  EstimateOptions o = f.options;
  if (!parse_mode(f.mode, &o.mode))
    throw std::invalid_argument("--mode: expected paper, complex, associated or auto, got \"" + f.mode + "\"");
  if (f.rounds < 0)
    throw std::invalid_argument("--rounds: expected a number of rounds >= 0 (0 = all), got " +
                                std::to_string(f.rounds));
  if (f.window < 0)
    throw std::invalid_argument("--window: expected a number of rounds >= 0 (0 = all), got " + std::to_string(f.window));
  if (f.reference < -1)
    throw std::invalid_argument("--reference: expected a drone id >= 0 (or -1 = lowest), got " +
                                std::to_string(f.reference));
  const auto check = [](const char* flag, double value, bool positive) {
    if (std::isfinite(value) && (positive ? value > 0 : value >= 0)) return;
    std::ostringstream s;
    s << flag << ": expected a finite number " << (positive ? "> 0" : ">= 0") << ", got " << value;
    throw std::invalid_argument(s.str());
  };
  const NoiseModel& n = o.noise;
  check("--noise-floor", n.floor, false);
  check("--noise-linear", n.linear, false);
  check("--noise-quadratic", n.quadratic, false);
  check("--noise-bearing", n.bearing, false);
  check("--noise-odometry", n.odometry, false);
  check("--noise-odometry-yaw", n.odometry_yaw, false);
  check("--noise-odometry-walk", n.odometry_walk, false);
  check("--noise-odometry-yaw-walk", n.odometry_yaw_walk, false);
  check("--gate", n.gate, true);
  check("--max-yaw-sigma", o.max_yaw_sigma, true);
  check("--max-position-sigma", o.max_position_sigma, true);
  check("--min-separation", o.min_separation, false);
  // The flags one by one, then the model as a whole (upper bounds, a σ floor), in the lib's words.
  if (std::string e = check_noise(n); !e.empty()) throw std::invalid_argument("--noise-* / --gate: " + e);
  o.max_rounds = f.rounds;
  o.window = f.window;
  o.reference = f.reference;
  return o;
}

}  // namespace fact::app
