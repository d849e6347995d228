// fact-lcm-publish-sample: publishes one sample of every top-level fact LCM type (test/lcm_samples.h)
// on its channel, --count times, for lcm-spy and Java decoding checks (test_lcm_spy.sh). A test
// tool, not an app: it makes no data of its own meaning.
//   fact-lcm-publish-sample --lcm-url 'udpm://239.255.76.67:7667?ttl=0' --count 5 --period-ms 100
//   fact-lcm-publish-sample --lcm-url 'file:///tmp/sample.lcmlog?mode=w'    (an LCM log file)
// Channels: FACT_ODOMETRY_<id>, FACT_SETPOINT_<id>, FACT_DETECTIONS_<id>, FACT_FRAMES_<id>,
// FACT_GOSSIP, FACT_SWARM_ROUNDS_<id>, FACT_RESULT_<id>, FACT_STATUS, FACT_TRUTH, and the gossip
// payload types on their own sample channels FACT_SAMPLE_ROUND_PACKET, FACT_SAMPLE_GOSSIP_REQUEST,
// FACT_SAMPLE_GOSSIP_SUMMARY. Prints one line per published round of messages; exits 1 if LCM fails.
#include "common/app.h"
#include "lcm_samples.h"

#include <CLI/CLI.hpp>

#include <chrono>
#include <string>
#include <thread>

namespace {

struct Options {
  std::string lcm_url;       // LCM provider URL; empty = LCM's default (udpm://239.255.76.67:7667)
  int drone_id = 1;          // id in the per-drone channel names and the messages
  int count = 3;             // how many times every type is published
  int period_ms = 100;       // ms between two publishes of the set
};

template <class T>
bool send(lcm::LCM& lcm, const std::string& channel, const T& msg, fact::app::Status& status) {
  if (lcm.publish(channel, &msg) != 0) return false;
  status.count("published");
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App cli{"Publishes one sample message of every fact LCM type on its channel (a test tool)."};
  cli.add_option("--lcm-url", o.lcm_url, "LCM URL (use udpm only inside scripts/netns-run.sh)");
  cli.add_option("--drone-id", o.drone_id, "drone id of the per-drone channels")->capture_default_str();
  cli.add_option("--count", o.count, "times every type is published")->capture_default_str()->check(CLI::Range(1, 100000));
  cli.add_option("--period-ms", o.period_ms, "ms between two sets")->capture_default_str()->check(CLI::Range(0, 60000));
  CLI11_PARSE(cli, argc, argv);

  fact::app::Log log("fact-lcm-publish-sample", o.drone_id);
  lcm::LCM lcm(o.lcm_url);
  if (!lcm.good()) {
    log.event("cannot open LCM at '" + o.lcm_url + "'");
    return 1;
  }
  fact::app::Status status(&lcm, "FACT_STATUS", "fact-lcm-publish-sample", o.drone_id);
  status.set_state("publishing");
  const int id = o.drone_id;
  using fact::app::channel;
  namespace s = fact::samples;
  for (int i = 0; i < o.count; ++i) {
    const int64_t t = fact::app::now_us();
    bool ok = send(lcm, channel("FACT_ODOMETRY", id), s::odometry(t, id), status) &&
              send(lcm, channel("FACT_SETPOINT", id), s::setpoint(t, id), status) &&
              send(lcm, channel("FACT_DETECTIONS", id), s::detections(t, id), status) &&
              send(lcm, channel("FACT_FRAMES", id), s::frame(t, id), status) &&
              send(lcm, "FACT_GOSSIP", s::gossip_packet(t, id), status) &&
              send(lcm, "FACT_SAMPLE_ROUND_PACKET", s::round_packet(t, id, i), status) &&
              send(lcm, "FACT_SAMPLE_GOSSIP_REQUEST", s::gossip_request(t, id), status) &&
              send(lcm, "FACT_SAMPLE_GOSSIP_CHALLENGE", s::gossip_challenge(t, id), status) &&
              send(lcm, "FACT_SAMPLE_GOSSIP_SUMMARY", s::gossip_summary(t, id), status) &&
              send(lcm, channel("FACT_SWARM_ROUNDS", id), s::swarm_rounds(t, id), status) &&
              send(lcm, channel("FACT_RESULT", id), s::swarm_result(t, id), status) &&
              send(lcm, "FACT_TRUTH", s::truth(t), status) &&
              send(lcm, "FACT_SIM_CLOCK", s::sim_clock(t), status) &&
              send(lcm, channel("FACT_FC_STATE", id), s::fc_state(t, id), status);
    if (!ok) {
      log.event("publish failed");
      return 1;
    }
    status.note("set " + std::to_string(i + 1) + " of " + std::to_string(o.count));
    status.publish(t);  // FACT_STATUS: a real app_status_t from fact::app::Status
    log.event("published set " + std::to_string(i + 1) + " of " + std::to_string(o.count) + " (12 types)");
    if (i + 1 < o.count) std::this_thread::sleep_for(std::chrono::milliseconds(o.period_ms));
  }
  return 0;
}
