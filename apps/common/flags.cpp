#include "common/flags.h"
#include "common/cli_checks.h"

#include <cmath>
#include <iostream>
#include <sstream>

namespace fact::app {

void add_common_flags(CLI::App& cli, CommonFlags* f, DroneIdFlag drone_id) {
  auto* id = cli.add_option("--drone-id", f->drone_id, "This drone's id (>= 0); names the default channels")
                 ->type_name("ID")->check(fact::app::decimal_integer());
  if (drone_id == DroneIdFlag::required)
    id->required();
  else
    id->capture_default_str();
  cli.add_option("--lcm-url", f->lcm_url, "LCM URL, e.g. udpm://239.255.76.67:7667?ttl=0 (default: LCM's default)")
      ->type_name("URL");
  cli.add_option("--status-channel", f->status_channel, "Status heartbeat channel (fact::app_status_t)")
      ->type_name("CHANNEL")
      ->capture_default_str();
  cli.add_option("--status-period", f->status_period, "Seconds between status messages (0.001 … 3600)")
      ->type_name("S")
      ->capture_default_str();
  cli.add_flag("--sim-clock", f->sim_clock,
               "Take time from the simulator's clock (fact::sim_clock_t on --clock-channel) instead of the wall "
               "clock; waits for its first tick");
  cli.add_option("--clock-channel", f->clock_channel, "Simulation clock channel")
      ->type_name("CHANNEL")
      ->capture_default_str();
}

void check_positive(const char* flag, double value) {
  if (std::isfinite(value) && value > 0) return;
  std::ostringstream s;
  s << flag << ": expected a finite number > 0, got " << value;
  throw FlagError(s.str());
}

void check_range(const char* flag, double value, double lo, double hi, const char* unit) {
  if (value >= lo && value <= hi) return;  // (false for NaN)
  std::ostringstream s;
  s << flag << ": expected a number in [" << lo << ", " << hi << "] " << unit << ", got " << value;
  throw FlagError(s.str());
}

void check_common_flags(const CommonFlags& f, DroneIdFlag drone_id) {
  (void)drone_id;  // (an empty --status-channel or --clock-channel is refused while parsing: refuse_empty_values)
  if (f.drone_id < 0)
    throw FlagError("--drone-id: expected an id >= 0, got " + std::to_string(f.drone_id));
  // 1 ms … 1 h: the period in µs neither rounds to 0 nor overflows (1e13 s gave a 1 µs period).
  check_range("--status-period", f.status_period, 0.001, 3600, "s");
}

bool start_clock(lcm::LCM& lcm, const CommonFlags& f, const Log& log, int timeout_ms) {
  if (!f.sim_clock) return true;
  follow_sim_clock(lcm, f.clock_channel);
  log.event("waiting for the simulation clock on " + f.clock_channel);
  if (wait_for_sim_clock(lcm, timeout_ms)) {
    log.event("simulation clock at " + std::to_string(now_us()) + " us");
    return true;
  }
  // (ticks that arrived but could not be used are named: a foreign type on the channel, a bad time)
  const SimClockTicks dropped = sim_clock_ticks_dropped();
  std::string seen;
  if (dropped.undecodable > 0) seen += ", " + std::to_string(dropped.undecodable) + " undecodable message(s) there";
  if (dropped.refused > 0) seen += ", " + std::to_string(dropped.refused) + " tick(s) at a time not in (0, 5e15] us";
  log.event("error: no simulation clock tick on " + f.clock_channel + " within " + std::to_string(timeout_ms) + " ms" +
            seen);
  return false;
}

int parse_flags(CLI::App& cli, int argc, char** argv, const char* app, const std::function<void()>& check) {
  try {
    refuse_empty_values(cli);
    cli.parse(argc, argv);
    check();
    return -1;
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return cli.exit(e);  // --help
    std::cerr << app << ": error: " << e.what() << " (see --help)\n";
  } catch (const FlagError& e) {
    std::cerr << app << ": error: " << e.what() << " (see --help)\n";
  }
  return 2;
}

}  // namespace fact::app
