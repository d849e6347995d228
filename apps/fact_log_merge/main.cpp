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
// event (a logger stopped mid-write) contributes every whole event before it.
// Exit codes: 0 merged; 1 the output cannot be written; 2 bad flags, or an input that cannot be
// read (nothing is written then).
#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <cstdio>
#include <iostream>
#include <memory>
#include <queue>
#include <string>
#include <vector>

namespace {

constexpr const char* kApp = "fact-log-merge";

// One input log and a copy of its next event (readNextEvent's buffer is reused on the next read).
struct Input {
  std::string path;
  std::unique_ptr<lcm::LogFile> log;
  std::string channel;
  std::string data;
  int64_t timestamp = 0;
  int64_t events = 0;  // read so far
  bool ended = false;

  void advance() {
    const lcm::LogEvent* e = log->readNextEvent();
    if (!e) {
      ended = true;
      return;
    }
    channel = e->channel;
    data.assign(static_cast<const char*>(e->data), static_cast<size_t>(e->datalen));
    timestamp = e->timestamp;
    ++events;
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
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return cli.exit(e) == 0 ? 0 : 2;
  }
  std::vector<Input> in(inputs.size());
  for (size_t i = 0; i < inputs.size(); ++i) {
    in[i].path = inputs[i];
    in[i].log = std::make_unique<lcm::LogFile>(inputs[i], "r");
    if (!in[i].log->good()) {
      std::cerr << kApp << ": error: cannot read the LCM log " << inputs[i] << " (input " << i + 1 << ")\n";
      return 2;
    }
    in[i].advance();
  }
  lcm::LogFile out(output, "w");
  if (!out.good()) {
    std::cerr << kApp << ": error: cannot write " << output << "\n";
    return 1;
  }
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
    if (out.writeEvent(&e) != 0) {
      std::cerr << kApp << ": error: writing event " << written << " to " << output << " failed\n";
      return 1;
    }
    ++written;
    in[i].advance();
    if (!in[i].ended) next.push(i);
  }
  std::string counts;
  for (const Input& i : in) {
    counts += (counts.empty() ? "" : ", ") + i.path + " " + std::to_string(i.events);
    if (i.events == 0) std::cerr << kApp << ": warning: " << i.path << " holds no events (empty or not an LCM log)\n";
  }
  std::cout << kApp << ": wrote " << written << " events to " << output << " (" << counts << ")\n";
  return 0;
}
