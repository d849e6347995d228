// fact-bench-gossip: the gossip figures of the LCM-stack issue, measured on real fact-gossip
// processes over udpm:// inside a private network namespace. Run it as
//   scripts/netns-run.sh build/bench/fact-bench-gossip [--quick]
// (it refuses to run when the network namespace has any interface but lo).
//
// Scenarios (N drones, default 8; rounds injected every --period s on FACT_ROUND_PACKET_<id>, each
// with --observations observations, as a drone seeing every other drone would make):
//   clean      every gossip on one swarm URL, no faults.
//   lossy      every gossip behind its own fact-fault-relay: --drop loss, --dup duplication and
//              --reorder hold-back towards each drone (independent per receiver, seeded).
//   spin       the full per-drone chain at steady state: the bench plays 15 Hz raw odometry (a
//              spin every --period s) on FACT_VIO_RAW_<id> to one fact-vio-relay per drone, which
//              publishes FACT_ODOMETRY_<id>; it plays 15 Hz detections (the drones in view) on
//              FACT_DETECTIONS_<id>; each fact-gossip builds and exchanges its own rounds and one
//              fact-solver per drone solves FACT_SWARM_ROUNDS_<id> and publishes FACT_RESULT_<id>
//              (counted, with their status strings; the synthetic detections need not make a
//              certifiable swarm); no faults.
// Figures:
//   latency    per round, from the moment the last drone's round packet was injected to the
//              moment the bench has received every drone's swarm_rounds_t holding that round
//              (target ≤ 0.5 s clean, ≤ 3 s lossy; "no round lost": every drone's final data is
//              byte-identical to what was injected).
//   bandwidth  bytes per drone per round at steady state: every FACT_GOSSIP message seen on the
//              swarm URL during the R rounds' window (R × period), divided by N × R. Counted as
//              LCM message bytes (envelope incl. 32-byte MAC) and on the wire (+ the LCM header
//              and channel name, + 28 bytes IPv4/UDP per datagram). Target ≤ 10 kB.
//   cpu        each process's user + system time over the window (/proc/<pid>/stat), as % of one
//              core; also the whole lifetime from wait4's rusage. In the spin scenario per drone:
//              relay, gossip, solver and the chain's sum (target: the chain <= 5 % of one core).
// Writes --out (default bench/results/gossip.csv, relative to the current directory) and prints
// the figures.
#include "common/cli_checks.h"
#include "common/convert.h"
#include "fact/app_status_t.hpp"
#include "fact/detections_t.hpp"
#include "fact/gossip_packet_t.hpp"
#include "fact/odometry_t.hpp"
#include "fact/round_packet_t.hpp"
#include "fact/swarm_result_t.hpp"
#include "fact/swarm_rounds_t.hpp"
#include "fact_gossip/wire.h"
#include "results_file.h"
#include "stats.h"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <numeric>
#include <random>
#include <sstream>
#include <string>
#include <vector>

extern char** environ;

