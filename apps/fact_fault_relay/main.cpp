// fact-fault-relay: a lossy link between one drone and the swarm, for tests and benchmarks on a
// kernel without netem. It joins two LCM URLs — the drone's (where that drone's fact-gossip
// runs) and the swarm's (shared by every drone's relay) — and forwards the given channels
// (default FACT_GOSSIP) both ways, byte for byte. On the directions named by --faults it drops a
// message with probability --drop, sends a second copy with probability --dup (after a random
// delay up to --max-delay-ms), and holds a message back by a random 1 … --max-delay-ms with
// probability --reorder, so later messages overtake it. Every random draw comes from one
// splitmix64 stream seeded by --seed, in message arrival order.
//
// The default --faults to-drone makes each receiving drone lose its own independent share of
// the swarm's traffic (one relay per drone, every packet crosses the receiver's relay once):
// --drop 0.2 is 20% loss per packet per receiver, like a radio where each receiver misses
// different packets. --faults both also loses on the way out (the loss compounds:
// 1 − (1 − p)² end to end).
//
// LCM's udpm delivers a process's own multicast back to it, so the relay remembers a hash of
// every message it publishes (channel + bytes, for 2 s) and does not forward that copy back: a
// message is forwarded once per direction. Identical bytes arriving from elsewhere within those
// 2 s would be taken for an echo; gossip envelopes never repeat (each carries a new sequence
// number), so only true duplicates are affected.
//
// --channel values are LCM channel regexes (GLib's, as LCM compiles them, matching whole names).
// The relay subscribes once per side to every channel and forwards a message when any pattern,
// compiled on its own, matches its channel: a channel that two patterns match is forwarded once
// (two subscriptions forwarded it twice, and each copy's echo was absorbed once: the copies
// bounced between the buses for ever; review, session 32). Hold-backs and echo memory run on the
// monotonic clock (a wall-clock step must not hold messages for the step).
//
// Publishes its counters (fact::app_status_t) on the drone URL's --status-channel.
// Exit codes: 0 on SIGINT/SIGTERM; 2 bad flags; 1 LCM unusable.
#include "common/app.h"
#include "common/cli_checks.h"

#include <CLI/CLI.hpp>
#include <glib.h>
#include <lcm/lcm-cpp.hpp>


#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

namespace {

using fact::app::monotonic_us;
using fact::app::now_us;

// Every parameter, with its unit, in one place.
struct Flags {
  std::string drone_url;                          // the drone's side (its fact-gossip)
  std::string swarm_url;                          // the shared side (every drone's relay)
  std::vector<std::string> channels{"FACT_GOSSIP"};
  double drop = 0;                                // probability per message
  double dup = 0;                                 // probability per message
  double reorder = 0;                             // probability per message
  double max_delay_ms = 40;                       // ms, the largest hold-back (reorder, duplicate)
  uint64_t seed = 1;
  std::string faults = "to-drone";                // to-drone | to-swarm | both
  int drone_id = -1;                              // for the status message only
  std::string status_channel = "FACT_STATUS";
  double status_period = 1.0;                     // s
};

// splitmix64: a small, portable, seedable stream.
class Random {
 public:
  explicit Random(uint64_t seed) : s_(seed) {}
  uint64_t next() {
    uint64_t z = (s_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)

 private:
  uint64_t s_;
};

uint64_t fnv(const std::string& channel, const void* data, size_t size) {
  uint64_t h = 0xcbf29ce484222325ull;
  const auto mix = [&](unsigned char b) {
    h ^= b;
    h *= 0x100000001b3ull;
  };
  for (char c : channel) mix(static_cast<unsigned char>(c));
  mix(0);
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < size; ++i) mix(p[i]);
  return h;
}

enum Side { kDrone = 0, kSwarm = 1 };

class Relay {
 public:
  Relay(const Flags& f, lcm::LCM* drone, lcm::LCM* swarm)
      : f_(f), lcm_{drone, swarm}, random_(f.seed), log_("fact-fault-relay", f.drone_id),
        status_(drone, f.status_channel, "fact-fault-relay", f.drone_id) {
    status_.set_period_us(static_cast<int64_t>(std::llround(f.status_period * 1e6)));
    faulty_[kDrone] = f.faults == "to-drone" || f.faults == "both";  // messages going to the drone
    faulty_[kSwarm] = f.faults == "to-swarm" || f.faults == "both";
  }

