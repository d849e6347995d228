// Multi-process gossip test: 6 real fact-gossip processes, each behind its own fact-fault-relay
// (20% loss, 10% duplication, 20% reordering towards the drone, seeded), over udpm:// inside ONE
// private network namespace. ctest runs this binary through scripts/netns-run.sh; run by hand
// it refuses to start unless the only network interface is lo (it never multicasts on a real
// network). Layout:
//   drone i's fact-gossip ── udpm://239.255.76.67:(7700+i) ── fact-fault-relay i ──┐
//                                                                                  ├─ udpm://239.255.76.67:7667 (swarm)
//   a 7th fact-gossip (id 9) with a WRONG swarm key, directly on the swarm URL ────┘
// Round packets are injected on FACT_ROUND_PACKET_<id> (--rounds-from-channel). Scenario: rounds
// 0–1 of every drone → all complete; drone 2's gossip is killed (SIGKILL) and restarted empty →
// it recovers everything, its own rounds included, from its peers; rounds 2–3 → all complete.
// Checks: every drone's final swarm_rounds_t is byte-identical (apart from utime and the
// publisher's id) and equal to the injected packets; the wrong-key sender's packets are counted
// as auth_failed and it never becomes a member; the relays really dropped, duplicated and
// delayed; every process exits 0 on SIGTERM.
#include "common/convert.h"
#include "fact/app_status_t.hpp"
#include "fact/detections_t.hpp"
#include "fact/gossip.h"
#include "fact/gossip_challenge_t.hpp"
#include "fact/gossip_packet_t.hpp"
#include "fact/gossip_summary_t.hpp"
#include "fact/odometry_t.hpp"
#include "fact/round_packet_t.hpp"
#include "fact/swarm_rounds_t.hpp"
#include "fact_gossip/wire.h"
#include "test_time.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <algorithm>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace {

constexpr int kDrones = 6;
constexpr int kWrongKeyId = 9;
const std::string kSwarmUrl = "udpm://239.255.76.67:7667?ttl=0";
std::string drone_url(int i) { return "udpm://239.255.76.67:" + std::to_string(7700 + i) + "?ttl=0"; }

// The interfaces of this process's network namespace (/proc/self/net/dev); only "lo" means we
// are inside a private one (scripts/netns-run.sh).
std::string network_interfaces() {
  std::ifstream f("/proc/self/net/dev");
  std::string line, names;
  for (int n = 0; std::getline(f, line); ++n) {
    const auto colon = line.find(':');
    if (n < 2 || colon == std::string::npos) continue;  // two header lines
    std::string name = line.substr(0, colon);
    name.erase(0, name.find_first_not_of(' '));
    names += (names.empty() ? "" : ",") + name;
  }
  return names;
}

int64_t now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