namespace {

// The apps are all built into one directory (build/apps): another app next to fact-gossip.
std::string sibling_binary(const std::string& name) {
  const std::string gossip = FACT_GOSSIP_BINARY;
  const auto slash = gossip.rfind('/');
  return (slash == std::string::npos ? std::string() : gossip.substr(0, slash + 1)) + name;
}

struct Config {
  int drones = 8;
  int rounds = 5;               // rounds per exchange scenario
  double period = 3.0;          // s between rounds (the spin period in the spin scenario)
  int observations = 7;         // per injected round packet
  double drop = 0.2, dup = 0.1, reorder = 0.2;
  double spin_seconds = 20;     // length of the spin scenario (s)
  double odometry_hz = 15;      // odometry and detection rate in the spin scenario
  std::string out = "bench/results/gossip.csv";
  std::string gossip_bin = FACT_GOSSIP_BINARY;
  std::string relay_bin = FACT_FAULT_RELAY_BINARY;
  std::string vio_relay_bin = sibling_binary("fact-vio-relay");   // spin scenario
  std::string solver_bin = sibling_binary("fact-solver");         // spin scenario
  std::string log = "/tmp/fact-bench-gossip.log";
  bool quick = false;
};

const std::string kSwarmUrl = "udpm://239.255.76.67:7667?ttl=0";
std::string drone_url(int i) { return "udpm://239.255.76.67:" + std::to_string(7700 + i) + "?ttl=0"; }

int64_t now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

std::string network_interfaces() {
  std::ifstream f("/proc/self/net/dev");
  std::string line, names;
  for (int n = 0; std::getline(f, line); ++n) {
    const auto colon = line.find(':');
    if (n < 2 || colon == std::string::npos) continue;
    std::string name = line.substr(0, colon);
    name.erase(0, name.find_first_not_of(' '));
    names += (names.empty() ? "" : ",") + name;
  }
  return names;
}

// CPU seconds (user + system) of a running process, from /proc/<pid>/stat.
double cpu_seconds(pid_t pid) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/stat");
  std::string s((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  const auto close = s.rfind(')');
  if (close == std::string::npos) return 0;
  std::istringstream in(s.substr(close + 2));
  std::string field;
  unsigned long long utime = 0, stime = 0;
  for (int k = 3; k <= 15 && in >> field; ++k) {
    if (k == 14) utime = std::stoull(field);
    if (k == 15) stime = std::stoull(field);
  }
  return static_cast<double>(utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

struct Child {
  std::string name;
  pid_t pid = 0;
  double cpu_at_mark = 0;
  double window_cpu = 0;     // s over the window
  double lifetime_cpu = 0;   // s, from wait4
  double lifetime = 0;       // s
  int64_t started = 0;
  int exit_code = -1;
};

class Processes {
 public:
  explicit Processes(std::string log) : log_(std::move(log)) {}
  ~Processes() {
    for (auto& c : children_)
      if (c.pid > 0) kill(c.pid, SIGKILL), waitpid(c.pid, nullptr, 0);
  }
  Child& start(const std::string& name, const std::vector<std::string>& args) {
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, log_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    Child c;
    c.name = name;
    c.started = now_us();
    if (posix_spawn(&c.pid, args[0].c_str(), &fa, nullptr, argv.data(), environ) != 0)
      throw std::runtime_error("cannot start " + args[0]);
    posix_spawn_file_actions_destroy(&fa);
    children_.push_back(c);
    return children_.back();
  }
  // Throws, naming the process, its exit and the log, when one of them has exited already (a relay
  // that refused its flags used to leave the scenario running on, with figures of nothing;
  // review, session 34). waitid with WNOWAIT leaves the child to stop_all's wait4.
  void require_running(const std::string& scenario) const {
    for (const auto& c : children_) {
      siginfo_t info{};
      if (waitid(P_PID, static_cast<id_t>(c.pid), &info, WEXITED | WNOHANG | WNOWAIT) != 0 || info.si_pid == 0) continue;
      const std::string how = info.si_code == CLD_EXITED ? "exited with code " + std::to_string(info.si_status)
                                                         : "was killed by signal " + std::to_string(info.si_status);
      throw std::runtime_error(scenario + ": " + c.name + " " + how + " (its output is in " + log_ + ")");
    }
  }
  void mark() {
    for (auto& c : children_) c.cpu_at_mark = cpu_seconds(c.pid);
  }
  void measure() {
    for (auto& c : children_) c.window_cpu = cpu_seconds(c.pid) - c.cpu_at_mark;
  }
  std::vector<Child> stop_all() {
    for (auto& c : children_) kill(c.pid, SIGTERM);
    for (auto& c : children_) {
      int status = 0;
      rusage ru{};
      wait4(c.pid, &status, 0, &ru);
      c.lifetime_cpu = static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
                       1e-6 * static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
      c.lifetime = 1e-6 * static_cast<double>(now_us() - c.started);
      c.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      c.pid = 0;
    }
    std::vector<Child> out = children_;
    children_.clear();
    return out;
  }

 private:
  std::string log_;
  std::vector<Child> children_;
};

// Listens on the given URLs: swarm_rounds_t per drone (with the time each K was first seen),
// status counters, and the FACT_GOSSIP traffic on the swarm URL (bytes per sender).
class Observer {
 public:
  struct Sink {
    Observer* o;
    void swarm_rounds(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      fact::swarm_rounds_t m;
      if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) != static_cast<int>(rbuf->data_size)) return;
      o->latest[m.drone_id] = m;
      auto& first = o->first_seen[m.drone_id];
      const int64_t t = now_us();
      for (int k = 1; k <= m.complete_rounds; ++k)
        if (!first.count(k)) first[k] = t;
    }
    void status(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      fact::app_status_t m;
      if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) != static_cast<int>(rbuf->data_size)) return;
      auto& c = o->counters[{m.app, m.drone_id}];
      for (int k = 0; k < m.num_counters; ++k) c[m.counter_names[k]] = m.counter_values[k];
    }
    void result(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      fact::swarm_result_t m;
      if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) != static_cast<int>(rbuf->data_size)) return;
      o->results[m.drone_id] += 1;
      o->result_status[m.status] += 1;
    }
    void gossip(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
      if (!o->counting) return;
      fact::gossip_packet_t m;
      if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) != static_cast<int>(rbuf->data_size)) return;
      o->message_bytes += static_cast<int64_t>(rbuf->data_size);
      // LCM short-message header (magic + sequence) + channel + NUL, then IPv4 (20) + UDP (8).
      o->wire_bytes += static_cast<int64_t>(rbuf->data_size) + 8 + static_cast<int64_t>(channel.size()) + 1 + 28;
      o->datagrams += 1;
      o->by_kind[m.kind] += static_cast<int64_t>(rbuf->data_size);
    }
  };

  Observer(const std::vector<std::string>& urls, int gossip_url_index) {
    for (size_t i = 0; i < urls.size(); ++i) {
      auto l = std::make_unique<lcm::LCM>(urls[i]);
      if (!l->good()) throw std::runtime_error("LCM unusable: " + urls[i]);
      l->subscribe("FACT_SWARM_ROUNDS_.*", &Sink::swarm_rounds, &sink_);
      l->subscribe("FACT_STATUS", &Sink::status, &sink_);
      l->subscribe("FACT_RESULT_.*", &Sink::result, &sink_);
      if (static_cast<int>(i) == gossip_url_index) l->subscribe("FACT_GOSSIP", &Sink::gossip, &sink_);
      lcms_.push_back(std::move(l));
    }
  }
  lcm::LCM& at(size_t i) { return *lcms_[i]; }
  void spin_until(int64_t end, const std::function<void()>& every = {}) {
    std::vector<pollfd> fds;
    for (auto& l : lcms_) fds.push_back({l->getFileno(), POLLIN, 0});
    for (int64_t now = now_us(); now < end; now = now_us()) {
      if (every) every();
      if (poll(fds.data(), fds.size(), static_cast<int>(std::min<int64_t>((end - now + 999) / 1000, 5))) <= 0) continue;
      for (size_t i = 0; i < fds.size(); ++i)
        if (fds[i].revents & POLLIN) lcms_[i]->handle();
    }
  }
  void spin(double seconds) { spin_until(now_us() + static_cast<int64_t>(seconds * 1e6)); }
  bool wait_for(const std::function<bool()>& pred, double seconds) {
    const int64_t end = now_us() + static_cast<int64_t>(seconds * 1e6);
    while (!pred() && now_us() < end) spin_until(std::min(end, now_us() + 20000));
    return pred();
  }

  std::map<int, fact::swarm_rounds_t> latest;
  std::map<int, std::map<int, int64_t>> first_seen;  // drone → K → time first seen
  std::map<std::pair<std::string, int>, std::map<std::string, int64_t>> counters;
  bool counting = false;
  int64_t message_bytes = 0, wire_bytes = 0, datagrams = 0;
  std::map<int, int64_t> by_kind;
  std::map<int, int64_t> results;                // drone → swarm_result_t received
  std::map<std::string, int64_t> result_status;  // status string → count

 private:
  Sink sink_{this};
  std::vector<std::unique_ptr<lcm::LCM>> lcms_;
};

