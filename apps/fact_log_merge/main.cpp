// fact-log-merge: several LCM logs (lcm-logger files) into one, in timestamp order. scripts/run-sim.sh
// records each drone's own bus and the swarm's bus with one lcm-logger each (an LCM URL is one
// multicast group) and merges them into run.lcm, the log that fact-run-report and
// scripts/replay.sh read.
//
//   fact-log-merge --output RUN.lcm IN1.lcm IN2.lcm ...
//
// Events are copied unchanged (channel, timestamp, bytes); an event's number is its place in the
// output. Each input is read once, front to back (a K-way merge: memory is one event per input),
// and events with equal timestamps keep the order of the inputs. An input that ends in a cut-off
// event (a logger stopped mid-write) contributes every whole event before it (with a warning).
// Inputs are read with fact::app::LogReader: a damaged input (a wrong sync word, an impossible
// length) is an error, never a silent early end. The output is written to OUTPUT.partial-XXXXXX
// and renamed when complete, and may not be one of the inputs; no input may be given twice. An
// input whose timestamps go back is merged as it is, with a warning.
// Exit codes: 0 merged; 1 the output cannot be written; 2 bad flags, an input that cannot be
// read, is damaged or is not an LCM log, or the output named as an input (nothing is written then).
#include "common/cli_checks.h"
#include "common/log_reader.h"
#include "fact/file_write.h"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <queue>
#include <string>
#include <vector>

namespace {

constexpr const char* kApp = "fact-log-merge";

// One input log and a copy of its next event (the reader's buffer is reused on the next read).
struct Input {
  std::string path;
  std::unique_ptr<fact::app::LogReader> log;
  std::string channel;
  std::string data;
  int64_t timestamp = 0;
  bool ended = false;
  // Events stamped over a second earlier than the one before: a recorder's clock set back. (Steps
  // of a few µs are lcm-logger's own: it stamps on receipt, and its receive paths race.)
  int64_t backwards = 0;
  static constexpr int64_t kClockStepUs = 1000000;

  void advance() {
    lcm::LogEvent e;
    if (!log->next(&e)) {
      ended = true;
      return;
    }
    if (log->events() > 1 && e.timestamp < timestamp - kClockStepUs) ++backwards;
    channel = e.channel;
    data.assign(static_cast<const char*>(e.data), static_cast<size_t>(e.datalen));
    timestamp = e.timestamp;
  }
};

}  // namespace

int main(int argc, char** argv) {
  std::string output;
  std::vector<std::string> inputs;
  CLI::App cli{"fact-log-merge: merges LCM logs (lcm-logger files) into one, in timestamp order.", kApp};
  cli.add_option("--output", output, "The merged log to write")->required()->type_name("FILE");
  cli.add_option("inputs", inputs, "The logs to merge")->required()->type_name("LOG");
  cli.footer("Exit codes: 0 merged; 1 the output cannot be written; 2 bad flags or an unreadable input.");
  if (const int code = fact::app::parse_command_line(cli, argc, argv); code >= 0) return code;
  std::vector<Input> in(inputs.size());
  for (size_t i = 0; i < inputs.size(); ++i) {
    if (fact::same_file(inputs[i], output)) {
      std::cerr << kApp << ": error: --output " << output << " is input " << i + 1 << " (" << inputs[i]
                << "): it would be overwritten before it is read\n";
      return 2;
    }
    for (size_t j = 0; j < i; ++j)
      if (fact::same_file(inputs[i], inputs[j])) {  // (its events would be merged twice)
        std::cerr << kApp << ": error: input " << i + 1 << " (" << inputs[i] << ") is input " << j + 1 << " ("
                  << inputs[j] << ") again\n";
        return 2;
      }
    in[i].path = inputs[i];
    in[i].log = std::make_unique<fact::app::LogReader>();
    if (const std::string e = in[i].log->open(inputs[i]); !e.empty()) {
      std::cerr << kApp << ": error: " << e << " (input " << i + 1 << ")\n";
      return 2;
    }
    in[i].advance();
  }
  // Written to a fresh OUTPUT.partial-XXXXXX (fact::open_partial_file: never an existing file, such
  // as an input named OUTPUT.partial, which was truncated and removed; with the old output's mode,
  // or 0666 less the umask, not mkstemp's 0600, which made run.lcm unreadable to others: review,
  // session 33) and renamed at the end: a damaged input or a failed write leaves nothing at OUTPUT.
  std::string partial;
  const int partial_fd = fact::open_partial_file(output, &partial);
  if (partial_fd < 0) {
    std::cerr << kApp << ": error: cannot write " << output << ".partial-*: " << std::strerror(errno) << "\n";
    return 1;
  }
  ::close(partial_fd);
  const auto fail = [&](int code, const std::string& why) {
    std::cerr << kApp << ": error: " << why << "\n";
    std::remove(partial.c_str());
    return code;
  };
  auto out = std::make_unique<lcm::LogFile>(partial, "w");
  if (!out->good()) return fail(1, "cannot write " + partial);
  // Min-heap on (timestamp, input index): the earliest event next, ties in input order.
  const auto later = [&](size_t a, size_t b) {
    return in[a].timestamp != in[b].timestamp ? in[a].timestamp > in[b].timestamp : a > b;
  };
  std::priority_queue<size_t, std::vector<size_t>, decltype(later)> next(later);
  for (size_t i = 0; i < in.size(); ++i)
    if (!in[i].ended) next.push(i);
  int64_t written = 0;
  while (!next.empty()) {
    const size_t i = next.top();
    next.pop();
    lcm::LogEvent e;
    e.eventnum = written;
    e.timestamp = in[i].timestamp;
    e.channel = in[i].channel;
    e.datalen = static_cast<int32_t>(in[i].data.size());
    e.data = in[i].data.data();
    if (out->writeEvent(&e) != 0) return fail(1, "writing event " + std::to_string(written) + " to " + partial + " failed");
    ++written;
    in[i].advance();
    if (!in[i].ended) next.push(i);
  }
  std::string counts;
  for (const Input& i : in) {
    if (!i.log->error().empty()) return fail(2, "the LCM log is damaged: " + i.log->error() + " (nothing written)");
    if (i.log->torn()) std::cerr << kApp << ": warning: " << i.log->note() << "\n";
    if (i.backwards > 0)
      std::cerr << kApp << ": warning: " << i.path << ": " << i.backwards << " event(s) stamped over 1 s earlier than "
                << "the one before (its recorder's clock was set back?): the merge is in timestamp order only where "
                << "the inputs are\n";
    counts += (counts.empty() ? "" : ", ") + i.path + " " + std::to_string(i.log->events());
    if (i.log->events() == 0 && std::filesystem::file_size(i.path) > 0)
      return fail(2, i.path + " is not an LCM log (no event in its " + std::to_string(std::filesystem::file_size(i.path)) +
                         " bytes; nothing written)");
    if (i.log->events() == 0) std::cerr << kApp << ": warning: " << i.path << " is empty\n";
  }
  // The last buffered bytes are written at close: check them (a full disk lost the end silently).
  std::FILE* f = out->getFilePtr();
  const bool flushed = std::fflush(f) == 0 && std::ferror(f) == 0;
  out.reset();
  if (!flushed) return fail(1, "writing " + partial + " failed at the end (disk full?)");
  if (std::rename(partial.c_str(), output.c_str()) != 0) return fail(1, "cannot rename " + partial + " to " + output);
  std::cout << kApp << ": wrote " << written << " events to " << output << " (" << counts << ")\n";
  return 0;
}