class Processes {
 public:
  ~Processes() {
    for (auto& [name, pid] : pids_) kill(pid, SIGKILL);
    for (auto& [name, pid] : pids_) waitpid(pid, nullptr, 0);
  }
  void start(const std::string& name, const std::vector<std::string>& args, const std::string& log) {
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    pid_t pid = 0;
    const int r = posix_spawn(&pid, args[0].c_str(), &fa, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    ASSERT_EQ(r, 0) << "cannot start " << args[0];
    pids_[name] = pid;
  }
  void kill_now(const std::string& name) {
    kill(pids_.at(name), SIGKILL);
    waitpid(pids_.at(name), nullptr, 0);
    pids_.erase(name);
  }
  // Waits up to `limit` for every process to exit by itself (then SIGKILL); the exit code of each
  // (-1 when it did not exit normally).
  std::map<std::string, int> wait_all(std::chrono::seconds limit) {
    std::map<std::string, int> codes;
    const auto end = std::chrono::steady_clock::now() + limit;
    for (auto& [name, pid] : pids_) {
      int status = 0;
      while (waitpid(pid, &status, WNOHANG) == 0) {
        if (std::chrono::steady_clock::now() >= end) {
          kill(pid, SIGKILL);
          waitpid(pid, &status, 0);
          break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
      codes[name] = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    pids_.clear();
    return codes;
  }
  // SIGTERM everything; the exit code of each (or -1 when it did not exit normally).
  std::map<std::string, int> stop_all() {
    std::map<std::string, int> codes;
    for (auto& [name, pid] : pids_) kill(pid, SIGTERM);
    for (auto& [name, pid] : pids_) {
      int status = 0;
      waitpid(pid, &status, 0);
      codes[name] = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    pids_.clear();
    return codes;
  }

 private:
  std::map<std::string, pid_t> pids_;
};

// Listens on every drone URL and the swarm URL: swarm_rounds_t per drone, status per (app, id).
class Observer {
 public:
  struct Sink {
    Observer* o;
    void swarm_rounds(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      fact::swarm_rounds_t m;
      if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) == static_cast<int>(rbuf->data_size))
        o->latest_rounds[m.drone_id] = m;
    }
    void status(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      fact::app_status_t m;
      if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) != static_cast<int>(rbuf->data_size)) return;
      auto& c = o->counters[{m.app, m.drone_id}];
      for (int k = 0; k < m.num_counters; ++k) c[m.counter_names[k]] = m.counter_values[k];
      o->states[{m.app, m.drone_id}] = m.state;
    }
  };

  explicit Observer(std::vector<std::string> urls) {
    for (const auto& u : urls) {
      auto l = std::make_unique<lcm::LCM>(u);
      good = good && l->good();
      l->subscribe("FACT_SWARM_ROUNDS_.*", &Sink::swarm_rounds, &sink_);
      l->subscribe("FACT_STATUS", &Sink::status, &sink_);
      lcms_.push_back(std::move(l));
    }
  }
  lcm::LCM& at(size_t i) { return *lcms_[i]; }

  // Handles messages for `ms` milliseconds.
  void spin(int ms) {
    const int64_t end = now_us() + ms * 1000LL;
    std::vector<pollfd> fds;
    for (auto& l : lcms_) fds.push_back({l->getFileno(), POLLIN, 0});
    for (int64_t now = now_us(); now < end; now = now_us()) {
      if (poll(fds.data(), fds.size(), static_cast<int>((end - now + 999) / 1000)) <= 0) continue;
      for (size_t i = 0; i < fds.size(); ++i)
        if (fds[i].revents & POLLIN) lcms_[i]->handle();
    }
  }
  // Spins until pred() or `seconds` × FACT_TEST_TIME_SCALE pass; returns pred().
  bool wait_for(const std::function<bool()>& pred, double seconds) {
    const int64_t end = now_us() + static_cast<int64_t>(fact::test::scaled_s(seconds) * 1e6);
    while (!pred() && now_us() < end) spin(50);
    return pred();
  }
  // Spins for `seconds` × FACT_TEST_TIME_SCALE: time for a few more status messages to arrive.
  void settle(double seconds) { spin(static_cast<int>(fact::test::scaled_s(seconds) * 1000)); }
  // Whether each (app, drone id) has published a status (so it has subscribed: the apps
  // subscribe before their loop, which publishes the status).
  bool have_status(const std::vector<std::pair<std::string, int>>& apps) {
    for (const auto& a : apps)
      if (!states.count(a)) return false;
    return true;
  }

  bool good = true;
  std::map<int, fact::swarm_rounds_t> latest_rounds;
  std::map<std::pair<std::string, int>, std::map<std::string, int64_t>> counters;
  std::map<std::pair<std::string, int>, std::string> states;

 private:
  Sink sink_{this};
  std::vector<std::unique_ptr<lcm::LCM>> lcms_;
};

fact::round_packet_t injected(int drone, int round) {
  fact::round_packet_t m;
  m.utime = 1700000000000000 + 1000000LL * round + drone;
  m.drone_id = drone;
  m.round = round;
  m.position[0] = 0.5 * drone;
  m.position[1] = -0.25 * round;
  m.position[2] = 1.5;
  m.yaw = 0.1 * drone - 0.3 * round;
  m.count = 5;
  for (int k = 0; k < m.count; ++k) {
    fact::observation_t o;
    o.odom_position[0] = 0.5 * drone + 0.01 * k;
    o.odom_position[1] = -0.25 * round;
    o.odom_position[2] = 1.5;
    o.odom_yaw = m.yaw + 0.9 * k;
    o.vector[0] = 2.0 + k;
    o.vector[1] = 0.1 * drone - 0.2 * k;
    o.vector[2] = 0.05 * round;
    m.observations.push_back(o);
  }
  return m;
}

// Round `round` of drones 1 and 2 (injected()) on their FACT_ROUND_PACKET_<id>, on obs's first URL.
void inject_drones_1_2(Observer& obs, int round) {
  for (int id : {1, 2}) {
    const fact::round_packet_t m = injected(id, round);
    obs.at(0).publish("FACT_ROUND_PACKET_" + std::to_string(id), &m);
  }
}

// The message without the publisher's own fields, as bytes.
std::vector<uint8_t> content_bytes(fact::swarm_rounds_t m) {
  m.utime = 0;
  m.drone_id = 0;
  return fact::app::encode_bytes(m);
}

std::string tail(const std::string& path, size_t lines) {
  std::ifstream f(path);
  std::vector<std::string> all;
  for (std::string l; std::getline(f, l);) all.push_back(l);
  std::string out;
  for (size_t i = all.size() > lines ? all.size() - lines : 0; i < all.size(); ++i) out += "    " + all[i] + "\n";
  return out;
}

class GossipProcesses : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string nets = network_interfaces();
    if (nets != "lo")
      GTEST_FAIL() << "network interfaces '" << nets << "': run this test inside a private network namespace "
                   << "(scripts/netns-run.sh " << "fact_gossip_process_tests), never on a real network";
    char tmpl[] = "/tmp/fact-gossip-test-XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
    std::ofstream(dir_ + "/swarm.key") << "8f3c6a1d2e4b5f60718293a4b5c6d7e8\n9011223344556677889900aabbccddee\n";
    std::ofstream(dir_ + "/wrong.key") << std::string(32, 'w');  // raw 32 bytes, another key
    log_ = dir_ + "/processes.log";
  }
  void TearDown() override {
    // FACT_TEST_SHOW_LOG=1: the processes' log lines even when the test passes.
    if (HasFailure() || std::getenv("FACT_TEST_SHOW_LOG"))
      std::cerr << "last lines of " << log_ << ":\n" << tail(log_, HasFailure() ? 60 : 400);
    if (!dir_.empty()) std::system(("rm -rf " + dir_).c_str());
  }

  std::vector<std::string> gossip_args(int id, const std::string& url, const std::string& key, bool roster) {
    std::vector<std::string> a{FACT_GOSSIP_BINARY, "--drone-id", std::to_string(id), "--lcm-url", url, "--key-file", key,
                               "--rounds-from-channel", "--min-members", std::to_string(kDrones), "--summary-period",
                               "0.5", "--silence-timeout", "4", "--settle", "0.6", "--status-period", "0.25"};
    if (roster) a.insert(a.end(), {"--roster", "0,1,2,3,4,5"});
    return a;
  }

  std::string dir_, log_;
};