fact::round_packet_t injected(int drone, int round, int observations) {
  fact::round_packet_t m;
  m.utime = 1700000000000000 + 1000000LL * round + drone;
  m.drone_id = drone;
  m.round = round;
  m.position[0] = 1.5 * drone;
  m.position[1] = -0.5 * round;
  m.position[2] = 1.4;
  m.yaw = 0.2 * drone + 0.1 * round;
  m.count = observations;
  for (int k = 0; k < observations; ++k) {
    fact::observation_t o;
    o.odom_position[0] = 1.5 * drone + 0.01 * k;
    o.odom_position[1] = -0.5 * round;
    o.odom_position[2] = 1.4;
    o.odom_yaw = m.yaw + 0.8 * k;
    o.vector[0] = 2.5 + 0.3 * k;
    o.vector[1] = 0.2 * drone - 0.1 * k;
    o.vector[2] = 0.05 * (k - 3);
    m.observations.push_back(o);
  }
  return m;
}

std::vector<uint8_t> content_bytes(fact::swarm_rounds_t m) {
  m.utime = 0;
  m.drone_id = 0;
  return fact::app::encode_bytes(m);
}

std::string roster(int n) {
  std::string s;
  for (int i = 0; i < n; ++i) s += (i ? "," : "") + std::to_string(i);
  return s;
}

using fact::bench::median;

struct Row {
  std::string scenario, metric;
  double value;
  std::string unit, target;
};

struct Report {
  std::vector<Row> rows;
  void add(const std::string& s, const std::string& m, double v, const std::string& u, const std::string& t = "") {
    rows.push_back({s, m, v, u, t});
  }
};

