// fact-rounds-publish: observation rounds from a file (fact-rounds-v1 JSON) onto LCM as the swarm's
// complete rounds (fact::swarm_rounds_t), the message fact-gossip gives fact-solver. It replays
// offline or generated data (fact-simgen) into a live solver, and feeds the solver in tests.
//
// Every publication carries rounds 0 … K−1 of the file (K = --rounds, or all); with --incremental
// the k-th publication carries only the first min(k, K), as gossip would when rounds complete one
// by one. Before publishing, the message is checked the way fact-solver reads it (every drone in
// every round, finite numbers, …), so the tool never sends what the solver would reject.
//
// Exit codes: 0 published (or stopped by SIGINT/SIGTERM); 1 LCM failed; 2 bad flags or input.
#include "common/cli_checks.h"
#include "common/app.h"
#include "common/convert.h"
#include "fact/json_io.h"
#include "fact/rounds.h"
#include "fact/swarm_rounds_t.hpp"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace {

constexpr const char* kApp = "fact-rounds-publish";

// Every parameter of the tool, with its unit.
struct Options {
  std::string input = "-";     // fact-rounds-v1 file; - = stdin
  std::string lcm_url;         // LCM provider URL; empty = LCM's default (LCM_DEFAULT_URL)
  int drone_id = 0;            // the drone whose gossip this stands in for (swarm_rounds_t.drone_id)
  std::string channel;         // empty = FACT_SWARM_ROUNDS_<drone-id>
  int count = 1;               // publications (0 = until SIGINT/SIGTERM)
  double interval = 0.5;       // s between publications (>= 0)
  int rounds = 0;              // publish only the first K rounds of the file (0 = all)
  bool incremental = false;    // publication k carries rounds 0 … min(k, K) − 1
  int64_t utime = -1;          // utime of every message (µs); −1 = the wall clock at publication
};

// Bad flags or input: exit code 2.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void add_flags(CLI::App& app, Options& o) {
  app.add_option("--input", o.input, "fact-rounds-v1 file to read; - for stdin")->type_name("FILE")->capture_default_str();
  app.add_option("--lcm-url", o.lcm_url, "LCM URL, e.g. udpm://239.255.76.67:7667?ttl=0 (default: LCM's default)")
      ->type_name("URL");
  app.add_option("--drone-id", o.drone_id, "Drone id written in the message and in the default channel (>= 0)")
      ->type_name("ID")
      ->capture_default_str()->check(fact::app::decimal_integer());
  app.add_option("--channel", o.channel, "Channel to publish on (default FACT_SWARM_ROUNDS_<drone-id>)")
      ->type_name("CHANNEL");
  app.add_option("--count", o.count, "Number of publications (0 = until SIGINT/SIGTERM)")
      ->type_name("N")
      ->capture_default_str()->check(fact::app::decimal_integer());
  app.add_option("--interval", o.interval, "Seconds between publications (>= 0)")->type_name("S")->capture_default_str();
  app.add_option("--rounds", o.rounds, "Publish only the first K rounds of the file (0 = all)")
      ->type_name("K")
      ->capture_default_str()->check(fact::app::decimal_integer());
  app.add_flag("--incremental", o.incremental,
               "Publication k carries only the first min(k, K) rounds, as rounds complete one by one");
  app.add_option("--utime", o.utime, "utime of every message in microseconds (-1 = the wall clock when published)")
      ->type_name("US")
      ->capture_default_str()->check(fact::app::decimal_integer());
  app.footer(
      "Publishes fact::swarm_rounds_t (the message fact-gossip sends fact-solver) from a\n"
      "fact-rounds-v1 file: round k of the file becomes round number k. One log line per\n"
      "publication on stderr. A fixed --utime makes the solver's result reproducible bit for bit\n"
      "(fact-solver stamps its result with the input's utime).\n"
      "Exit codes: 0 published; 1 LCM failed; 2 bad flags or input.");
}

void check(Options& o) {
  if (o.drone_id < 0) throw InputError("--drone-id: expected an id >= 0, got " + std::to_string(o.drone_id));
  if (o.channel.empty()) o.channel = fact::app::channel("FACT_SWARM_ROUNDS", o.drone_id);
  if (o.count < 0) throw InputError("--count: expected >= 0 (0 = until stopped), got " + std::to_string(o.count));
  if (!(o.interval >= 0 && o.interval <= 86400)) {  // (a day: a longer pause overflowed the clock's ticks)
    std::ostringstream s;
    s << "--interval: expected a number of seconds in [0, 86400], got " << o.interval;
    throw InputError(s.str());
  }
  // LCM channel names are at most 63 bytes (udpm refused a longer one at publish time, exit 1).
  if (o.channel.size() > 63)
    throw InputError("--channel: " + std::to_string(o.channel.size()) + " characters, LCM allows at most 63: " + o.channel);
  if (o.rounds < 0) throw InputError("--rounds: expected >= 0 (0 = all), got " + std::to_string(o.rounds));
  if (o.utime < -1) throw InputError("--utime: expected microseconds >= 0 (or -1 = clock), got " + std::to_string(o.utime));
}

