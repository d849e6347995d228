// fact-solver: the swarm's complete rounds in (fact::swarm_rounds_t on FACT_SWARM_ROUNDS_<id>, from
// fact-gossip), the relative poses with their certificate out (fact::swarm_result_t on
// FACT_RESULT_<id>), through the same fact::estimate_poses as the offline fact-solve.
//
// It estimates whenever complete_rounds grows beyond the last estimate (up to --rounds, when
// given) or the set of drones changes (a drone joined or went silent); repeats and older messages
// are counted ("stale") and ignored. Messages that arrive while an estimate runs are coalesced:
// only the newest usable one is estimated next.
//
// Deterministic: the published message depends only on the input message and the flags. Its utime
// is the input message's utime (not the clock) and solve_us is 0 unless --publish-solve-time, so
// every drone given the same data, and every replay of a log, publishes the same bytes.
//
// Bad input (a truncated or foreign message, NaN, an unknown drone id, a duplicate packet, a round
// count beyond --max-complete-rounds, a message from another drone's gossip) is counted and logged,
// never fatal. Counters go out on FACT_STATUS (fact::app_status_t, about once a second).
//
// Exit codes: 0 stopped by SIGINT/SIGTERM; 1 LCM failed; 2 bad flags.
#include "common/app.h"
#include "common/convert.h"
#include "common/estimator_flags.h"
#include "common/flags.h"
#include "fact/estimator.h"
#include "fact/memory.h"
#include "fact/swarm_result_t.hpp"
#include "fact/swarm_rounds_t.hpp"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cmath>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

constexpr const char* kApp = "fact-solver";

// Every parameter of the app, with its unit.
struct Options {
  fact::app::CommonFlags common;      // --drone-id (default 0), --lcm-url, status, --sim-clock
  std::string rounds_channel;         // input; empty = FACT_SWARM_ROUNDS_<id>
  std::string result_channel;         // output; empty = FACT_RESULT_<id>
  int max_complete_rounds = 1000;     // a message claiming more complete rounds is rejected (bad input)
  bool publish_solve_time = false;    // fill swarm_result_t.solve_us (breaks bit-identity across drones)
  // Estimator options (mode, rounds, reference, noise model, certification limits), the same
  // flags as fact-solve: common/estimator_flags.h.
  fact::app::EstimatorFlags estimator;
};

using fact::app::FlagError;

void add_flags(CLI::App& app, Options& o) {
  o.common.drone_id = 0;
  fact::app::add_common_flags(app, &o.common, fact::app::DroneIdFlag::optional);
  app.add_option("--rounds-channel", o.rounds_channel, "Input channel (default FACT_SWARM_ROUNDS_<id>)")
      ->type_name("CHANNEL");
  app.add_option("--result-channel", o.result_channel, "Output channel (default FACT_RESULT_<id>)")->type_name("CHANNEL");
  app.add_option("--max-complete-rounds", o.max_complete_rounds,
                 "Reject a message claiming more complete rounds than this (>= 1)")
      ->type_name("K")
      ->capture_default_str()->check(fact::app::decimal_integer());
  app.add_flag("--publish-solve-time", o.publish_solve_time,
               "Fill solve_us with the measured time (then drones' results differ in that field)");
  fact::app::add_estimator_flags(app, o.estimator);
  app.footer(
      "Subscribes to the swarm's complete rounds (fact::swarm_rounds_t, from fact-gossip) and, each\n"
      "time complete_rounds grows or the set of drones changes, publishes fact::swarm_result_t:\n"
      "the yaw (rad) and origin (m) of every drone's odometry frame in the reference drone's frame,\n"
      "with the SDP certificate.\n"
      "The result's utime is the input message's utime and solve_us is 0 (unless\n"
      "--publish-solve-time), so the same data gives the same bytes on every drone and in replays.\n"
      "Noise model: sigma(d) = sqrt(floor^2 + (linear*d + quadratic*d^2)^2 + (bearing*d)^2).\n"
      "Counters (undecodable, invalid_input, stale, results_published, certified, ...) go out on\n"
      "the status channel as fact::app_status_t. One log line per estimate on stderr.\n"
      "Exit codes: 0 stopped by SIGINT/SIGTERM; 1 LCM failed; 2 bad flags.");
}