TEST_F(GossipProcesses, LossyRestartedAndAttackedSwarmAgreesByteForByte) {
  std::vector<std::string> urls;
  for (int i = 0; i < kDrones; ++i) urls.push_back(drone_url(i));
  urls.push_back(kSwarmUrl);
  Observer obs(urls);
  ASSERT_TRUE(obs.good) << "LCM udpm unusable (no multicast route?)";

  Processes procs;
  for (int i = 0; i < kDrones; ++i)
    procs.start("relay" + std::to_string(i),
                {FACT_FAULT_RELAY_BINARY, "--drone-url", drone_url(i), "--swarm-url", kSwarmUrl, "--drop", "0.2",
                 "--dup", "0.1", "--reorder", "0.2", "--max-delay-ms", "40", "--seed", std::to_string(100 + i),
                 "--drone-id", std::to_string(i), "--status-period", "0.25"},
                log_);
  for (int i = 0; i < kDrones; ++i)
    procs.start("gossip" + std::to_string(i), gossip_args(i, drone_url(i), dir_ + "/swarm.key", true), log_);
  procs.start("intruder", gossip_args(kWrongKeyId, kSwarmUrl, dir_ + "/wrong.key", false), log_);
  std::vector<std::pair<std::string, int>> apps = {{"fact-gossip", kWrongKeyId}};
  for (int i = 0; i < kDrones; ++i) apps.insert(apps.end(), {{"fact-gossip", i}, {"fact-fault-relay", i}});
  ASSERT_TRUE(obs.wait_for([&] { return obs.have_status(apps); }, 10)) << "not every process is up";
  obs.spin(500);  // the gossips hear each other's summaries

  const auto inject = [&](int round) {
    for (int i = 0; i < kDrones; ++i) {
      const fact::round_packet_t m = injected(i, round);
      obs.at(static_cast<size_t>(i)).publish("FACT_ROUND_PACKET_" + std::to_string(i), &m);
    }
    const fact::round_packet_t m = injected(kWrongKeyId, round);
    obs.at(kDrones).publish("FACT_ROUND_PACKET_" + std::to_string(kWrongKeyId), &m);
  };
  const auto all_complete = [&](int rounds) {
    for (int i = 0; i < kDrones; ++i) {
      auto it = obs.latest_rounds.find(i);
      if (it == obs.latest_rounds.end() || it->second.complete_rounds != rounds) return false;
    }
    return true;
  };

  // Rounds 0 and 1.
  inject(0);
  obs.spin(100);
  inject(1);
  ASSERT_TRUE(obs.wait_for([&] { return all_complete(2); }, 10)) << "rounds 0–1 not complete everywhere";

  // Drone 2's gossip dies and restarts with nothing.
  procs.kill_now("gossip2");
  obs.latest_rounds.erase(2);
  obs.spin(300);
  procs.start("gossip2", gossip_args(2, drone_url(2), dir_ + "/swarm.key", true), log_);
  ASSERT_TRUE(obs.wait_for([&] { return obs.latest_rounds.count(2) && obs.latest_rounds[2].complete_rounds == 2; }, 10))
      << "the restarted gossip did not recover rounds 0–1";
  const std::vector<uint8_t> recovered = content_bytes(obs.latest_rounds[2]);
  EXPECT_EQ(recovered, content_bytes(obs.latest_rounds[0])) << "the restarted gossip recovered different data";

  // Rounds 2 and 3.
  inject(2);
  obs.spin(100);
  inject(3);
  ASSERT_TRUE(obs.wait_for([&] { return all_complete(4); }, 10)) << "rounds 0–3 not complete everywhere";
  obs.settle(0.7);  // a few more status messages

  // Byte-identical, and exactly what was injected (drones ascending, then rounds).
  fact::swarm_rounds_t expected;
  expected.complete_rounds = 4;
  expected.num_drones = kDrones;
  for (int i = 0; i < kDrones; ++i) expected.drone_ids.push_back(i);
  for (int i = 0; i < kDrones; ++i)
    for (int r = 0; r < 4; ++r) expected.packets.push_back(injected(i, r));
  expected.num_packets = static_cast<int32_t>(expected.packets.size());
  const std::vector<uint8_t> want = content_bytes(expected);
  for (int i = 0; i < kDrones; ++i) {
    EXPECT_EQ(content_bytes(obs.latest_rounds[i]), want) << "drone " << i << "'s swarm_rounds_t differs";
    fact::Rounds rounds;
    EXPECT_EQ(fact::app::rounds_from_message(obs.latest_rounds[i], &rounds), "");
    EXPECT_EQ(rounds.rounds.size(), 4u);
  }

  // Counters, from the status messages.
  const auto gossip = [&](int id) -> std::map<std::string, int64_t>& { return obs.counters[{"fact-gossip", id}]; };
  const auto state = [&](int id) { return obs.states[{"fact-gossip", id}]; };
  int64_t auth_failed = 0, duplicates = 0;
  for (int i = 0; i < kDrones; ++i) {
    auto& g = gossip(i);
    auth_failed += g["auth_failed"];
    duplicates += g["duplicate_envelopes"] + g["duplicate_rounds"];
    EXPECT_GT(g["packets_sent"], 0) << "drone " << i;
    EXPECT_EQ(g["digest_mismatches"], 0) << "drone " << i;
    EXPECT_EQ(state(i).find("9:"), std::string::npos) << "the intruder became a member of drone " << i;
    auto& r = obs.counters[{"fact-fault-relay", i}];
    EXPECT_GT(r["dropped"], 0) << "relay " << i;
    EXPECT_GT(r["duplicated"], 0) << "relay " << i;
    EXPECT_GT(r["delayed"], 0) << "relay " << i;
  }
  EXPECT_GT(auth_failed, 0) << "no wrong-key packet was counted";
  EXPECT_GT(duplicates, 0);
  EXPECT_GT(gossip(2)["requests_sent"], 0) << "the restarted gossip never requested";
  EXPECT_GT(gossip(kWrongKeyId)["auth_failed"], 0) << "the intruder accepted the swarm's packets";
  EXPECT_EQ(obs.latest_rounds.count(kWrongKeyId), 0u);

  for (const auto& [name, code] : procs.stop_all()) EXPECT_EQ(code, 0) << name << " did not exit cleanly";
}

