// The flags every LCM app shares, declared once with their units: the drone id, the LCM URL, the
// status heartbeat, and the simulation clock. Each app adds its own flags beside them.
#pragma once

#include "common/app.h"
#include "common/cli_checks.h"  // (decimal_integer, for the apps' integer flags)

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <functional>
#include <stdexcept>
#include <string>

namespace fact::app {

// A bad flag value; the message names the flag and the value. Apps exit 2 with it.
struct FlagError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct CommonFlags {
  int drone_id = -1;                          // this drone's id (>= 0); names per-drone channels
  std::string lcm_url;                        // "" = LCM's default ($LCM_DEFAULT_URL)
  std::string status_channel = "FACT_STATUS"; // fact::app_status_t heartbeat
  double status_period = 1.0;                 // s between heartbeats (0.001 … 3600)
  bool sim_clock = false;                     // take time from the simulator's clock
  std::string clock_channel = "FACT_SIM_CLOCK";  // fact::sim_clock_t
};

enum class DroneIdFlag { required, optional };

// Adds --drone-id, --lcm-url, --status-channel, --status-period, --sim-clock, --clock-channel.
void add_common_flags(CLI::App& cli, CommonFlags* f, DroneIdFlag drone_id);

// Throws FlagError when a value is unusable (e.g. "--status-period: expected a finite number > 0,
// got -1"). --drone-id must be >= 0 (an optional one keeps the default the app set).
void check_common_flags(const CommonFlags& f, DroneIdFlag drone_id);

// Throws FlagError("<flag>: expected a finite number > 0, got <value>") unless value is.
void check_positive(const char* flag, double value);
// Throws FlagError("<flag>: expected a number in [lo, hi] <unit>, got <value>") unless value is.
void check_range(const char* flag, double value, double lo, double hi, const char* unit);

// Parses the command line into cli, then runs check (which throws FlagError for an unusable
// value). Returns -1 when the app should go on, else the code to exit with: 0 after --help, 2 after
// a bad flag, with "<app>: error: <reason> (see --help)" on stderr.
int parse_flags(CLI::App& cli, int argc, char** argv, const char* app, const std::function<void()>& check);

// With --sim-clock: follows the simulation clock on --clock-channel and waits (up to timeout_ms,
// logging that it waits) for its first tick; false, after logging why, when none came.
// Without: nothing to do, true.
bool start_clock(lcm::LCM& lcm, const CommonFlags& f, const Log& log, int timeout_ms = 30000);

}  // namespace fact::app