  ~Relay() {
    for (GRegex* re : patterns_) g_regex_unref(re);
  }

  // Compiles the patterns (anchored, as LCM would) and subscribes once per side to every channel;
  // "" or the pattern that does not compile. (Joining the patterns into one regex changed what
  // back-references and named groups meant: review, session 32.)
  std::string subscribe() {
    for (const std::string& c : f_.channels) {
      GError* error = nullptr;
      GRegex* re = g_regex_new(("^(?:" + c + ")$").c_str(), static_cast<GRegexCompileFlags>(0),
                               static_cast<GRegexMatchFlags>(0), &error);
      if (re == nullptr) {
        const std::string why = error != nullptr ? error->message : "not a regex";
        if (error != nullptr) g_error_free(error);
        return "--channel " + c + ": not a valid channel regex: " + why;
      }
      patterns_.push_back(re);
    }
    lcm_[kDrone]->subscribe(".*", &Relay::from_drone, this);
    lcm_[kSwarm]->subscribe(".*", &Relay::from_swarm, this);
    return "";
  }

  bool wanted(const std::string& channel) const {
    for (GRegex* re : patterns_)
      if (g_regex_match(re, channel.c_str(), static_cast<GRegexMatchFlags>(0), nullptr)) return true;
    return false;
  }

  const fact::app::Log& log() const { return log_; }

  // Releases held-back messages that are due; returns the wait until the next one (µs, ≤ cap).
  // now: monotonic_us(); the status message is stamped with the wall clock.
  int64_t release(int64_t now, int64_t cap) {
    while (!held_.empty() && held_.begin()->first <= now) {
      const Held& h = held_.begin()->second;
      publish(h.to, h.channel, h.bytes, now);
      held_.erase(held_.begin());
    }
    status_.set_state("held " + std::to_string(held_.size()));
    status_.tick(now_us());
    int64_t wait = cap;
    if (!held_.empty()) wait = std::min(wait, held_.begin()->first - now);
    return std::max<int64_t>(wait, 0);
  }

 private:
  struct Held {
    Side to;
    std::string channel;
    std::vector<uint8_t> bytes;
  };

  void from_drone(const lcm::ReceiveBuffer* rbuf, const std::string& channel) { forward(kDrone, kSwarm, rbuf, channel); }
  void from_swarm(const lcm::ReceiveBuffer* rbuf, const std::string& channel) { forward(kSwarm, kDrone, rbuf, channel); }

  void forget_old_echoes(int64_t now) {
    while (!echo_order_.empty() && (now - echo_order_.front().first > 2000000 || echo_order_.size() > 20000)) {
      const auto [t, key] = echo_order_.front();
      echo_order_.pop_front();
      auto it = echoes_.find(key);
      if (it != echoes_.end() && --it->second <= 0) echoes_.erase(it);
    }
  }

  void publish(Side to, const std::string& channel, const std::vector<uint8_t>& bytes, int64_t now) {
    const uint64_t key = fnv(channel, bytes.data(), bytes.size()) ^ static_cast<uint64_t>(to);
    ++echoes_[key];
    echo_order_.push_back({now, key});
    if (lcm_[to]->publish(channel, bytes.data(), static_cast<unsigned>(bytes.size())) != 0) {
      status_.count("publish_failed");
      return;
    }
    status_.count(to == kSwarm ? "forwarded_to_swarm" : "forwarded_to_drone");
  }

