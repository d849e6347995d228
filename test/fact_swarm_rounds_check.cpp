// fact_swarm_rounds_check: the complete rounds every drone's fact-gossip published, from one LCM log
// per drone (lcm-logger), checked against the rounds that were injected. Used by
// test_gossip_multi_host.sh.
//
//   fact_swarm_rounds_check --input rounds.json --rounds K LOG...
//
// One log per drone of the file, in ascending id order. In the log of drone <id>, the last message
// on FACT_SWARM_ROUNDS_<id> must decode as fact::swarm_rounds_t from drone <id>, hold K complete rounds of every drone of the file, pass
// fact::app::rounds_from_message, and be byte-identical (apart from utime and the publisher's id)
// to the others and to the file's rounds 0 … K−1 as fact_round_inject publishes them. Prints one
// line per log. Exit codes: 0 all complete and identical; 1 not; 2 usage or unreadable input.
#include "common/convert.h"
#include "fact/json_io.h"
#include "fact/swarm_rounds_t.hpp"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace {

int64_t injected_utime(int drone, int round) { return 1700000000000000LL + 1000000LL * round + drone; }

std::string content_bytes(fact::swarm_rounds_t m) {
  m.utime = 0;
  m.drone_id = 0;
  std::string b(static_cast<size_t>(m.getEncodedSize()), '\0');
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

}  // namespace

int main(int argc, char** argv) {
  std::string input;
  int k = 0;
  std::vector<std::string> logs;
  CLI::App app{"Checks every drone's last swarm_rounds_t (one lcm-logger file per drone) against the injected rounds"};
  app.add_option("--input", input, "fact-rounds-v1 JSON file that was injected")->required();
  app.add_option("--rounds", k, "Complete rounds expected (>= 1)")->required();
  app.add_option("logs", logs, "One LCM log per drone")->required();
  CLI11_PARSE(app, argc, argv);

  std::ifstream f(input);
  std::stringstream text;
  text << f.rdbuf();
  fact::Rounds rounds;
  try {
    rounds = fact::rounds_from_json(text.str());
  } catch (const std::exception& e) {
    std::cerr << "fact_swarm_rounds_check: " << input << ": " << e.what() << "\n";
    return 2;
  }
  if (k < 1 || k > static_cast<int>(rounds.rounds.size())) {
    std::cerr << "fact_swarm_rounds_check: --rounds " << k << " out of range\n";
    return 2;
  }
  fact::swarm_rounds_t expected;
  expected.complete_rounds = k;
  expected.num_drones = static_cast<int32_t>(rounds.drones.size());
  expected.drone_ids = rounds.drones;
  for (int id : rounds.drones)
    for (int r = 0; r < k; ++r)
      expected.packets.push_back(fact::app::to_message(id, r, rounds.rounds[r].drones.at(id), injected_utime(id, r)));
  expected.num_packets = static_cast<int32_t>(expected.packets.size());
  const std::string want = content_bytes(expected);

  if (logs.size() != rounds.drones.size()) {
    std::cerr << "fact_swarm_rounds_check: " << logs.size() << " logs for " << rounds.drones.size() << " drones\n";
    return 2;
  }
  bool ok = true;
  for (size_t d = 0; d < logs.size(); ++d) {
    const std::string& path = logs[d];
    const int id = rounds.drones[d];
    const std::string channel = "FACT_SWARM_ROUNDS_" + std::to_string(id);
    lcm::LogFile log(path, "r");
    if (!log.good()) {
      std::cerr << "fact_swarm_rounds_check: cannot read " << path << "\n";
      return 2;
    }
    fact::swarm_rounds_t last;
    std::string last_channel;
    int n = 0;
    while (const lcm::LogEvent* ev = log.readNextEvent()) {
      if (ev->channel != channel) continue;
      fact::swarm_rounds_t m;
      if (m.decode(ev->data, 0, ev->datalen) != ev->datalen) {
        std::cout << path << ": event " << ev->eventnum << " on " << ev->channel << " is not a swarm_rounds_t\n";
        ok = false;
        continue;
      }
      last = m;
      last_channel = ev->channel;
      ++n;
    }
    if (n == 0) {
      std::cout << path << ": no swarm_rounds_t on " << channel << "\n";
      ok = false;
      continue;
    }
    fact::Rounds got;
    const std::string err = fact::app::rounds_from_message(last, &got);
    const bool same = content_bytes(last) == want;
    const bool own = last.drone_id == id;
    std::cout << path << ": " << n << " swarm_rounds_t, last from drone " << last.drone_id << " on " << last_channel
              << ": " << last.complete_rounds << " complete round(s) of " << last.num_drones << " drone(s), "
              << last.num_packets << " packets" << (err.empty() ? "" : ", invalid: " + err)
              << (same ? ", identical to the injected rounds" : ", DIFFERENT from the injected rounds")
              << (own ? "" : ", but drone " + std::to_string(id) + " was expected") << "\n";
    ok = ok && err.empty() && same && own;
  }
  return ok ? 0 : 1;
}