std::string key_file() {
  std::random_device rd;
  std::string hex;
  const char* digits = "0123456789abcdef";
  for (int i = 0; i < 64; ++i) hex += digits[rd() % 16];
  const std::string path = "/tmp/fact-bench-gossip-" + std::to_string(getpid()) + ".key";
  std::ofstream(path) << hex << "\n";
  chmod(path.c_str(), 0600);
  return path;
}

std::vector<std::string> gossip_args(const Config& c, int id, const std::string& url, const std::string& key,
                                     bool from_channel) {
  std::vector<std::string> a{c.gossip_bin,    "--drone-id", std::to_string(id), "--lcm-url", url,
                             "--key-file",    key,          "--roster",         roster(c.drones),
                             "--min-members", std::to_string(c.drones), "--status-period", "0.5"};
  if (from_channel) a.push_back("--rounds-from-channel");
  return a;
}

// clean / lossy: injected rounds.
void run_exchange(const Config& c, bool lossy, const std::string& key, Report* report) {
  const std::string name = lossy ? "lossy" : "clean";
  std::vector<std::string> urls;
  for (int i = 0; i < c.drones; ++i) urls.push_back(lossy ? drone_url(i) : kSwarmUrl);
  if (lossy) urls.push_back(kSwarmUrl);
  else urls.resize(1);
  const int swarm_index = lossy ? c.drones : 0;
  Observer obs(urls, swarm_index);
  Processes procs(c.log);
  std::vector<Child*> gossips;
  if (lossy)
    for (int i = 0; i < c.drones; ++i)
      procs.start("relay" + std::to_string(i),
                  {c.relay_bin, "--drone-url", drone_url(i), "--swarm-url", kSwarmUrl, "--drop", std::to_string(c.drop),
                   "--dup", std::to_string(c.dup), "--reorder", std::to_string(c.reorder), "--seed",
                   std::to_string(1000 + i), "--drone-id", std::to_string(i)});
  for (int i = 0; i < c.drones; ++i)
    procs.start("gossip" + std::to_string(i), gossip_args(c, i, lossy ? drone_url(i) : kSwarmUrl, key, true));
  obs.spin(2.0);  // start-up and settle (1.5 s)
  procs.require_running(name);

  std::vector<int64_t> t_inject(static_cast<size_t>(c.rounds));
  const int64_t t0 = now_us();
  const int64_t window_end = t0 + static_cast<int64_t>(c.rounds * c.period * 1e6);
  obs.counting = true;
  procs.mark();
  for (int r = 0; r < c.rounds; ++r) {
    obs.spin_until(t0 + static_cast<int64_t>(r * c.period * 1e6));
    for (int i = 0; i < c.drones; ++i) {
      const fact::round_packet_t m = injected(i, r, c.observations);
      obs.at(lossy ? static_cast<size_t>(i) : 0).publish("FACT_ROUND_PACKET_" + std::to_string(i), &m);
    }
    t_inject[static_cast<size_t>(r)] = now_us();
  }
  obs.spin_until(window_end);
  obs.counting = false;
  procs.measure();
  const auto all_complete = [&] {
    for (int i = 0; i < c.drones; ++i)
      if (!obs.latest.count(i) || obs.latest[i].complete_rounds < c.rounds) return false;
    return true;
  };
  const bool complete = obs.wait_for(all_complete, 10);
  obs.spin(1.1);  // the last status messages
  procs.require_running(name);
  std::vector<Child> done = procs.stop_all();

  // Latency per round: every drone holding it.
  std::vector<double> lat;
  int lost = 0;
  for (int r = 0; r < c.rounds; ++r) {
    int64_t last = 0;
    bool all = true;
    for (int i = 0; i < c.drones; ++i) {
      auto it = obs.first_seen[i].find(r + 1);
      if (it == obs.first_seen[i].end()) all = false;
      else last = std::max(last, it->second);
    }
    if (!all) {
      ++lost;
      continue;
    }
    lat.push_back(1e-6 * static_cast<double>(last - t_inject[static_cast<size_t>(r)]));
  }
  // Identical and exactly what was injected.
  fact::swarm_rounds_t expected;
  expected.complete_rounds = c.rounds;
  expected.num_drones = c.drones;
  for (int i = 0; i < c.drones; ++i) expected.drone_ids.push_back(i);
  for (int i = 0; i < c.drones; ++i)
    for (int r = 0; r < c.rounds; ++r) expected.packets.push_back(injected(i, r, c.observations));
  expected.num_packets = static_cast<int32_t>(expected.packets.size());
  const std::vector<uint8_t> want = content_bytes(expected);
  int identical = 0;
  for (int i = 0; i < c.drones; ++i)
    if (obs.latest.count(i) && content_bytes(obs.latest[i]) == want) ++identical;

  const double per = static_cast<double>(c.drones) * c.rounds;
  std::vector<double> cpu;
  double relay_cpu = 0;
  int bad_exit = 0;
  for (const Child& ch : done) {
    if (ch.exit_code != 0) ++bad_exit;
    if (ch.name.rfind("gossip", 0) == 0) cpu.push_back(100.0 * ch.window_cpu / (c.rounds * c.period));
    else relay_cpu += 100.0 * ch.window_cpu / (c.rounds * c.period);
  }
  int64_t auth_failed = 0, requests = 0, answers = 0, suppressed = 0, dup_env = 0;
  for (int i = 0; i < c.drones; ++i) {
    auto& g = obs.counters[{"fact-gossip", i}];
    auth_failed += g["auth_failed"];
    requests += g["requests_sent"];
    answers += g["answers_sent"];
    suppressed += g["answers_suppressed"];
    dup_env += g["duplicate_envelopes"];
  }
  const std::string target_latency = lossy ? "<= 3 s" : "<= 0.5 s";
  report->add(name, "drones", c.drones, "");
  report->add(name, "rounds", c.rounds, "");
  report->add(name, "round_period", c.period, "s");
  if (lossy) {
    report->add(name, "drop", c.drop, "probability");
    report->add(name, "dup", c.dup, "probability");
    report->add(name, "reorder", c.reorder, "probability");
  }
  report->add(name, "all_complete", complete ? 1 : 0, "bool", "1");
  report->add(name, "rounds_never_complete", lost, "rounds", "0");
  report->add(name, "drones_byte_identical_to_injected", identical, "drones", std::to_string(c.drones));
  for (size_t r = 0; r < lat.size(); ++r) report->add(name, "latency_round_" + std::to_string(r), lat[r], "s", target_latency);
  report->add(name, "latency_median", median(lat), "s", target_latency);
  report->add(name, "latency_max", lat.empty() ? NAN : *std::max_element(lat.begin(), lat.end()), "s", target_latency);
  report->add(name, "bytes_per_drone_per_round_lcm", static_cast<double>(obs.message_bytes) / per, "B", "<= 10000");
  report->add(name, "bytes_per_drone_per_round_wire", static_cast<double>(obs.wire_bytes) / per, "B", "<= 10000");
  report->add(name, "datagrams_per_drone_per_round", static_cast<double>(obs.datagrams) / per, "");
  report->add(name, "round_bytes_per_drone_per_round", static_cast<double>(obs.by_kind[1]) / per, "B");
  report->add(name, "summary_bytes_per_drone_per_round", static_cast<double>(obs.by_kind[2]) / per, "B");
  report->add(name, "request_bytes_per_drone_per_round", static_cast<double>(obs.by_kind[3]) / per, "B");
  report->add(name, "requests_sent", static_cast<double>(requests), "");
  report->add(name, "answers_sent", static_cast<double>(answers), "");
  report->add(name, "answers_suppressed", static_cast<double>(suppressed), "");
  report->add(name, "duplicate_envelopes", static_cast<double>(dup_env), "");
  report->add(name, "auth_failed", static_cast<double>(auth_failed), "", "0");
  report->add(name, "gossip_cpu_mean", std::accumulate(cpu.begin(), cpu.end(), 0.0) / std::max<size_t>(cpu.size(), 1),
              "% of one core");
  report->add(name, "gossip_cpu_max", cpu.empty() ? NAN : *std::max_element(cpu.begin(), cpu.end()), "% of one core");
  if (lossy) report->add(name, "relays_cpu_total", relay_cpu, "% of one core");
  report->add(name, "processes_not_exiting_0", bad_exit, "", "0");
}