// Checks the flags and derives the estimator's options.
fact::EstimateOptions check(Options& o) {
  fact::app::check_common_flags(o.common, fact::app::DroneIdFlag::optional);
  if (o.rounds_channel.empty()) o.rounds_channel = fact::app::channel("FACT_SWARM_ROUNDS", o.common.drone_id);
  if (o.result_channel.empty()) o.result_channel = fact::app::channel("FACT_RESULT", o.common.drone_id);
  if (o.max_complete_rounds < 1)
    throw FlagError("--max-complete-rounds: expected >= 1, got " + std::to_string(o.max_complete_rounds));
  try {
    return fact::app::estimator_options(o.estimator);
  } catch (const std::invalid_argument& e) {
    throw FlagError(e.what());
  }
}

// The usable input waiting for the next estimate.
struct Pending {
  int complete_rounds = 0;
  std::vector<int> drone_ids;  // as in the message
  int64_t utime = 0;
  fact::Rounds rounds;
};

class Solver {
 public:
  Solver(lcm::LCM& lcm, const Options& o, const fact::EstimateOptions& e)
      : lcm_(lcm),
        options_(o),
        estimate_options_(e),
        log_(kApp, o.common.drone_id),
        status_(&lcm, o.common.status_channel, kApp, o.common.drone_id) {
    status_.set_period_us(static_cast<int64_t>(std::llround(o.common.status_period * 1e6)));
    status_.set_state("waiting for rounds");
    // Counters the status shows from the start, so a reader sees zeros rather than nothing.
    for (const char* name : {"messages", "undecodable", "invalid_input", "stale", "estimates", "results_published",
                             "certified", "ambiguous", "estimator_invalid_input"})
      status_.count(name, 0);
  }

  void on_rounds(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    status_.count("messages");
    fact::swarm_rounds_t msg;
    if (!fact::app::decode(rbuf, channel, &msg, &status_, log_)) return;
    if (msg.drone_id != options_.common.drone_id) {
      reject("swarm_rounds from drone " + std::to_string(msg.drone_id) + " on " + channel + " (this is drone " +
             std::to_string(options_.common.drone_id) + ")");
      return;
    }
    if (msg.complete_rounds < 1 || msg.complete_rounds > options_.max_complete_rounds) {
      reject("complete_rounds " + std::to_string(msg.complete_rounds) + " on " + channel + " outside [1, " +
             std::to_string(options_.max_complete_rounds) + "]");
      return;
    }
    // New data: another set of drones (one joined or went silent, whatever the round count), or
    // more usable rounds of the same set. Otherwise a repeat, an older message, or rounds beyond
    // --rounds: nothing new.
    const int newest = pending_ ? pending_->complete_rounds : estimated_rounds_;
    const std::vector<int>& newest_ids = pending_ ? pending_->drone_ids : estimated_ids_;
    const std::vector<int> ids(msg.drone_ids.begin(), msg.drone_ids.end());
    if (ids == newest_ids && usable(msg.complete_rounds) <= usable(newest)) {
      status_.count("stale");
      return;
    }
    fact::Rounds rounds;
    const std::string error = fact::app::rounds_from_message(msg, &rounds);
    if (!error.empty()) {
      reject("swarm_rounds on " + channel + ": " + error);
      return;
    }
    pending_ = Pending{msg.complete_rounds, ids, msg.utime, std::move(rounds)};
  }

  // Runs after every wait of the loop: takes every queued message, estimates the newest, publishes
  // the status when due.
  void every(int64_t now) {
    while (lcm_.handleTimeout(0) > 0) {
    }
    if (pending_) {
      Pending p = std::move(*pending_);
      pending_.reset();
      try {
        estimate(p);
      } catch (const std::exception& e) {  // estimate_poses does not throw on bad input: a bug, not fatal
        status_.count("estimator_failed");
        status_.note(std::string("estimator threw: ") + e.what());
        log_.event("estimate of complete_rounds=" + std::to_string(p.complete_rounds) + " failed: estimator threw: " +
                   e.what());
      }
    }
    status_.tick(now);
  }

  void final_status() {
    status_.set_state("stopped");
    status_.publish(fact::app::now_us());
  }

 private:
  // How many of `complete_rounds` rounds the estimator uses (--rounds caps it).
  int usable(int complete_rounds) const {
    const int cap = estimate_options_.max_rounds;
    return cap > 0 && complete_rounds > cap ? cap : complete_rounds;
  }

