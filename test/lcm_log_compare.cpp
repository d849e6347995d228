// fact_lcm_log_compare: the swarm results in two LCM logs (lcm-logger files), compared byte for
// byte. Used by test_replay.sh: the original run's results against those of a fresh solver fed
// the replayed log.
//
//   fact_lcm_log_compare ORIGINAL.lcm REPLAY.lcm CHANNEL [EXPECTED_LAST_STATUS]
//
// Every message on CHANNEL in each log must decode as fact::swarm_result_t; the two logs must hold
// the same number (at least one) and the i-th of each must be the same bytes. With
// EXPECTED_LAST_STATUS, the last result's status must be that (e.g. certified). Prints one line per
// result. Exit codes: 0 identical; 1 different; 2 usage, or a log that cannot be read.
#include <lcm/lcm-cpp.hpp>

#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "fact/swarm_result_t.hpp"

namespace {

struct Entry {
  std::string bytes;
  fact::swarm_result_t result;
};

// The results on `channel` in the log at `path`; false (with a message) if unreadable or undecodable.
bool read_results(const std::string& path, const std::string& channel, std::vector<Entry>* out) {
  lcm::LogFile log(path, "r");
  if (!log.good()) {
    std::cerr << "fact_lcm_log_compare: cannot read " << path << "\n";
    return false;
  }
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (ev->channel != channel) continue;
    Entry e;
    e.bytes.assign(static_cast<const char*>(ev->data), static_cast<std::size_t>(ev->datalen));
    if (e.result.decode(ev->data, 0, ev->datalen) != ev->datalen) {
      std::cerr << "fact_lcm_log_compare: " << path << ": event " << ev->eventnum << " on " << channel
                << " is not a fact::swarm_result_t (" << ev->datalen << " bytes)\n";
      return false;
    }
    out->push_back(std::move(e));
  }
  return true;
}

void print(const char* which, std::size_t i, const Entry& e) {
  const fact::swarm_result_t& r = e.result;
  std::printf("%s[%zu]: utime=%lld drone=%d rounds_used=%d mode=%s status=%s bytes=%zu", which, i,
              static_cast<long long>(r.utime), r.drone_id, r.rounds_used, r.mode.c_str(), r.status.c_str(),
              e.bytes.size());
  for (const auto& d : r.drones) std::printf(" %d:(%.17g,%.17g,%.17g)", d.id, d.yaw, d.position[0], d.position[1]);
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4 && argc != 5) {
    std::cerr << "usage: fact_lcm_log_compare ORIGINAL.lcm REPLAY.lcm CHANNEL [EXPECTED_LAST_STATUS]\n";
    return 2;
  }
  const std::string channel = argv[3];
  std::vector<Entry> original, replay;
  if (!read_results(argv[1], channel, &original) || !read_results(argv[2], channel, &replay)) return 2;
  for (std::size_t i = 0; i < original.size(); ++i) print("original", i, original[i]);
  for (std::size_t i = 0; i < replay.size(); ++i) print("replay", i, replay[i]);
  if (original.empty()) {
    std::cerr << "fact_lcm_log_compare: no result on " << channel << " in " << argv[1] << "\n";
    return 1;
  }
  if (original.size() != replay.size()) {
    std::cerr << "fact_lcm_log_compare: " << original.size() << " results in the original, " << replay.size()
              << " in the replay\n";
    return 1;
  }
  for (std::size_t i = 0; i < original.size(); ++i) {
    if (original[i].bytes != replay[i].bytes) {
      std::cerr << "fact_lcm_log_compare: result " << i << " differs between the original and the replay\n";
      return 1;
    }
  }
  if (argc == 5 && original.back().result.status != argv[4]) {
    std::cerr << "fact_lcm_log_compare: the last result's status is " << original.back().result.status
              << ", expected " << argv[4] << " (" << original.back().result.reason << ")\n";
    return 1;
  }
  std::printf("identical: %zu results on %s\n", original.size(), channel.c_str());
  return 0;
}