// spin: the full chain per drone (vio-relay → gossip → solver), 15 Hz raw odometry and
// detections, own rounds built, exchanged and solved.
void run_spin(const Config& c, const std::string& key, Report* report) {
  const std::string name = "spin";
  for (const std::string& bin : {c.vio_relay_bin, c.solver_bin})
    if (access(bin.c_str(), X_OK) != 0)
      throw std::runtime_error("spin scenario needs " + bin + " (build fact-vio-relay and fact-solver, or pass "
                               "--vio-relay-bin/--solver-bin)");
  Observer obs({kSwarmUrl}, 0);
  Processes procs(c.log);
  for (int i = 0; i < c.drones; ++i) {
    const std::string id = std::to_string(i);
    procs.start("relay" + id, {c.vio_relay_bin, "--source", "lcm", "--drone-id", id, "--lcm-url", kSwarmUrl});
    procs.start("gossip" + id, gossip_args(c, i, kSwarmUrl, key, false));
    procs.start("solver" + id, {c.solver_bin, "--drone-id", id, "--lcm-url", kSwarmUrl});
  }
  obs.spin(1.0);
  procs.require_running(name);
  // Drone i at (3 cos(2πi/N), 3 sin(2πi/N)), each spinning at 2π per period; its odometry frame is
  // the world turned by 0.3 i (the frames differ, as they do).
  const int n = c.drones;
  std::vector<Eigen::Vector2d> pos(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) pos[static_cast<size_t>(i)] = 3.0 * Eigen::Vector2d(std::cos(2 * M_PI * i / n), std::sin(2 * M_PI * i / n));
  const int64_t step = static_cast<int64_t>(1e6 / c.odometry_hz);
  const int64_t start = now_us();
  const int64_t end = start + static_cast<int64_t>(c.spin_seconds * 1e6);
  const int64_t warm = start + static_cast<int64_t>(std::min(5.0, 0.25 * c.spin_seconds) * 1e6);
  int64_t next = start, seq = 0;
  bool marked = false;
  int64_t published = 0;
  const double rate = 2 * M_PI / c.period;
  while (next < end) {
    obs.spin_until(next);
    if (!marked && next >= warm) {
      procs.mark();
      marked = true;
    }
    const double t = 1e-6 * static_cast<double>(next - start);
    for (int i = 0; i < n; ++i) {
      const double world_yaw = rate * t + 0.7 * i;
      const double frame_yaw = 0.3 * i;
      fact::odometry_t o{};
      o.utime = next;
      o.drone_id = i;
      o.seq = seq;
      const Eigen::Vector2d p = pos[static_cast<size_t>(i)];
      const double cf = std::cos(-frame_yaw), sf = std::sin(-frame_yaw);
      o.position[0] = cf * p.x() - sf * p.y();
      o.position[1] = sf * p.x() + cf * p.y();
      o.position[2] = 1.5;
      o.yaw = world_yaw - frame_yaw;  // unwrapped
      obs.at(0).publish("FACT_VIO_RAW_" + std::to_string(i), &o);
      fact::detections_t d{};
      d.utime = next;
      d.drone_id = i;
      d.frame_seq = seq;
      for (int j = 0; j < n; ++j) {
        if (j == i) continue;
        const Eigen::Vector2d rel = pos[static_cast<size_t>(j)] - p;
        const double bearing = std::remainder(std::atan2(rel.y(), rel.x()) - world_yaw, 2 * M_PI);
        if (std::abs(bearing) > 0.75) continue;  // outside an 87° field of view
        fact::detection_t det{};
        det.track_id = 100 + j;
        det.vector[0] = rel.norm() * std::cos(bearing);
        det.vector[1] = rel.norm() * std::sin(bearing);
        det.vector[2] = 0.0;
        det.confidence = 0.9f;
        det.range = rel.norm();
        d.detections.push_back(det);
      }
      d.count = static_cast<int32_t>(d.detections.size());
      obs.at(0).publish("FACT_DETECTIONS_" + std::to_string(i), &d);
      published += 2;
    }
    ++seq;
    next += step;
  }
  procs.measure();
  const double window = 1e-6 * static_cast<double>(end - warm);
  obs.spin(1.1);
  procs.require_running(name);
  std::vector<Child> done = procs.stop_all();
  // Per drone, % of one core over the window: relay, gossip, solver, and the chain's sum.
  std::map<std::string, std::vector<double>> cpu_of;  // kind → per drone
  std::vector<double> life;                           // gossip, whole lifetime
  int bad_exit = 0;
  for (const Child& ch : done) {
    const auto digit = ch.name.find_first_of("0123456789");
    const std::string kind = ch.name.substr(0, digit);
    const size_t drone = static_cast<size_t>(std::stoi(ch.name.substr(digit)));
    auto& v = cpu_of[kind];
    v.resize(static_cast<size_t>(n), 0.0);
    v[drone] = 100.0 * ch.window_cpu / window;
    if (kind == "gossip") life.push_back(100.0 * ch.lifetime_cpu / ch.lifetime);
    if (ch.exit_code != 0) ++bad_exit;
  }
  for (const char* kind : {"relay", "gossip", "solver"}) cpu_of[kind].resize(static_cast<size_t>(n), 0.0);
  std::vector<double> chain(static_cast<size_t>(n), 0.0);
  for (size_t i = 0; i < chain.size(); ++i) chain[i] = cpu_of["relay"][i] + cpu_of["gossip"][i] + cpu_of["solver"][i];
  const auto mean = [](const std::vector<double>& v) {
    return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(std::max<size_t>(v.size(), 1));
  };
  const auto max = [](const std::vector<double>& v) { return v.empty() ? NAN : *std::max_element(v.begin(), v.end()); };
  int solvers_with_result = 0;
  int64_t results_total = 0, results_min = -1;
  for (int i = 0; i < n; ++i) {
    const int64_t k = obs.results.count(i) ? obs.results[i] : 0;
    if (k > 0) ++solvers_with_result;
    results_total += k;
    results_min = results_min < 0 ? k : std::min(results_min, k);
  }
  int64_t relayed = 0, relay_rejected = 0, solver_estimates = 0;
  for (int i = 0; i < n; ++i) {
    for (const auto& [counter, value] : obs.counters[{"fact-vio-relay", i}]) {
      if (counter == "published") relayed += value;
      else if (counter.rfind("rejected_", 0) == 0 || counter == "wrong_drone_id" || counter == "undecodable")
        relay_rejected += value;
    }
    solver_estimates += obs.counters[{"fact-solver", i}]["estimates"];
  }
  int min_rounds = 1 << 30;
  for (int i = 0; i < n; ++i) min_rounds = std::min(min_rounds, obs.latest.count(i) ? obs.latest[i].complete_rounds : 0);
  int identical = 0;
  for (int i = 0; i < n; ++i)
    if (obs.latest.count(i) && obs.latest.count(0) && obs.latest[i].complete_rounds == obs.latest[0].complete_rounds &&
        content_bytes(obs.latest[i]) == content_bytes(obs.latest[0]))
      ++identical;
  int64_t obs_total = 0, packets = 0;
  if (obs.latest.count(0))
    for (const auto& p : obs.latest[0].packets) obs_total += p.count, ++packets;
  report->add(name, "drones", n, "");
  report->add(name, "odometry_and_detections_rate", c.odometry_hz, "Hz per drone");
  report->add(name, "spin_period", c.period, "s");
  report->add(name, "duration", c.spin_seconds, "s");
  report->add(name, "complete_rounds_min", min_rounds, "rounds");
  report->add(name, "drones_byte_identical", identical, "drones", std::to_string(n));
  report->add(name, "observations_per_packet", packets ? static_cast<double>(obs_total) / packets : 0, "");
  report->add(name, "relay_odometry_published", static_cast<double>(relayed), "messages");
  report->add(name, "relay_odometry_rejected", static_cast<double>(relay_rejected), "messages", "0");
  report->add(name, "solver_estimates", static_cast<double>(solver_estimates), "");
  report->add(name, "solvers_with_result", solvers_with_result, "drones", std::to_string(n));
  report->add(name, "results_total", static_cast<double>(results_total), "swarm_result_t");
  report->add(name, "results_min_per_drone", static_cast<double>(std::max<int64_t>(results_min, 0)), "swarm_result_t", ">= 1");
  for (const auto& [status, count] : obs.result_status)
    report->add(name, "results_status_" + (status.empty() ? std::string("empty") : status), static_cast<double>(count),
                "swarm_result_t");
  report->add(name, "window", window, "s");
  report->add(name, "relay_cpu_mean", mean(cpu_of["relay"]), "% of one core");
  report->add(name, "relay_cpu_max", max(cpu_of["relay"]), "% of one core");
  report->add(name, "gossip_cpu_mean", mean(cpu_of["gossip"]), "% of one core");
  report->add(name, "gossip_cpu_max", max(cpu_of["gossip"]), "% of one core");
  report->add(name, "solver_cpu_mean", mean(cpu_of["solver"]), "% of one core");
  report->add(name, "solver_cpu_max", max(cpu_of["solver"]), "% of one core");
  report->add(name, "chain_cpu_mean", mean(chain), "% of one core", "<= 5");
  report->add(name, "chain_cpu_max", max(chain), "% of one core", "<= 5");
  report->add(name, "gossip_cpu_lifetime_mean", mean(life), "% of one core");
  report->add(name, "processes_not_exiting_0", bad_exit, "", "0");
}

}  // namespace