// --swarm-url: each gossip reads its rounds and publishes the complete data on its own drone's
// bus, and only FACT_GOSSIP crosses the swarm bus, as run-sim.sh and run-drone.sh use it. No relay
// joins the buses here: the two gossips can only meet on the swarm bus.
TEST_F(GossipProcesses, OnlyTheGossipCrossesTheSwarmBus) {
  Observer drones({drone_url(0), drone_url(1)});
  ASSERT_TRUE(drones.good);
  std::map<std::string, int> swarm_channels;  // what the swarm bus carried, by channel
  lcm::LCM swarm(kSwarmUrl);
  ASSERT_TRUE(swarm.good());
  swarm.subscribeFunction(
      ".*", +[](const lcm::ReceiveBuffer*, const std::string& channel, std::map<std::string, int>* seen) { ++(*seen)[channel]; },
      &swarm_channels);
  Processes procs;
  for (int i = 0; i < 2; ++i) {
    std::vector<std::string> a = gossip_args(i, drone_url(i), dir_ + "/swarm.key", false);
    a.insert(a.end(), {"--swarm-url", kSwarmUrl});
    a[std::find(a.begin(), a.end(), "--min-members") - a.begin() + 1] = "2";
    procs.start("gossip" + std::to_string(i), a, log_);
  }
  ASSERT_TRUE(drones.wait_for([&] { return drones.have_status({{"fact-gossip", 0}, {"fact-gossip", 1}}); }, 10))
      << "the gossips are not up";
  drones.spin(500);
  for (int round = 0; round < 2; ++round)
    for (int i = 0; i < 2; ++i) {
      const fact::round_packet_t m = injected(i, round);
      drones.at(static_cast<size_t>(i)).publish("FACT_ROUND_PACKET_" + std::to_string(i), &m);
    }
  const auto complete = [&] {
    for (int i = 0; i < 2; ++i)
      if (!drones.latest_rounds.count(i) || drones.latest_rounds[i].complete_rounds != 2) return false;
    return true;
  };
  const int64_t end = now_us() + static_cast<int64_t>(fact::test::scaled_s(10) * 1e6);
  while (!complete() && now_us() < end) {
    drones.spin(20);
    while (swarm.handleTimeout(0) > 0) {
    }
  }
  ASSERT_TRUE(complete()) << "the two drones did not complete rounds 0–1 over the swarm bus";
  drones.settle(0.5);
  while (swarm.handleTimeout(0) > 0) {
  }
  // Both hold the same packets: drone 0's complete data holds drone 1's rounds, which only the
  // swarm bus could have brought.
  EXPECT_EQ(drones.latest_rounds[0].num_packets, 4);
  EXPECT_EQ(drones.latest_rounds[1].num_packets, 4);
  ASSERT_GT(swarm_channels["FACT_GOSSIP"], 0);
  for (const auto& [channel, n] : swarm_channels) {  // LCM_SELF_TEST: each new udpm instance checks itself
    if (channel == "LCM_SELF_TEST") continue;
    EXPECT_EQ(channel, "FACT_GOSSIP") << n << " message(s) on " << channel << " leaked onto the swarm bus";
  }
  const auto codes = procs.stop_all();
  for (const auto& [name, code] : codes) EXPECT_EQ(code, 0) << name;
}

// The round-building path of fact-gossip: odometry (a spin of 2π plus a little) and detections of
// two tracks go in on FACT_ODOMETRY_4 / FACT_DETECTIONS_4; the round packet it publishes (in its
// swarm_rounds_t, alone with --min-members 1) must be exactly what fact::gossip::RoundBuilder
// makes of the same samples. Bad input on its channels is counted, not fatal.
// Flags that can never work exit 2 naming the flag and its value (NaN periods and 1e14 s delays
// were converted to µs first and reported as "negative" or not named; --min-members above the
// roster started a gossip that could never complete).
TEST_F(GossipProcesses, BadTimesAndCountsExitTwoNamingTheFlag) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--summary-min-interval", "nan"}, "--summary-min-interval: expected a number in [0, 3600] s, got nan"},
      {{"--settle", "1e14"}, "--settle: expected a number in [0, 3600] s, got 1e+14"},
      {{"--answer-slot", "inf"}, "--answer-slot"},
      {{"--round-period", "1e300"}, "--round-period"},
      {{"--silence-timeout", "0"}, "--silence-timeout: expected a number in [0.001, 3600] s, got 0"},
      {{"--request-interval", "-2"}, "--request-interval"},
      {{"--summary-period", "nan"}, "--summary-period"},
      {{"--min-members", "50", "--roster", "0,1"}, "--min-members 50 can never be reached: at most 2 drones (--roster)"},
  };
  for (const auto& [flags, reason] : cases) {
    std::vector<std::string> args{FACT_GOSSIP_BINARY, "--drone-id", "0", "--lcm-url", "memq://", "--insecure"};
    args.insert(args.end(), flags.begin(), flags.end());
    const std::string log = dir_ + "/bad.log";
    std::remove(log.c_str());
    Processes procs;
    procs.start("gossip", args, log);
    const std::map<std::string, int> codes = procs.wait_all(std::chrono::seconds(5));
    EXPECT_EQ(codes.at("gossip"), 2) << flags[0];
    const std::string text = tail(log, 5);
    EXPECT_NE(text.find(reason), std::string::npos) << text;
  }
}

