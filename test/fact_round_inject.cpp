// fact_round_inject: one drone's round packets from a fact-rounds-v1 file (fact-simgen) onto LCM as
// fact::round_packet_t on FACT_ROUND_PACKET_<id>, the channel fact-gossip --rounds-from-channel
// reads. Used by test_gossip_multi_host.sh, which runs one per drone network namespace.
//
//   fact_round_inject --lcm-url URL --drone-id ID --input rounds.json [--rounds K] [--repeat N]
//
// Round k of the file becomes round number k; its utime is injected_utime(id, k) below (the same
// rule fact_swarm_rounds_check uses for the expected data). Exit codes: 0 published; 1 LCM failed;
// 2 bad flags or input (unreadable file, drone not in a round).
#include "common/convert.h"
#include "fact/json_io.h"
#include "fact/round_packet_t.hpp"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>

namespace {

struct Options {
  std::string lcm_url;     // LCM provider URL ("" = LCM's default)
  int drone_id = -1;       // the drone whose packets are published
  std::string input;       // fact-rounds-v1 file
  int rounds = 0;          // publish rounds 0 … K−1 (0 = all)
  int repeat = 1;          // publish every packet this many times (duplicates are ignored by gossip)
  double interval = 0.05;  // s between packets
};

int64_t injected_utime(int drone, int round) { return 1700000000000000LL + 1000000LL * round + drone; }

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{"Publishes one drone's round packets (fact::round_packet_t) from a fact-rounds-v1 file"};
  app.add_option("--lcm-url", o.lcm_url, "LCM URL");
  app.add_option("--drone-id", o.drone_id, "Drone id (its packets, channel FACT_ROUND_PACKET_<id>)")->required();
  app.add_option("--input", o.input, "fact-rounds-v1 JSON file")->required();
  app.add_option("--rounds", o.rounds, "Publish rounds 0 … K-1 only (0 = all)")->capture_default_str();
  app.add_option("--repeat", o.repeat, "Times each packet is published (>= 1)")->capture_default_str();
  app.add_option("--interval", o.interval, "Seconds between packets (>= 0)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  if (o.drone_id < 0 || o.rounds < 0 || o.repeat < 1 || !(o.interval >= 0)) {
    std::cerr << "fact_round_inject: bad --drone-id, --rounds, --repeat or --interval\n";
    return 2;
  }
  std::ifstream f(o.input);
  if (!f) {
    std::cerr << "fact_round_inject: cannot read " << o.input << "\n";
    return 2;
  }
  std::stringstream text;
  text << f.rdbuf();
  fact::Rounds rounds;
  try {
    rounds = fact::rounds_from_json(text.str());
  } catch (const std::exception& e) {
    std::cerr << "fact_round_inject: " << o.input << ": " << e.what() << "\n";
    return 2;
  }
  const int k_max = o.rounds > 0 ? o.rounds : static_cast<int>(rounds.rounds.size());
  if (k_max > static_cast<int>(rounds.rounds.size())) {
    std::cerr << "fact_round_inject: the file has only " << rounds.rounds.size() << " rounds\n";
    return 2;
  }
  lcm::LCM lcm(o.lcm_url);
  if (!lcm.good()) {
    std::cerr << "fact_round_inject: LCM is not usable with URL '" << o.lcm_url << "'\n";
    return 1;
  }
  const std::string chan = "FACT_ROUND_PACKET_" + std::to_string(o.drone_id);
  for (int rep = 0; rep < o.repeat; ++rep)
    for (int k = 0; k < k_max; ++k) {
      const auto it = rounds.rounds[k].drones.find(o.drone_id);
      if (it == rounds.rounds[k].drones.end()) {
        std::cerr << "fact_round_inject: drone " << o.drone_id << " is not in round " << k << "\n";
        return 2;
      }
      const fact::round_packet_t m = fact::app::to_message(o.drone_id, k, it->second, injected_utime(o.drone_id, k));
      if (lcm.publish(chan, &m) != 0) {
        std::cerr << "fact_round_inject: publishing on " << chan << " failed\n";
        return 1;
      }
      std::this_thread::sleep_for(std::chrono::duration<double>(o.interval));
    }
  std::cerr << "fact_round_inject: drone " << o.drone_id << ": " << k_max << " round(s) published on " << chan
            << " (x" << o.repeat << ")\n";
  return 0;
}