  void forward(Side from, Side to, const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    if (!wanted(channel)) return;
    const int64_t now = monotonic_us();
    forget_old_echoes(now);
    const uint64_t key = fnv(channel, rbuf->data, rbuf->data_size) ^ static_cast<uint64_t>(from);
    auto echo = echoes_.find(key);
    if (echo != echoes_.end()) {  // our own publication, looped back
      if (--echo->second <= 0) echoes_.erase(echo);
      status_.count("echoes_skipped");
      return;
    }
    std::vector<uint8_t> bytes(static_cast<const uint8_t*>(rbuf->data),
                               static_cast<const uint8_t*>(rbuf->data) + rbuf->data_size);
    if (!faulty_[to]) {
      publish(to, channel, bytes, now);
      return;
    }
    // Five draws per faulty message, always, so the stream stays aligned whatever happens.
    const double u_drop = random_.uniform(), u_dup = random_.uniform(), u_reorder = random_.uniform();
    const double u_delay = random_.uniform(), u_dup_delay = random_.uniform();
    if (u_drop < f_.drop) {
      status_.count("dropped");
      return;
    }
    const int64_t max_delay = static_cast<int64_t>(f_.max_delay_ms * 1000);
    if (u_reorder < f_.reorder) {
      status_.count("delayed");
      hold(now + 1000 + static_cast<int64_t>(u_delay * static_cast<double>(std::max<int64_t>(max_delay - 1000, 0))), to,
           channel, bytes);
    } else {
      publish(to, channel, bytes, now);
    }
    if (u_dup < f_.dup) {
      status_.count("duplicated");
      hold(now + static_cast<int64_t>(u_dup_delay * static_cast<double>(max_delay)), to, channel, std::move(bytes));
    }
  }

  void hold(int64_t due, Side to, const std::string& channel, std::vector<uint8_t> bytes) {
    if (held_.size() >= 10000) {  // bounded: a stalled side must not eat memory
      status_.count("dropped_overflow");
      return;
    }
    held_.emplace(due, Held{to, channel, std::move(bytes)});
  }