// A challenge to fact-gossip whose envelope screens as a replay (the challenger's numbers are
// below what the gossip holds of it) is still answered, once per nonce: two
// drones that each hold the other's old numbers otherwise refused each other's challenges until
// their clocks passed the old numbers (review, session 32). The test process is drone 1, with the
// swarm key: it raises drone 2's window for drone 1, then challenges it with lower numbers.
TEST_F(GossipProcesses, AChallengeIsAnsweredEvenWhenItsNumbersAreOld) {
  const std::string url = drone_url(7);
  ASSERT_EQ(fact::app::init_crypto(), "");
  fact::app::SwarmKey key;
  ASSERT_EQ(fact::app::load_key(dir_ + "/swarm.key", &key), "");
  lcm::LCM bus(url);
  ASSERT_TRUE(bus.good());
  struct Answers {
    std::vector<fact::gossip_challenge_t> got;
    void on(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      fact::gossip_packet_t env;
      fact::gossip_challenge_t m;
      if (env.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) > 0 && env.sender_id == 2 &&
          env.kind == fact::gossip_packet_t::RESPONSE && m.decode(env.payload.data(), 0, env.payload_size) > 0)
        got.push_back(m);
    }
  } answers;
  bus.subscribe("FACT_GOSSIP", &Answers::on, &answers);
  Processes procs;
  procs.start("gossip2", {FACT_GOSSIP_BINARY, "--drone-id", "2", "--lcm-url", url, "--key-file", dir_ + "/swarm.key",
                          "--rounds-from-channel", "--status-period", "0.2"},
              log_);
  std::this_thread::sleep_for(std::chrono::milliseconds(static_cast<int>(fact::test::scaled_s(0.5) * 1000)));
  const int64_t high = now_us();
  fact::gossip_summary_t summary{};  // (every count 0)
  summary.utime = high;
  summary.drone_id = 1;
  const fact::gossip_packet_t first = fact::app::make_envelope(1, high, fact::gossip_packet_t::SUMMARY,
                                                               fact::app::encode_bytes(summary), high, key);
  bus.publish("FACT_GOSSIP", &first);
  const auto challenge = [&](int64_t seq, uint8_t tag) {
    fact::gossip_challenge_t c;
    c.utime = now_us();
    c.peer_id = 2;
    for (int k = 0; k < 16; ++k) c.nonce[k] = static_cast<uint8_t>(tag + k);
    const fact::gossip_packet_t env =
        fact::app::make_envelope(1, seq, fact::gossip_packet_t::CHALLENGE, fact::app::encode_bytes(c), c.utime, key);
    bus.publish("FACT_GOSSIP", &env);
  };
  const auto pump = [&](double seconds) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<int>(seconds * 1000));
    while (std::chrono::steady_clock::now() < end) bus.handleTimeout(10);
  };
  pump(0.2);
  const int64_t low = high - 3600000000LL;  // drone 1 "restarted with its clock an hour back"
  challenge(low, 40);
  for (int i = 1; i < 5; ++i) challenge(low + i, 40);  // the same challenge replayed: not answered again
  challenge(low + 5, 41);                               // a new nonce: answered
  pump(fact::test::scaled_s(0.6));
  ASSERT_EQ(answers.got.size(), 2u) << "the challenges with old numbers were not answered once per nonce";
  EXPECT_EQ(answers.got[0].peer_id, 1);
  EXPECT_EQ(answers.got[0].nonce[0], 40);
  EXPECT_EQ(answers.got[0].nonce[15], 40 + 15);
  EXPECT_EQ(answers.got[1].nonce[0], 41);
  for (const auto& [name, code] : procs.stop_all()) EXPECT_EQ(code, 0) << name;
}

// fact-fault-relay: a channel that two --channel patterns match is forwarded once (two
// subscriptions forwarded every message twice and the copies bounced between the buses for ever:
// 32 000 copies of 3 messages in 1.5 s; review, session 32). Flags that cannot work exit 2 naming
// the flag: the same bus twice (another spelling of one URL), NaN probabilities, bad patterns.
TEST_F(GossipProcesses, FaultRelayForwardsOnceAndRefusesUnusableFlags) {
  const std::string drone = drone_url(6), swarm = "udpm://239.255.76.68:7668?ttl=0";
  lcm::LCM drone_side(drone), swarm_side(swarm);
  ASSERT_TRUE(drone_side.good() && swarm_side.good());
  struct Count {
    std::map<std::string, int> n;
    void on(const lcm::ReceiveBuffer*, const std::string& channel) { ++n[channel]; }
  } arrived;
  swarm_side.subscribe(".*", &Count::on, &arrived);
  Processes procs;
  procs.start("relay", {FACT_FAULT_RELAY_BINARY, "--drone-url", drone, "--swarm-url", swarm, "--channel", "FACT_GOSSIP",
                        "--channel", "FACT_GOSSIP", "--channel", "FACT_.*", "--channel", "(?:FACT_GOSS)IP",
                        "--channel", "(Y)\\1_CH", "--faults",
                        "both", "--status-channel", "RELAY_STATUS"},
              log_);
  std::this_thread::sleep_for(std::chrono::milliseconds(static_cast<int>(fact::test::scaled_s(0.5) * 1000)));
  const std::string bytes = "not an envelope, forwarded byte for byte";
  for (int i = 0; i < 3; ++i)
    drone_side.publish("FACT_GOSSIP", (bytes + std::to_string(i)).data(), static_cast<unsigned>(bytes.size() + 1));
  drone_side.publish("NOT_FACT_GOSSIP", bytes.data(), static_cast<unsigned>(bytes.size()));  // no pattern matches it whole
  drone_side.publish("YY_CH", bytes.data(), static_cast<unsigned>(bytes.size()));  // a back-reference keeps its meaning
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<int>(fact::test::scaled_s(1) * 1000));
  while (std::chrono::steady_clock::now() < end) swarm_side.handleTimeout(20);
  EXPECT_EQ(arrived.n["FACT_GOSSIP"], 3);
  EXPECT_EQ(arrived.n.count("NOT_FACT_GOSSIP"), 0u);
  EXPECT_EQ(arrived.n["YY_CH"], 1);
  for (const auto& [name, code] : procs.stop_all()) EXPECT_EQ(code, 0) << name;

  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--swarm-url", drone + "&ttl=1"}, "are the same bus udpm://239.255.76.67:7706"},
      {{"--drop", "nan"}, "--drop: expected a probability in [0, 1], got nan"},
      {{"--reorder", "1.5"}, "--reorder: expected a probability in [0, 1]"},
      {{"--max-delay-ms", "nan"}, "--max-delay-ms: expected a number in [1, 10000] ms, got nan"},
      {{"--channel", "("}, "--channel (: not a valid channel regex"},
      {{"--channel", ""}, "--channel: expected a value, got an empty string"},
      {{"--status-channel", ""}, "--status-channel: expected a value, got an empty string"},
      {{"--drone-id", "-7"}, "--drone-id: expected an id >= 0, got -7"},
  };
  for (const auto& [flags, reason] : cases) {
    std::vector<std::string> args{FACT_FAULT_RELAY_BINARY, "--drone-url", drone};
    if (flags[0] != "--swarm-url") args.insert(args.end(), {"--swarm-url", swarm});
    args.insert(args.end(), flags.begin(), flags.end());
    const std::string log = dir_ + "/bad-relay.log";
    std::remove(log.c_str());
    Processes bad;
    bad.start("relay", args, log);
    const std::map<std::string, int> codes = bad.wait_all(std::chrono::seconds(5));
    EXPECT_EQ(codes.at("relay"), 2) << flags[0] << " " << flags[1];
    const std::string text = tail(log, 5);
    EXPECT_NE(text.find(reason), std::string::npos) << text;
  }
}

