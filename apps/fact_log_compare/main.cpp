// fact-log-compare: does a replay match the recorded run? Compares two LCM logs (lcm-logger
// files): every drone's solver results (FACT_RESULT_<id>, fact::swarm_result_t) byte for byte,
// each recorded result against the replay's result for the same input (utime), and every drone's planner decisions (the sequence of "<phase> round <k>" states that
// fact-planner publishes in its FACT_STATUS heartbeat: takeoff, spin, move, done; waits are left
// out, see decision()). scripts/replay.sh
// uses it on the original run's log and the log of fresh processes fed the replayed data.
//
//   fact-log-compare ORIGINAL.lcm REPLAY.lcm [--drones 0,1,2] [--no-planner]
//
// Prints one table row per drone. Exit codes: 0 everything matches; 1 something differs (the row
// says what); 2 bad flags, an unreadable log, no result in the original, or a log that lost
// messages: one holding fewer results (or complete rounds) of a compared drone, between two of
// its fact-solver's (or fact-gossip's) FACT_STATUS heartbeats, than the app's counter
// (results_published, swarm_rounds_published) grew by — a recorder that missed UDP messages,
// which no replay can match. (The app publishes a message before the heartbeat that counts it,
// on the same bus, so one recorder sees them in that order.)
#include "common/cli_checks.h"
#include "common/app.h"
#include "common/log_reader.h"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace {

constexpr const char* kApp = "fact-log-compare";

// What one log says about each drone.
struct DroneTrace {
  std::vector<std::string> result_bytes;  // FACT_RESULT_<id>, in log order
  // The same, by the result's utime (its input's), in log order: one input may give several
  // results (fact-rounds-publish --incremental publishes its rounds with one utime).
  std::map<int64_t, std::vector<std::string>> by_utime;
  std::string last_status, last_reason;   // of the last result
  int last_rounds = 0;
  std::vector<std::string> planner_states;  // "<phase> round <k>", consecutive repeats dropped
  // Messages of one channel against the publishing app's counter, from its first heartbeat in
  // the log on (a log may start after the app did).
  struct Tally {
    bool counting = false;  // a heartbeat with the counter was seen
    int64_t first = 0;      // the counter at the first heartbeat
    int64_t recorded = 0;   // messages in the log since that heartbeat
    int64_t published = 0;  // the counter's growth since then, at the latest heartbeat
    int64_t lost = 0;       // the largest shortfall of recorded against published at a heartbeat
    void message() { recorded += counting; }
    void heartbeat(int64_t counter) {
      if (!counting) {
        counting = true;
        first = counter;
        return;
      }
      published = counter - first;
      lost = std::max(lost, published - recorded);
    }
  };
  Tally results, rounds;  // FACT_RESULT_<id> against fact-solver, FACT_SWARM_ROUNDS_<id> against fact-gossip
};

// "spin round 1: spin 2π ..." → "spin round 1". Not decisions (""): hovers ("hover: odometry
// stale ...") and waits ("wait round 1: ..."), whose presence depends on whether the round's result
// arrived before or after the spin ended, a race between processes, not a choice.
std::string decision(const std::string& state) {
  const std::string head = state.substr(0, state.find(':'));
  if (head.find(" round ") == std::string::npos || head.rfind("wait ", 0) == 0) return "";
  return head;
}

struct Channels {
  std::string result_prefix, rounds_prefix, status;  // "FACT_RESULT_", "FACT_SWARM_ROUNDS_", "FACT_STATUS"
};

bool read_log(const std::string& path, const Channels& ch, std::map<int, DroneTrace>* out) {
  fact::app::LogDecoder dec(kApp);
  const std::string why = fact::app::for_each_log_event(path, kApp, [&](const lcm::LogEvent& e) {
    if (e.channel.rfind(ch.result_prefix, 0) == 0) {
      fact::swarm_result_t m;
      if (!dec.decode(e, &m)) return;
      DroneTrace& t = (*out)[m.drone_id];
      t.results.message();
      t.result_bytes.emplace_back(static_cast<const char*>(e.data), static_cast<size_t>(e.datalen));
      t.by_utime[m.utime].push_back(t.result_bytes.back());
      t.last_status = m.status;
      t.last_reason = m.reason;
      t.last_rounds = m.rounds_used;
    } else if (e.channel.rfind(ch.rounds_prefix, 0) == 0) {
      fact::swarm_rounds_t m;
      if (dec.decode(e, &m)) (*out)[m.drone_id].rounds.message();
    } else if (e.channel == ch.status) {
      fact::app_status_t m;
      if (!dec.decode(e, &m)) return;
      DroneTrace& t = (*out)[m.drone_id];
      if (m.app == "fact-solver")
        if (const auto value = fact::app::counter_value(m, "results_published")) t.results.heartbeat(*value);
      if (m.app == "fact-gossip")
        if (const auto value = fact::app::counter_value(m, "swarm_rounds_published")) t.rounds.heartbeat(*value);
      if (m.app != "fact-planner") return;
      const std::string d = decision(m.state);
      if (!d.empty() && (t.planner_states.empty() || t.planner_states.back() != d)) t.planner_states.push_back(d);
    }
  });
  if (!why.empty()) std::cerr << kApp << ": error: " << why << "\n";
  return why.empty();
}