  // Counted; logged the first 10 times, then every 100th (a flood of bad messages stays readable).
  void reject(const std::string& why) {
    status_.note(why);
    fact::app::count_and_log(status_, log_, "invalid_input", "rejected: " + why);
  }

  void estimate(const Pending& p) {
    const auto start = std::chrono::steady_clock::now();
    const fact::Estimate e = fact::estimate_poses(p.rounds, estimate_options_);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    fact::swarm_result_t result = fact::app::result_to_message(e, options_.common.drone_id, p.utime);
    if (!options_.publish_solve_time) result.solve_us = 0;
    estimated_rounds_ = p.complete_rounds;
    estimated_ids_ = p.drone_ids;
    status_.count("estimates");
    status_.count(e.status == fact::EstimateStatus::certified   ? "certified"
                  : e.status == fact::EstimateStatus::ambiguous ? "ambiguous"
                                                                : "estimator_invalid_input");
    const int published = lcm_.publish(options_.result_channel, &result);
    if (published == 0)
      status_.count("results_published");
    else
      status_.count("publish_failed");

    std::ostringstream line;
    line << "estimate: complete_rounds=" << p.complete_rounds << " rounds_used=" << e.rounds_used
         << " N=" << p.rounds.drones.size() << " mode=" << fact::to_string(e.mode)
         << " status=" << fact::to_string(e.status) << " time_ms=" << ms;
    if (!e.certified()) line << " reason: " << e.reason;
    if (published != 0) line << " (publish on " << options_.result_channel << " failed)";
    log_.event(line.str());
    std::ostringstream note;
    note << "rounds " << p.complete_rounds << ": " << fact::to_string(e.status) << " (" << fact::to_string(e.mode)
         << ") in " << ms << " ms";
    status_.note(note.str());
    status_.set_state(e.certified() ? "certified" : "not certified");
    status_.publish(fact::app::now_us());  // a new result is worth a heartbeat at once
  }

  lcm::LCM& lcm_;
  const Options options_;
  const fact::EstimateOptions estimate_options_;
  fact::app::Log log_;
  fact::app::Status status_;
  int estimated_rounds_ = 0;        // complete_rounds of the last estimate (0 = none yet)
  std::vector<int> estimated_ids_;  // its drone_ids
  std::optional<Pending> pending_;  // the newest usable input not yet estimated
};

}  // namespace

int main(int argc, char** argv) {
  Options options;
  CLI::App app{"Estimates the swarm's relative poses from the complete rounds fact-gossip publishes and\n"
               "publishes them with their certificate (LCM).",
               kApp};
  add_flags(app, options);
  app.get_formatter()->column_width(34);
  fact::EstimateOptions estimate_options;
  if (const int code = fact::app::parse_flags(app, argc, argv, kApp, [&] { estimate_options = check(options); }); code >= 0) return code;

  const fact::app::Log log(kApp, options.common.drone_id);
  if (!fact::keep_freed_memory())  // each round's solve reuses the last one's memory (fact/memory.h)
    log.event("memory policy unavailable on this C library: solves may page-fault their workspace in");
  lcm::LCM lcm(options.common.lcm_url);
  if (!fact::app::lcm_opened(lcm, options.common.lcm_url, log)) return 1;
  fact::app::install_stop_handler();
  if (!fact::app::start_clock(lcm, options.common, log)) return 1;
  Solver solver(lcm, options, estimate_options);
  lcm.subscribe(options.rounds_channel, &Solver::on_rounds, &solver);
  const fact::NoiseModel& noise = estimate_options.noise;
  std::ostringstream model;  // the range model, so a log says which sensor calibration it ran with
  model << "range sigma^2 = " << noise.floor << "^2 + (" << noise.linear << "*d + " << noise.quadratic << "*d^2)^2 m^2";
  log.event("listening on " + options.rounds_channel + ", publishing on " + options.result_channel + " (mode " +
            options.estimator.mode + ", " + model.str() + ")");
  const int code = fact::app::run_loop(lcm, 100, [&](int64_t now) { solver.every(now); });
  solver.final_status();
  log.event(code == 0 ? "stopped" : "stopped: LCM failed");
  return code;
}