#ifdef FACT_CLOCK_SHIFT_LIBRARY
// Starts one process with clock_shift.c preloaded: its wall clock runs shifted by the seconds in
// the file `shift` (re-read as the test rewrites it); processes started later are not shifted.
void start_clock_shifted(Processes& procs, const std::string& name, const std::vector<std::string>& args,
                         const std::string& log, const std::string& shift) {
  ::setenv("FACT_CLOCK_SHIFT_FILE", shift.c_str(), 1);
  ::setenv("LD_PRELOAD", FACT_CLOCK_SHIFT_LIBRARY, 1);
  procs.start(name, args, log);
  ::unsetenv("LD_PRELOAD");
  ::unsetenv("FACT_CLOCK_SHIFT_FILE");
}

// Drone 1's wall clock steps back an hour, then forward two (clock_shift.c, preloaded into it
// alone): it goes on completing rounds, and never publishes a set without the live drone 2. With
// the gossip's timeouts on the wall clock, the step back froze it for the hour and the step
// forward made drone 2 silent for a second (review, helper-17). A third process with drone 2's id
// is reported by drone 2 (duplicate_drone_id).
TEST_F(GossipProcesses, WallClockStepsNeitherFreezeNorSplitTheSwarm) {
  const std::string url = drone_url(1);
  Observer obs({url});
  ASSERT_TRUE(obs.good);
  const std::string shift = dir_ + "/clock_shift";
  const auto step_clock = [&](const char* seconds) { std::ofstream(shift) << seconds << "\n"; };
  step_clock("0");
  const auto args = [&](int id) {
    return std::vector<std::string>{FACT_GOSSIP_BINARY, "--drone-id", std::to_string(id), "--lcm-url", url,
                                    "--insecure", "--rounds-from-channel", "--min-members", "2", "--summary-period",
                                    "0.3", "--silence-timeout", "2", "--settle", "0.3", "--status-period", "0.2"};
  };
  Processes procs;
  start_clock_shifted(procs, "gossip1", args(1), log_, shift);
  procs.start("gossip2", args(2), log_);
  ASSERT_TRUE(obs.wait_for([&] { return obs.have_status({{"fact-gossip", 1}, {"fact-gossip", 2}}); }, 5));
  std::vector<fact::swarm_rounds_t> published_by_1;
  const auto complete = [&](int id, int rounds) {
    auto it = obs.latest_rounds.find(id);
    return it != obs.latest_rounds.end() && it->second.complete_rounds == rounds;
  };
  inject_drones_1_2(obs, 0);
  inject_drones_1_2(obs, 1);
  ASSERT_TRUE(obs.wait_for([&] { return complete(1, 2) && complete(2, 2); }, 5));
  step_clock("-3600");
  obs.spin(500);
  inject_drones_1_2(obs, 2);
  EXPECT_TRUE(obs.wait_for([&] { return complete(1, 3) && complete(2, 3); }, 5))
      << "drone 1 stopped completing rounds after its clock stepped back";
  step_clock("3600");
  // Every set drone 1 publishes from now on holds both drones (the latest is watched as it comes).
  bool split = false;
  for (int i = 0; i < 30; ++i) {
    obs.spin(50);
    auto it = obs.latest_rounds.find(1);
    if (it != obs.latest_rounds.end() && it->second.num_drones != 2) split = true;
  }
  EXPECT_FALSE(split) << "drone 1 published a set without drone 2 after its clock stepped forward";
  inject_drones_1_2(obs, 3);
  EXPECT_TRUE(obs.wait_for([&] { return complete(1, 4) && complete(2, 4); }, 5));
  EXPECT_EQ(obs.latest_rounds[1].num_drones, 2);
  EXPECT_EQ(content_bytes(obs.latest_rounds[1]), content_bytes(obs.latest_rounds[2]));

  // Another process with drone 2's id: drone 2 sees envelopes with its id it did not send.
  procs.start("gossip2b", args(2), log_);
  EXPECT_TRUE(obs.wait_for([&] { return obs.counters[{"fact-gossip", 2}]["duplicate_drone_id"] > 0; }, 5))
      << "drone 2 did not notice another process with its id";
  for (const auto& [name, code] : procs.stop_all()) EXPECT_EQ(code, 0) << name;
  EXPECT_NE(tail(log_, 400).find("another process uses drone id 2"), std::string::npos);
}