  Flags f_;
  lcm::LCM* lcm_[2];
  bool faulty_[2] = {false, false};
  Random random_;
  fact::app::Log log_;
  fact::app::Status status_;
  std::multimap<int64_t, Held> held_;
  std::unordered_map<uint64_t, int> echoes_;
  std::deque<std::pair<int64_t, uint64_t>> echo_order_;
  std::vector<GRegex*> patterns_;  // --channel, compiled
};

// The bus a URL names, for telling whether two URLs are one bus: "" is LCM's default; options
// (after '?', e.g. ttl) do not change the bus; a udpm URL without an address is LCM's default group.
std::string bus_of(std::string url) {
  if (url.empty()) {
    const char* env = std::getenv("LCM_DEFAULT_URL");
    url = env != nullptr && *env != '\0' ? env : "udpm://239.255.76.67:7667";
  }
  url = url.substr(0, url.find('?'));
  if (url == "udpm://" || url == "udpm") url = "udpm://239.255.76.67:7667";
  return url;
}

// "" or what is wrong with the flags (naming the flag and the value).
std::string flags_error(const Flags& f) {
  if (bus_of(f.drone_url) == bus_of(f.swarm_url))
    return "--drone-url " + f.drone_url + " and --swarm-url " + f.swarm_url + " are the same bus " + bus_of(f.drone_url) +
           " (the relay would feed itself)";
  for (auto [name, v] : {std::pair{"--drop", f.drop}, {"--dup", f.dup}, {"--reorder", f.reorder}})
    if (!(v >= 0 && v <= 1)) return std::string(name) + ": expected a probability in [0, 1], got " + std::to_string(v);
  if (!(f.max_delay_ms >= 1 && f.max_delay_ms <= 10000))
    return "--max-delay-ms: expected a number in [1, 10000] ms, got " + std::to_string(f.max_delay_ms);
  if (!(f.status_period >= 0.001 && f.status_period <= 3600))  // (as every app: the µs neither 0 nor overflowing)
    return "--status-period: expected a number in [0.001, 3600] s, got " + std::to_string(f.status_period);
  if (f.drone_id < -1) return "--drone-id: expected an id >= 0, got " + std::to_string(f.drone_id);
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  Flags f;
  CLI::App cli{"fact-fault-relay: forwards LCM channels between a drone's URL and the swarm's URL, with seeded "
               "loss, duplication and reordering."};
  cli.add_option("--drone-url", f.drone_url, "LCM URL of the drone side (its fact-gossip)")->required();
  cli.add_option("--swarm-url", f.swarm_url, "LCM URL of the swarm side (shared by every relay)")->required();
  cli.add_option("--channel", f.channels,
                 "Channel(s) to forward (repeatable; LCM channel regexes, e.g. 'FACT_.*'; a channel several match "
                 "is forwarded once)")
      ->capture_default_str();
  cli.add_option("--drop", f.drop, "Probability a message is dropped (0 … 1)")->capture_default_str();
  cli.add_option("--dup", f.dup, "Probability a message is sent twice (0 … 1)")->capture_default_str();
  cli.add_option("--reorder", f.reorder, "Probability a message is held back, overtaken by later ones (0 … 1)")
      ->capture_default_str();
  cli.add_option("--max-delay-ms", f.max_delay_ms, "ms, the longest hold-back (reorder, duplicate copy; 1 … 10000)")
      ->capture_default_str();
  cli.add_option("--seed", f.seed, "Seed of the fault stream (>= 0)")->capture_default_str()->check(fact::app::uint64_text());
  cli.add_option("--faults", f.faults, "Directions with faults: to-drone | to-swarm | both")
      ->capture_default_str()
      ->check(CLI::IsMember({"to-drone", "to-swarm", "both"}));
  cli.add_option("--drone-id", f.drone_id, "Drone id, for the status message and logs")
      ->check(fact::app::decimal_integer());
  cli.add_option("--status-channel", f.status_channel, "Status channel (on the drone URL)")->capture_default_str();
  cli.add_option("--status-period", f.status_period, "s between status messages (0.001 … 3600)")->capture_default_str();
  cli.footer("Exit codes: 0 stopped by SIGINT/SIGTERM; 2 bad flags; 1 LCM unusable.");
  if (const int code = fact::app::parse_command_line(cli, argc, argv); code >= 0) return code;
  fact::app::Log boot("fact-fault-relay", f.drone_id);
  if (const std::string e = flags_error(f); !e.empty()) {
    boot.event("error: " + e);
    return 2;
  }
  lcm::LCM drone(f.drone_url), swarm(f.swarm_url);
  if (!drone.good() || !swarm.good()) {
    boot.event(std::string("LCM is not usable with ") + (!drone.good() ? "--drone-url " + f.drone_url : "--swarm-url " + f.swarm_url));
    return 1;
  }
  fact::app::install_stop_handler();
  Relay relay(f, &drone, &swarm);
  if (const std::string e = relay.subscribe(); !e.empty()) {
    boot.event("error: " + e);
    return 2;
  }
  relay.log().event("started: " + f.drone_url + " <-> " + f.swarm_url + ", drop " + std::to_string(f.drop) + ", dup " +
                    std::to_string(f.dup) + ", reorder " + std::to_string(f.reorder) + " (faults " + f.faults +
                    ", seed " + std::to_string(f.seed) + ")");
  const std::vector<lcm::LCM*> sides = {&drone, &swarm};
  while (!fact::app::stop_requested()) {
    const int64_t wait = relay.release(monotonic_us(), 100000);
    const int r = fact::app::handle_any(sides, wait);
    if (r == -1) {
      relay.log().event(std::string("poll failed: ") + std::strerror(errno));
      return 1;
    }
    if (r == -2 && !fact::app::stop_requested()) {
      relay.log().event("LCM handle failed: stopping");
      return 1;
    }
  }
  relay.log().event("stopping (signal)");
  return 0;
}