// Errors for each of drones whose results or rounds in log fall short of what its apps counted.
std::vector<std::string> lost_messages(const std::string& path, std::map<int, DroneTrace>& log,
                                       const std::vector<int>& drones, const Channels& ch) {
  std::vector<std::string> lost;
  for (int id : drones) {
    const auto say = [&](const DroneTrace::Tally& t, const std::string& channel, const char* app, const char* name) {
      if (t.lost <= 0) return;
      lost.push_back(path + ": drone " + std::to_string(id) + ": " + channel + std::to_string(id) + " lacks " +
                     std::to_string(t.lost) + " message(s): " + app + " counted " + std::to_string(t.published) +
                     " published (" + name + ", from its first to its last FACT_STATUS in the log), the log holds " +
                     std::to_string(t.recorded) + ": the recorder lost messages, a replay cannot match");
    };
    say(log[id].results, ch.result_prefix, "fact-solver", "results_published");
    say(log[id].rounds, ch.rounds_prefix, "fact-gossip", "swarm_rounds_published");
  }
  return lost;
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : " → ") + x;
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  std::string original, replay, result_channel = "FACT_RESULT", rounds_channel = "FACT_SWARM_ROUNDS",
                             status_channel = "FACT_STATUS";
  std::vector<int> drones;
  bool no_planner = false;
  CLI::App cli{"fact-log-compare: checks that a replay matches the recorded run: solver results byte for byte,\n"
               "planner decisions (the sequence of phases and rounds, the last one included).",
               kApp};
  cli.add_option("original", original, "LCM log of the recorded run")->required()->type_name("ORIGINAL.lcm");
  cli.add_option("replay", replay, "LCM log of the replay")->required()->type_name("REPLAY.lcm");
  cli.add_option("--drones", drones, "Drone ids to compare (default: every drone with a result in the original)")
      ->delimiter(',')->check(fact::app::decimal_integer());
  cli.add_option("--result-channel", result_channel, "Result channel base (+ _<id>)")->capture_default_str();
  cli.add_option("--rounds-channel", rounds_channel, "Complete-rounds channel base (+ _<id>), counted against fact-gossip's status")
      ->capture_default_str();
  cli.add_option("--status-channel", status_channel, "Status channel (the planners' decisions, the apps' counters)")
      ->capture_default_str();
  cli.add_flag("--no-planner", no_planner, "Compare the results only");
  cli.footer("Exit codes: 0 everything matches; 1 something differs; 2 bad flags, unreadable log, no result, or a log\n"
             "that lost messages (fewer results or rounds of a compared drone than its apps' status counters grew by in it).");
  if (const int code = fact::app::parse_command_line(cli, argc, argv); code >= 0) return code;
  const Channels ch{result_channel + "_", rounds_channel + "_", status_channel};
  std::map<int, DroneTrace> a, b;
  if (!read_log(original, ch, &a) || !read_log(replay, ch, &b)) return 2;
  if (drones.empty())
    for (const auto& [id, t] : a)
      if (!t.result_bytes.empty()) drones.push_back(id);
  if (drones.empty()) {
    std::cerr << kApp << ": error: no result on " << result_channel << "_<id> in " << original << "\n";
    return 2;
  }
  std::vector<std::string> lost = lost_messages(original, a, drones, ch);
  if (replay != original)
    for (const std::string& e : lost_messages(replay, b, drones, ch)) lost.push_back(e);
  for (const std::string& e : lost) std::cerr << kApp << ": error: " << e << "\n";
  if (!lost.empty()) return 2;
  bool all = true;
  std::printf("drone  results orig/replay  identical  last result            planner decisions\n");
  for (int id : drones) {
    if (!a.count(id) || a[id].result_bytes.empty()) {
      std::cerr << kApp << ": error: --drones: drone " << id << " has no result in " << original << "\n";
      return 2;
    }
    const DroneTrace &x = a[id], &y = b[id];
    if (!no_planner && x.planner_states.empty()) {
      std::cerr << kApp << ": error: no planner decisions for drone " << id << " on " << status_channel << " in "
                << original << " (compare the results only with --no-planner)\n";
      return 2;
    }
    // Every recorded result must be in the replay, the same bytes for the same input (utime), each
    // taken once. A replay result the recording lacks is reported, not a difference: under load a
    // recorder can miss a UDP message that the apps themselves received.
    int missing = 0, differing = 0, extra = 0;
    for (const auto& [t, list] : x.by_utime) {
      auto it = y.by_utime.find(t);
      if (it == y.by_utime.end()) {
        missing += static_cast<int>(list.size());
        continue;
      }
      std::vector<std::string> left = it->second;  // the replay's results for this input, not yet matched
      for (const std::string& bytes : list) {
        auto match = std::find(left.begin(), left.end(), bytes);
        if (match == left.end()) ++differing;
        else left.erase(match);
      }
      extra += static_cast<int>(left.size());
    }
    for (const auto& [t, list] : y.by_utime)
      if (x.by_utime.count(t) == 0) extra += static_cast<int>(list.size());
    const bool same_results = missing == 0 && differing == 0;
    const bool same_planner = no_planner || (x.planner_states == y.planner_states && !x.planner_states.empty());
    all = all && same_results && same_planner;
    std::printf("%5d  %7zu / %-7zu      %-9s  %-9s rounds %-3d  %s\n", id, x.result_bytes.size(), y.result_bytes.size(),
                same_results ? "yes" : "NO", x.last_status.c_str(), x.last_rounds,
                no_planner ? "(not compared)" : same_planner ? "same" : "DIFFERENT");
    if (!same_results) std::printf("       %d recorded results differ, %d are missing from the replay\n", differing, missing);
    if (extra > 0) std::printf("       %d replay results for inputs the recording missed (not a difference)\n", extra);
    if (!no_planner) {
      std::printf("       original: %s\n", join(x.planner_states).c_str());
      if (!same_planner) std::printf("       replay:   %s\n", join(y.planner_states).c_str());
    }
  }
  std::printf(all ? "== the replay matches the recorded run\n" : "== the replay DIFFERS from the recorded run\n");
  return all ? 0 : 1;
}