// Drone 2's gossip dies and restarts with its wall clock an hour back (a board without a real-time
// clock): its envelope numbers are below its old ones, which drone 1 refuses as replays. Drone 1
// challenges it, drone 2 answers, and drone 1 takes its new numbers: both complete the next
// round together. Before the challenge, drone 1 refused drone 2 until its clock passed the old
// numbers (an hour), and drone 2 went silent for it.
TEST_F(GossipProcesses, ASenderRestartedWithItsClockBackIsTakenBackAfterAChallenge) {
  const std::string url = drone_url(5);
  Observer obs({url});
  ASSERT_TRUE(obs.good);
  const std::string shift = dir_ + "/clock_shift_back";
  std::ofstream(shift) << "-3600\n";
  const auto args = [&](int id) {
    return std::vector<std::string>{FACT_GOSSIP_BINARY, "--drone-id", std::to_string(id), "--lcm-url", url,
                                    "--key-file", dir_ + "/swarm.key", "--session", "restart-test",
                                    "--rounds-from-channel", "--min-members", "2", "--summary-period", "0.3",
                                    "--silence-timeout", "2", "--settle", "0.3", "--status-period", "0.2"};
  };
  const auto complete = [&](int id, int rounds) {
    auto it = obs.latest_rounds.find(id);
    return it != obs.latest_rounds.end() && it->second.complete_rounds == rounds && it->second.num_drones == 2;
  };
  Processes procs;
  procs.start("gossip1", args(1), log_);
  procs.start("gossip2", args(2), log_);
  ASSERT_TRUE(obs.wait_for([&] { return obs.have_status({{"fact-gossip", 1}, {"fact-gossip", 2}}); }, 5));
  inject_drones_1_2(obs, 0);
  inject_drones_1_2(obs, 1);
  ASSERT_TRUE(obs.wait_for([&] { return complete(1, 2) && complete(2, 2); }, 5));
  procs.kill_now("gossip2");
  obs.latest_rounds.erase(2);
  start_clock_shifted(procs, "gossip2", args(2), log_, shift);
  // The restarted drone 2 recovers rounds 0–1 (answers to its requests), then both complete round 2.
  EXPECT_TRUE(obs.wait_for([&] { return complete(2, 2); }, 5)) << "the restarted drone 2 did not recover rounds 0–1";
  inject_drones_1_2(obs, 2);
  EXPECT_TRUE(obs.wait_for([&] { return complete(1, 3) && complete(2, 3); }, 5))
      << "drone 1 did not take the restarted drone 2's rounds";
  EXPECT_EQ(content_bytes(obs.latest_rounds[1]), content_bytes(obs.latest_rounds[2]));
  obs.settle(0.5);
  auto& drone1 = obs.counters[{"fact-gossip", 1}];
  auto& drone2 = obs.counters[{"fact-gossip", 2}];
  EXPECT_GE(drone1["senders_renumbered"], 1);
  EXPECT_GE(drone1["challenges_sent"], 1);
  EXPECT_GE(drone2["challenges_answered"], 1);
  for (const auto& [name, code] : procs.stop_all()) EXPECT_EQ(code, 0) << name;
  EXPECT_NE(tail(log_, 400).find("drone 2 answered a challenge: its envelope numbers restart at"), std::string::npos);
}
#endif

// A recording of one flight's gossip (session A), played on the bus of a later flight with the same
// swarm key, is refused by a fresh gossip of session B (auth_failed), where a fresh gossip of
// session A takes drone 2's rounds from it (review, helper-17: without sessions the recording
// replaced a drone's real rounds on every drone).
TEST_F(GossipProcesses, ARecordingOfAnotherSessionIsRefused) {
  const std::string url = drone_url(3);
  Observer obs({url});
  ASSERT_TRUE(obs.good);
  lcm::LCM recorder(url);
  ASSERT_TRUE(recorder.good());
  std::vector<std::string> recorded;  // drone 2's envelopes, as sent
  struct Sink {
    std::vector<std::string>* out;
    void on(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      fact::gossip_packet_t m;
      if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) == static_cast<int>(rbuf->data_size) &&
          m.sender_id == 2)
        out->emplace_back(static_cast<const char*>(rbuf->data), rbuf->data_size);
    }
  } sink{&recorded};
  recorder.subscribe("FACT_GOSSIP", &Sink::on, &sink)->setQueueCapacity(100000);
  const auto args = [&](int id, const std::string& session) {
    return std::vector<std::string>{FACT_GOSSIP_BINARY, "--drone-id", std::to_string(id), "--lcm-url", url,
                                    "--key-file", dir_ + "/swarm.key", "--session", session, "--rounds-from-channel",
                                    "--min-members", "2", "--settle", "0.3", "--status-period", "0.2"};
  };
  {
    Processes flight_a;
    flight_a.start("gossip1", args(1, "A"), log_);
    flight_a.start("gossip2", args(2, "A"), log_);
    ASSERT_TRUE(obs.wait_for([&] { return obs.have_status({{"fact-gossip", 1}, {"fact-gossip", 2}}); }, 5));
    for (int round : {0, 1}) inject_drones_1_2(obs, round);
    ASSERT_TRUE(obs.wait_for([&] { return obs.latest_rounds.count(1) && obs.latest_rounds[1].complete_rounds == 2; }, 5));
    for (const auto& [name, code] : flight_a.stop_all()) EXPECT_EQ(code, 0) << name;
  }
  while (recorder.handleTimeout(0) > 0) {
  }
  ASSERT_GT(recorded.size(), 2u);
  // A fresh drone 1 of `session` hears the recording: what it counts and holds of drone 2.
  const auto replay_to = [&](const std::string& session) {
    obs.states.clear();
    obs.counters.clear();
    Processes later;
    later.start("gossip1", args(1, session), log_);
    EXPECT_TRUE(obs.wait_for([&] { return obs.have_status({{"fact-gossip", 1}}); }, 5));
    for (const std::string& bytes : recorded) {
      obs.at(0).publish("FACT_GOSSIP", bytes.data(), static_cast<unsigned>(bytes.size()));
      obs.spin(2);
    }
    obs.settle(0.6);
    const std::string state = obs.states[{"fact-gossip", 1}];
    const int64_t auth_failed = obs.counters[{"fact-gossip", 1}]["auth_failed"];
    for (const auto& [name, code] : later.stop_all()) EXPECT_EQ(code, 0) << name;
    return std::make_pair(state, auth_failed);
  };
  const auto [state_b, failed_b] = replay_to("B");
  EXPECT_EQ(failed_b, static_cast<int64_t>(recorded.size())) << state_b;
  EXPECT_EQ(state_b.find(" 2:"), std::string::npos) << "session B took drone 2's old rounds: " << state_b;
  const auto [state_a, failed_a] = replay_to("A");
  EXPECT_EQ(failed_a, 0) << state_a;
  EXPECT_NE(state_a.find(" 2:2"), std::string::npos) << "the control did not take the recording: " << state_a;
}