std::string read_input(const std::string& name) {
  std::ifstream file;
  std::istream* in = &std::cin;
  if (name != "-") {
    std::error_code ec;
    if (std::filesystem::is_directory(name, ec)) throw InputError("--input " + name + ": is a directory, not a rounds file");
    file.open(name, std::ios::binary);
    if (!file) throw InputError("--input " + name + ": cannot open: " + std::strerror(errno));
    in = &file;
  }
  std::string text;
  try {
    text.assign(std::istreambuf_iterator<char>(*in), std::istreambuf_iterator<char>());
  } catch (const std::exception& e) {  // (a read error the stream reports by throwing)
    throw InputError((name == "-" ? std::string("stdin") : name) + ": read failed: " + e.what());
  }
  if (in->bad()) throw InputError((name == "-" ? std::string("stdin") : name) + ": read failed");
  return text;
}

// The messages to publish, one per distinct number of rounds (1 … K with --incremental, else K),
// each checked by reading it back as fact-solver does. utime is filled in at publication.
std::vector<fact::swarm_rounds_t> messages_from(const fact::Rounds& all, const Options& o) {
  if (o.rounds > static_cast<int>(all.rounds.size()))
    throw InputError("--rounds " + std::to_string(o.rounds) + ": " + o.input + " holds only " +
                     std::to_string(all.rounds.size()) + " round(s)");
  const fact::Rounds rounds = fact::first_rounds(all, o.rounds);
  const int total = static_cast<int>(rounds.rounds.size());
  if (total == 0) throw InputError(o.input + ": no rounds to publish");
  std::vector<fact::swarm_rounds_t> out;
  for (int k = o.incremental ? 1 : total; k <= total; ++k) {
    fact::swarm_rounds_t m = fact::app::rounds_to_message(fact::first_rounds(rounds, k), o.drone_id, 0);
    fact::Rounds back;
    const std::string error = fact::app::rounds_from_message(m, &back);
    if (!error.empty())
      throw InputError(o.input + ": the first " + std::to_string(k) + " rounds cannot be published: " + error);
    out.push_back(std::move(m));
  }
  return out;
}

// Sleeps `seconds`, waking early when a stop is requested.
void pause(double seconds) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point end =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
  while (!fact::app::stop_requested()) {
    const Clock::duration left = end - Clock::now();
    if (left <= Clock::duration::zero()) return;
    std::this_thread::sleep_for(std::min<Clock::duration>(left, std::chrono::milliseconds(50)));
  }
}

int run(const Options& o) {
  fact::Rounds rounds;
  try {
    rounds = fact::rounds_from_json(read_input(o.input));
  } catch (const fact::FormatError& e) {
    throw InputError((o.input == "-" ? std::string("stdin") : o.input) + ": " + e.what());
  }
  std::vector<fact::swarm_rounds_t> messages = messages_from(rounds, o);

  const fact::app::Log log(kApp, o.drone_id);
  lcm::LCM lcm(o.lcm_url);
  if (!fact::app::lcm_opened(lcm, o.lcm_url, log)) return 1;
  fact::app::install_stop_handler();
  for (int i = 0; (o.count == 0 || i < o.count) && !fact::app::stop_requested(); ++i) {
    if (i > 0) pause(o.interval);
    if (fact::app::stop_requested()) break;
    fact::swarm_rounds_t& m = messages[std::min<std::size_t>(i, messages.size() - 1)];
    m.utime = o.utime >= 0 ? o.utime : fact::app::now_us();
    if (lcm.publish(o.channel, &m) != 0) {
      log.event("error: publish on " + o.channel + " failed");
      return 1;
    }
    log.event("published complete_rounds=" + std::to_string(m.complete_rounds) + " drones=" +
              std::to_string(m.num_drones) + " packets=" + std::to_string(m.num_packets) + " bytes=" +
              std::to_string(m.getEncodedSize()) + " on " + o.channel);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  CLI::App app{"Publishes observation rounds from a fact-rounds-v1 file as the swarm's complete rounds\n"
               "(fact::swarm_rounds_t) on LCM, e.g. into a running fact-solver.",
               kApp};
  add_flags(app, options);
  app.get_formatter()->column_width(30);
  try {
    fact::app::refuse_empty_values(app);
    app.parse(argc, argv);
    check(options);
    return run(options);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    std::cerr << kApp << ": error: " << e.what() << " (see --help)\n";
    return 2;
  } catch (const InputError& e) {
    std::cerr << kApp << ": error: " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << kApp << ": error: " << e.what() << '\n';
    return 1;
  }
}