int main(int argc, char** argv) {
  Config c;
  CLI::App cli{"fact-bench-gossip: latency, loss tolerance, bandwidth and CPU of fact-gossip processes over udpm. "
               "Run inside a private network namespace: scripts/netns-run.sh fact-bench-gossip"};
  cli.add_option("--drones", c.drones, "Swarm size")->capture_default_str()->check(fact::app::decimal_integer())
      ->check(CLI::Range(2, 30));
  cli.add_option("--rounds", c.rounds, "Rounds per exchange scenario")->capture_default_str()
      ->check(fact::app::decimal_integer())->check(CLI::Range(1, 100));
  cli.add_option("--period", c.period, "s between rounds (spin period)")->capture_default_str()->check(CLI::Range(0.2, 60.0));
  // (fact-gossip takes at most 64 observations a packet; a rate of 0 Hz hung the spin scenario)
  cli.add_option("--observations", c.observations, "Observations per injected round packet")->capture_default_str()
      ->check(fact::app::decimal_integer())->check(CLI::Range(1, 64));
  cli.add_option("--drop", c.drop, "Loss probability (lossy scenario)")->capture_default_str()->check(CLI::Range(0.0, 1.0));
  cli.add_option("--dup", c.dup, "Duplication probability (lossy scenario)")->capture_default_str()->check(CLI::Range(0.0, 1.0));
  cli.add_option("--reorder", c.reorder, "Hold-back probability (lossy scenario)")->capture_default_str()->check(CLI::Range(0.0, 1.0));
  cli.add_option("--spin-seconds", c.spin_seconds, "Length of the spin scenario (s)")->capture_default_str()->check(CLI::Range(2.0, 3600.0));
  cli.add_option("--odometry-hz", c.odometry_hz, "Odometry and detection rate in the spin scenario")->capture_default_str()->check(CLI::Range(1.0, 200.0));
  cli.add_option("--out", c.out, "CSV to write")->capture_default_str();
  cli.add_option("--gossip-bin", c.gossip_bin, "fact-gossip executable")->capture_default_str();
  cli.add_option("--relay-bin", c.relay_bin, "fact-fault-relay executable")->capture_default_str();
  cli.add_option("--vio-relay-bin", c.vio_relay_bin, "fact-vio-relay executable (spin scenario)")->capture_default_str();
  cli.add_option("--solver-bin", c.solver_bin, "fact-solver executable (spin scenario)")->capture_default_str();
  cli.add_option("--log", c.log, "Where the processes' log lines go")->capture_default_str();
  cli.add_flag("--quick", c.quick, "3 rounds every 1.5 s, 8 s of spin scenario (where --rounds, --period or --spin-seconds do not say)");
  if (const int code = fact::app::parse_command_line(cli, argc, argv); code >= 0) return code;
  if (c.quick) {  // a flag given explicitly wins, in whatever order
    if (cli.count("--rounds") == 0) c.rounds = 3;
    if (cli.count("--period") == 0) c.period = 1.5;
    if (cli.count("--spin-seconds") == 0) c.spin_seconds = 8;
  }
  const std::string nets = network_interfaces();
  if (nets != "lo") {
    std::cerr << "fact-bench-gossip: network interfaces '" << nets
              << "': run inside a private network namespace (scripts/netns-run.sh fact-bench-gossip); udpm must "
                 "never reach a real network\n";
    return 2;
  }
  std::ofstream(c.log, std::ios::trunc);
  const std::string key = key_file();
  Report report;
  try {
    std::cerr << "clean: " << c.drones << " drones, " << c.rounds << " rounds every " << c.period << " s …\n";
    run_exchange(c, false, key, &report);
    std::cerr << "lossy: drop " << c.drop << ", dup " << c.dup << ", reorder " << c.reorder << " …\n";
    run_exchange(c, true, key, &report);
    std::cerr << "spin: " << c.odometry_hz << " Hz raw odometry + detections through vio-relay, gossip and solver, "
              << c.spin_seconds << " s …\n";
    run_spin(c, key, &report);
  } catch (const std::exception& e) {
    std::cerr << "fact-bench-gossip: " << e.what() << "\n";
    std::remove(key.c_str());
    return 1;
  }
  std::remove(key.c_str());
  std::ostringstream out;  // written whole below (results_file.h)
  out << "scenario,metric,value,unit,target\n";
  for (const Row& r : report.rows) {
    char v[64];
    std::snprintf(v, sizeof v, "%.6g", r.value);
    out << r.scenario << "," << r.metric << "," << v << "," << r.unit << "," << r.target << "\n";
    if (r.metric.rfind("latency_round_", 0) == 0) continue;
    std::printf("%-6s %-38s %12s %-16s %s\n", r.scenario.c_str(), r.metric.c_str(), v, r.unit.c_str(),
                r.target.empty() ? "" : ("target " + r.target).c_str());
  }
  try {
    fact::bench::write_results_file(c.out, out.str());
  } catch (const std::exception& e) {
    std::cerr << "fact-bench-gossip: " << e.what() << "\n";
    return 1;
  }
  std::printf("written: %s (process logs: %s)\n", c.out.c_str(), c.log.c_str());
  return 0;
}