TEST_F(GossipProcesses, BuildsARoundFromASpinAndCountsBadInput) {
  const std::string url = drone_url(4);
  Observer obs({url});
  ASSERT_TRUE(obs.good);
  Processes procs;
  procs.start("gossip4", {FACT_GOSSIP_BINARY, "--drone-id", "4", "--lcm-url", url, "--insecure", "--min-members", "1",
                          "--settle", "0.2", "--status-period", "0.2"},
              log_);
  ASSERT_TRUE(obs.wait_for([&] { return obs.have_status({{"fact-gossip", 4}}); }, 5)) << "fact-gossip is not up";

  fact::gossip::RoundBuilder local;  // the same defaults as fact-gossip's
  // One spin of odometry time from t_start, odometry seq from seq; the bad input once, mid-spin.
  const auto spin = [&](int64_t t_start, int64_t seq, bool bad_input) {
  for (int i = 0; i <= 160; ++i) {
    const int64_t t = t_start + i * 10000;  // 100 Hz, 1.6 s of odometry time
    fact::odometry_t o{};
    o.utime = t;
    o.drone_id = 4;
    o.seq = seq++;
    o.position[0] = 0.2 * i * 0.01;
    o.position[1] = -1.0;
    o.position[2] = 1.2;
    o.yaw = 0.4 + 2 * M_PI * 0.8 * i * 0.01;  // 0.8 turns per second: 2π after 1.25 s
    obs.at(0).publish("FACT_ODOMETRY_4", &o);
    local.add_odometry(t, Eigen::Vector3d(o.position[0], o.position[1], o.position[2]), o.yaw);
    if (i % 3 == 1) {
      fact::detections_t d{};
      d.utime = t + 5000;  // between odometry samples
      d.drone_id = 4;
      d.frame_seq = i;
      for (int track : {11, 12}) {
        fact::detection_t det{};
        det.track_id = track;
        const double bearing = std::remainder(-(o.yaw + 0.03) + (track == 11 ? 1.0 : 2.5), 2 * M_PI);
        det.vector[0] = 3 * std::cos(bearing);
        det.vector[1] = 3 * std::sin(bearing);
        det.vector[2] = 0.1 * track - 1.0;
        det.confidence = 0.9f;
        det.range = std::hypot(3.0, det.vector[2]);
        d.detections.push_back(det);
        local.add_detection(d.utime, track, Eigen::Vector3d(det.vector[0], det.vector[1], det.vector[2]));
      }
      d.count = static_cast<int32_t>(d.detections.size());
      obs.at(0).publish("FACT_DETECTIONS_4", &d);
    }
    if (i == 80 && bad_input) {  // bad input: NaN odometry, another drone's detections, a truncated envelope
      fact::odometry_t bad = o;
      bad.utime += 1;
      bad.position[1] = std::nan("");
      obs.at(0).publish("FACT_ODOMETRY_4", &bad);
      fact::detections_t foreign{};
      foreign.drone_id = 7;
      obs.at(0).publish("FACT_DETECTIONS_4", &foreign);
      const std::vector<uint8_t> junk(11, 0x5a);
      obs.at(0).publish("FACT_GOSSIP", junk.data(), static_cast<unsigned>(junk.size()));
    }
    obs.spin(2);
  }
  };
  spin(1700000000000000, 0, true);
  std::vector<fact::gossip::BuiltRound> rounds = local.take_rounds();
  ASSERT_EQ(rounds.size(), 1u);
  ASSERT_EQ(rounds[0].data.observations.size(), 2u);

  ASSERT_TRUE(obs.wait_for([&] { return obs.latest_rounds.count(4) > 0; }, 5)) << "no round published";
  obs.settle(0.5);
  const fact::swarm_rounds_t& got = obs.latest_rounds[4];
  ASSERT_EQ(got.complete_rounds, 1);
  ASSERT_EQ(got.num_packets, 1);
  fact::gossip::Packet p{4, 0, rounds[0].end_utime, rounds[0].data};
  EXPECT_EQ(fact::app::encode_bytes(got.packets[0]), fact::app::encode_bytes(fact::app::packet_to_message(p)));
  auto& c = obs.counters[{"fact-gossip", 4}];
  EXPECT_EQ(c["rejected_odometry"], 1);
  EXPECT_EQ(c["foreign_drone"], 1);
  EXPECT_EQ(c["undecodable"], 1);
  EXPECT_EQ(c["rounds_built"], 1);

  // fact-vio-relay restarts after a VIO clock reset: seq 0 and times 100 s earlier. The next spin
  // is round 1 (the builder used to refuse every sample older than the last and build nothing).
  local.restart();
  spin(1700000000000000 - 100000000, 0, false);
  rounds = local.take_rounds();
  ASSERT_EQ(rounds.size(), 1u);
  ASSERT_TRUE(obs.wait_for([&] { return obs.latest_rounds[4].complete_rounds == 2; }, 5))
      << "no round after the odometry restarted";
  const fact::swarm_rounds_t& after = obs.latest_rounds[4];
  ASSERT_EQ(after.num_packets, 2);
  fact::gossip::Packet p1{4, 1, rounds[0].end_utime, rounds[0].data};
  EXPECT_EQ(fact::app::encode_bytes(after.packets[1]), fact::app::encode_bytes(fact::app::packet_to_message(p1)));
  obs.settle(0.5);
  EXPECT_EQ(c["odometry_restarts"], 1);
  EXPECT_EQ(c["rounds_built"], 2);
  for (const auto& [name, code] : procs.stop_all()) EXPECT_EQ(code, 0) << name << " did not exit cleanly";
}

}  // namespace
