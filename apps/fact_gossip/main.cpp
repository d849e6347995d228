// fact-gossip: one per drone. Builds this drone's round packets from its detections and
// odometry (or takes ready-made ones), exchanges round packets with every other drone's gossip
// on FACT_GOSSIP until all hold the same complete data, and publishes that data
// (fact::swarm_rounds_t on FACT_SWARM_ROUNDS_<id>) whenever it grows. The logic is
// fact::gossip::Gossip and fact::gossip::RoundBuilder (lib/include/fact/gossip.h); this file is the
// LCM shell: subscriptions, the authenticated envelope (fact_gossip/wire.h), status and logs.
//
// Subscribes: FACT_DETECTIONS_<id> (detections_t) and FACT_ODOMETRY_<id> (odometry_t), or with
// --rounds-from-channel FACT_ROUND_PACKET_<id> (round_packet_t, numbered by their sender);
// FACT_GOSSIP (gossip_packet_t). Publishes: FACT_GOSSIP, FACT_SWARM_ROUNDS_<id>, FACT_STATUS.
// With --swarm-url, FACT_GOSSIP (in and out) is on that URL, the swarm's bus, and everything else
// on --lcm-url, the drone's own bus: the only traffic between drones is the gossip.
// Exit codes: 0 on SIGINT/SIGTERM; 2 bad flags, key or options; 1 LCM unusable.
#include "common/cli_checks.h"
#include "common/app.h"
#include "common/flags.h"
#include "common/convert.h"
#include "fact/detections_t.hpp"
#include "fact/gossip.h"
#include "fact/odometry_t.hpp"
#include "fact/round_packet_t.hpp"
#include "fact/swarm_rounds_t.hpp"
#include "fact_gossip/wire.h"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cmath>
#include <deque>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace {

using fact::app::channel;
using fact::app::monotonic_us;
using fact::app::now_us;

// Every parameter, with its unit, in one place.
struct Flags {
  fact::app::CommonFlags common;            // --drone-id (required), --lcm-url, status, --sim-clock
  std::string key_file;                     // swarm key: 32 raw bytes or 64 hex digits
  bool insecure = false;                    // no key: zero macs, nothing checked
  std::string session;                      // this flight's name, mixed into the key ("" = none)
  std::vector<int> roster;                  // the swarm's ids (empty: any id 0 … max_drone_id)
  int max_drone_id = 9999;
  int min_members = 2;                      // complete data needs at least this many drones
  bool rounds_from_channel = false;         // take round_packet_t instead of building rounds
  double round_period = 0;                  // s; > 0: rounds of this length instead of spins
  double spin_angle = 2 * M_PI;             // rad of net yaw turn that closes a round
  double max_speed = 0.25;                  // m/s; faster, the drone is moving and the open round restarts
  double detection_latency = 0.3;           // s of odometry time a round waits for late detections
  double max_odometry_gap = 0.5;            // s; no interpolation across larger gaps
  double summary_period = 1.0;              // s, heartbeat summary
  double summary_min_interval = 0.1;        // s, event summary after a change, at most this often
  double silence_timeout = 5.0;             // s, a drone unheard this long is silent
  double request_interval = 0.2;            // s, re-request one origin at most this often
  double answer_slot = 0.015;               // s, answer delay per rank (non-origin holders)
  double settle = 1.5;                      // s after start before completing or numbering own rounds
  int max_rounds = 128;                     // rounds kept per drone
  int max_origins = 32;                     // drone ids tracked
  int future_window = 16;                   // rounds accepted past what is held
  int max_observations = 64;                // per round packet
  std::string gossip_channel = "FACT_GOSSIP";
  std::string swarm_url;                    // "" = the gossip on --lcm-url too
  std::string detections_channel;           // default FACT_DETECTIONS_<id>
  std::string odometry_channel;             // default FACT_ODOMETRY_<id>
  std::string round_channel;                // default FACT_ROUND_PACKET_<id>
  std::string output_channel;               // default FACT_SWARM_ROUNDS_<id>
};

int64_t us(double seconds) { return static_cast<int64_t>(std::llround(seconds * 1e6)); }

// The times and counts of the flags, in their units and one by one, before any is converted to µs
// (1e14 s overflowed and read as "negative"; NaN passed as a period); throws FlagError naming the
// flag and the value. Periods and timeouts are 1 ms … 1 h, delays 0 … 1 h.
void check_times(const Flags& f) {
  using fact::app::check_range;
  check_range("--summary-period", f.summary_period, 0.001, 3600, "s");
  check_range("--silence-timeout", f.silence_timeout, 0.001, 3600, "s");
  check_range("--request-interval", f.request_interval, 0.001, 3600, "s");
  check_range("--max-odometry-gap", f.max_odometry_gap, 0.001, 3600, "s");
  check_range("--summary-min-interval", f.summary_min_interval, 0, 3600, "s");
  check_range("--answer-slot", f.answer_slot, 0, 3600, "s");
  check_range("--settle", f.settle, 0, 3600, "s");
  check_range("--detection-latency", f.detection_latency, 0, 3600, "s");
  if (f.round_period != 0) check_range("--round-period", f.round_period, 0.001, 3600, "s (or 0: spins)");
  check_range("--spin-angle", f.spin_angle, 1e-3, 1e3, "rad");
  check_range("--max-speed", f.max_speed, 0, 1e3, "m/s");
  // Complete data holds only live drones of the roster (or of the ids tracked): more can never be.
  const int most = f.roster.empty() ? f.max_origins : static_cast<int>(f.roster.size());
  if (f.min_members > most)
    throw fact::app::FlagError("--min-members " + std::to_string(f.min_members) + " can never be reached: at most " +
                               std::to_string(most) + (f.roster.empty() ? " drones (--max-origins)" : " drones (--roster)"));
}

std::string ids_text(const std::vector<int>& ids) {
  std::string s = "[";
  for (size_t i = 0; i < ids.size(); ++i) s += (i ? "," : "") + std::to_string(ids[i]);
  return s + "]";
}

class GossipApp {
 public:
  GossipApp(const Flags& f, const fact::gossip::Options& go, const fact::gossip::BuilderOptions& bo,
            const fact::app::SwarmKey& key, lcm::LCM* lcm, lcm::LCM* swarm, int64_t start, int64_t first_seq)
      : f_(f),
        key_(key),
        lcm_(lcm),
        swarm_(swarm),
        log_("fact-gossip", f.common.drone_id),
        status_(lcm, f.common.status_channel, "fact-gossip", f.common.drone_id),
        gossip_(go, start),
        builder_(bo),
        seq_(first_seq) {
    status_.set_period_us(us(f.common.status_period));
  }

  void subscribe() {
    swarm_->subscribe(f_.gossip_channel, &GossipApp::on_gossip, this);
    if (f_.rounds_from_channel) {
      lcm_->subscribe(f_.round_channel, &GossipApp::on_round_packet, this);
    } else {
      lcm_->subscribe(f_.odometry_channel, &GossipApp::on_odometry, this);
      lcm_->subscribe(f_.detections_channel, &GossipApp::on_detections, this);
    }
  }

  const fact::app::Log& log() const { return log_; }

  // Everything periodic and everything an event may have caused: rounds the builder closed, the
  // gossip's messages, completion, logs, status. `now` is monotonic_us(): every interval and
  // timeout of the gossip runs on it (a wall-clock step back froze the gossip for the step, one
  // forward made every peer silent); messages are stamped with now_us().
  void step(int64_t now) {
    for (auto& r : builder_.take_rounds()) {
      const std::string e = gossip_.add_own_round(now, r.end_utime, r.data);
      if (!e.empty()) reject("own_round_refused", "own round refused: " + e);
    }
    for (const auto& out : gossip_.tick(now)) send(out);
    publish_complete(now);
    for (const std::string& line : gossip_.take_events()) {
      log_.event(line);
      status_.note(line);
    }
    if (now - last_status_ >= status_.period_us()) update_status(now);
    status_.tick(now_us());
  }

  int64_t next_deadline(int64_t now) const {
    return std::min(gossip_.next_deadline(now), last_status_ + status_.period_us());
  }

 private:
  // A refused input: counted; logged the 1st, 10th, 100th, … time per counter (bounded logs).
  void reject(const std::string& counter, const std::string& line) {
    status_.count(counter);
    const int64_t n = status_.value(counter);
    int64_t p = 1;
    while (p < n) p *= 10;
    if (p == n) log_.event(line + " [" + counter + " = " + std::to_string(n) + "]");
  }

  void send(const fact::gossip::Outgoing& out) {
    std::vector<uint8_t> payload;
    int8_t kind = 0;
    switch (out.kind) {
      case fact::gossip::Outgoing::Kind::round:
        payload = fact::app::encode_bytes(fact::app::packet_to_message(out.packet));
        kind = fact::gossip_packet_t::ROUND;
        break;
      case fact::gossip::Outgoing::Kind::summary:
        payload = fact::app::encode_bytes(fact::app::summary_to_message(out.summary, now_us()));
        kind = fact::gossip_packet_t::SUMMARY;
        break;
      case fact::gossip::Outgoing::Kind::request:
        payload = fact::app::encode_bytes(fact::app::request_to_message(out.request, now_us()));
        kind = fact::gossip_packet_t::REQUEST;
        break;
    }
    send_envelope(kind, std::move(payload));
  }

  void send_envelope(int8_t kind, std::vector<uint8_t> payload) {
    const fact::gossip_packet_t env =
        fact::app::make_envelope(f_.common.drone_id, seq_++, kind, std::move(payload), now_us(), key_);
    const int size = env.getEncodedSize();
    if (swarm_->publish(f_.gossip_channel, &env) != 0) {
      reject("publish_failed", "publishing on " + f_.gossip_channel + " failed");
      return;
    }
    status_.count("packets_sent");
    status_.count("bytes_sent", size);
  }

  void publish_complete(int64_t now) {
    const fact::gossip::Completion c = gossip_.completion(now);
    if (!c.ready || (c.rounds == published_rounds_ && c.drones == published_drones_)) return;
    fact::swarm_rounds_t m;
    m.utime = now_us();
    m.drone_id = f_.common.drone_id;
    m.complete_rounds = c.rounds;
    m.num_drones = static_cast<int32_t>(c.drones.size());
    m.drone_ids.assign(c.drones.begin(), c.drones.end());
    for (const fact::gossip::Packet* p : gossip_.complete_packets(c)) m.packets.push_back(fact::app::packet_to_message(*p));
    m.num_packets = static_cast<int32_t>(m.packets.size());
    if (lcm_->publish(f_.output_channel, &m) != 0) {
      reject("publish_failed", "publishing on " + f_.output_channel + " failed");
      return;
    }
    published_rounds_ = c.rounds;
    published_drones_ = c.drones;
    status_.count("swarm_rounds_published");
    const std::string line = "complete: " + std::to_string(c.rounds) + " round(s) of drones " + ids_text(c.drones) +
                             " published on " + f_.output_channel +
                             (c.silent.empty() ? "" : " (silent: " + ids_text(c.silent) + ")");
    log_.event(line);
    status_.note(line);
  }

  void update_status(int64_t now) {
    last_status_ = now;
    for (const auto& [name, v] : gossip_.counters().list()) sync(name, v);
    for (const auto& [name, v] : builder_.counters().list()) sync(name, v);
    const fact::gossip::Completion c = gossip_.completion(now);
    std::string s = "complete " + std::to_string(c.rounds) + " rounds; live " + ids_text(c.live) + "; silent " +
                    ids_text(c.silent) + "; held";
    for (const auto& m : gossip_.members(now)) s += " " + std::to_string(m.id) + ":" + std::to_string(m.rounds_held);
    status_.set_state(s);
  }

  // Status counts increments only: report the lib's counters as differences.
  void sync(const std::string& name, int64_t value) {
    const int64_t delta = value - status_.value(name);
    if (delta != 0) status_.count(name, delta);
  }

  void on_gossip(const lcm::ReceiveBuffer* rbuf, const std::string& chan) {
    fact::gossip_packet_t env;
    if (!fact::app::decode(rbuf, chan, &env, &status_, log_)) return;
    const int64_t now = monotonic_us();
    if (env.sender_id == f_.common.drone_id) {
      // Our own packets come back by multicast loopback, numbered first_seq_ … seq_ − 1; any
      // other number is another process using this drone id.
      if (env.seq < first_seq_ || env.seq >= seq_)
        reject("duplicate_drone_id", "envelope seq " + std::to_string(env.seq) + " with this drone's id " +
                                         std::to_string(f_.common.drone_id) + " was not sent by this process: another "
                                         "process uses drone id " + std::to_string(f_.common.drone_id));
      return;
    }
    if (env.payload_size < 0 || static_cast<size_t>(env.payload_size) != env.payload.size()) {
      reject("undecodable", "envelope from drone " + std::to_string(env.sender_id) + ": payload_size " +
                                std::to_string(env.payload_size) + " ≠ payload bytes");
      return;
    }
    if (!fact::app::verify(env, key_)) {
      reject("auth_failed", "envelope from drone " + std::to_string(env.sender_id) + " seq " + std::to_string(env.seq) +
                                " fails authentication (wrong swarm key or altered): dropped");
      return;
    }
    if (env.kind < fact::gossip_packet_t::ROUND || env.kind > fact::gossip_packet_t::RESPONSE) {
      reject("bad_kind", "envelope from drone " + std::to_string(env.sender_id) + " of unknown kind " +
                             std::to_string(static_cast<int>(env.kind)));
      return;
    }
    const fact::gossip::Screen screen = gossip_.screen_envelope(now, env.sender_id, env.seq);
    if (screen != fact::gossip::Screen::accept) {
      if (screen == fact::gossip::Screen::unknown_id || screen == fact::gossip::Screen::table_full)
        reject("envelopes_refused", "envelope from drone " + std::to_string(env.sender_id) + " refused: " +
                                        fact::gossip::to_string(screen));
      // Duplicates and replays are counted by the gossip (duplicate_envelopes, replayed); replays
      // are logged too (the first 10, then every 100th) and challenge the sender: a drone restarted
      // with its clock set back answers, and its new numbers are taken from then on.
      if (screen == fact::gossip::Screen::replay) on_replay(now, env);
      return;
    }
    std::string err;
    const void* data = env.payload.data();
    const int size = env.payload_size;
    const std::string from = " from drone " + std::to_string(env.sender_id);
    if (env.kind == fact::gossip_packet_t::ROUND) {
      fact::round_packet_t m;
      fact::gossip::Packet p;
      if (!(err = fact::app::decode_error(data, size, &m)).empty()) return reject("undecodable", "round payload" + from + ": " + err);
      if (!(err = fact::app::packet_from_message(m, &p)).empty()) return reject("rejected_invalid_payload", err + from);
      err = gossip_.on_round(now, env.sender_id, p);
    } else if (env.kind == fact::gossip_packet_t::SUMMARY) {
      fact::gossip_summary_t m;
      fact::gossip::Summary s;
      if (!(err = fact::app::decode_error(data, size, &m)).empty()) return reject("undecodable", "summary payload" + from + ": " + err);
      if (!(err = fact::app::summary_from_message(m, &s)).empty()) return reject("rejected_invalid_payload", err + from);
      if (s.sender != env.sender_id) return reject("rejected_invalid_payload", "summary of drone " + std::to_string(s.sender) + from);
      err = gossip_.on_summary(now, s);
    } else if (env.kind == fact::gossip_packet_t::CHALLENGE || env.kind == fact::gossip_packet_t::RESPONSE) {
      fact::gossip_challenge_t m;
      if (!(err = fact::app::decode_error(data, size, &m)).empty()) return reject("undecodable", "challenge payload" + from + ": " + err);
      // A challenge to this drone is answered; an answer that passed the window needed no renumbering.
      if (env.kind == fact::gossip_packet_t::CHALLENGE && m.peer_id == f_.common.drone_id) answer(env.sender_id, m);
      return;
    } else {
      fact::gossip_request_t m;
      fact::gossip::Request r;
      if (!(err = fact::app::decode_error(data, size, &m)).empty()) return reject("undecodable", "request payload" + from + ": " + err);
      if (!(err = fact::app::request_from_message(m, &r)).empty()) return reject("rejected_invalid_payload", err + from);
      if (r.requester != env.sender_id) return reject("rejected_invalid_payload", "request by drone " + std::to_string(r.requester) + from);
      err = gossip_.on_request(now, r);
    }
    // Refusals are counted by the gossip; duplicates are normal and not logged.
    if (!err.empty() && err != "duplicate") {
      status_.note(err + from);
      log_limited(err + from);
    }
  }

  // An authenticated envelope numbered below its sender's window: the answer to our challenge
  // (RESPONSE, its numbers restart), or a reason to challenge the sender (logged). A CHALLENGE to
  // this drone is answered too, once per nonce (the last 16 of each challenger are remembered, so
  // a replayed challenge cannot take the place of the real one): two drones that each hold
  // the other's old numbers (both restarted with their clocks set back, and a recording of one
  // played to the other) would otherwise refuse each other's challenges for ever (review,
  // session 32). Answering cannot renumber anyone: only the challenger's fresh nonce does.
  void on_replay(int64_t now, const fact::gossip_packet_t& env) {
    const std::string from = "drone " + std::to_string(env.sender_id);
    if (env.kind == fact::gossip_packet_t::CHALLENGE) {
      fact::gossip_challenge_t m;
      if (fact::app::decode_error(env.payload.data(), env.payload_size, &m).empty() && m.peer_id == f_.common.drone_id) {
        fact::gossip::Nonce nonce;
        std::copy(std::begin(m.nonce), std::end(m.nonce), nonce.begin());
        std::deque<fact::gossip::Nonce>& seen = answered_[env.sender_id];
        if (std::find(seen.begin(), seen.end(), nonce) == seen.end()) {
          seen.push_back(nonce);
          if (seen.size() > 16) seen.pop_front();
          answer(env.sender_id, m);
        }
      }
    }
    if (env.kind == fact::gossip_packet_t::RESPONSE) {
      fact::gossip_challenge_t m;
      const std::string err = fact::app::decode_error(env.payload.data(), env.payload_size, &m);
      if (!err.empty()) return reject("undecodable", "challenge answer payload from " + from + ": " + err);
      if (m.peer_id != f_.common.drone_id) return;  // another drone's challenge
      fact::gossip::Nonce nonce;
      std::copy(std::begin(m.nonce), std::end(m.nonce), nonce.begin());
      if (!gossip_.answer_challenge(now, env.sender_id, env.seq, nonce))
        log_limited("answer from " + from + " seq " + std::to_string(env.seq) + " to no outstanding challenge of ours "
                    "(late, or a recording)");
      return;  // the gossip logs the renumbering (take_events)
    }
    const fact::gossip::Nonce nonce = fact::app::random_nonce();
    const bool challenge = gossip_.open_challenge(now, env.sender_id, nonce);
    fact::app::log_counted(log_, "replayed", gossip_.counters().replayed,
                           "envelope from " + from + " seq " + std::to_string(env.seq) +
                               " is older than its replay window: dropped" +
                               (challenge ? "; challenged " + from + " (restarted with its clock set back?)" : ""));
    if (challenge)
      send_envelope(fact::gossip_packet_t::CHALLENGE,
                    fact::app::encode_bytes(fact::app::challenge_to_message(env.sender_id, nonce, now_us())));
  }

  // A peer challenged this drone: the nonce goes back in an envelope of this process's numbers.
  void answer(int challenger, const fact::gossip_challenge_t& m) {
    fact::gossip::Nonce nonce;
    std::copy(std::begin(m.nonce), std::end(m.nonce), nonce.begin());
    send_envelope(fact::gossip_packet_t::RESPONSE,
                  fact::app::encode_bytes(fact::app::challenge_to_message(challenger, nonce, now_us())));
    status_.count("challenges_answered");
    fact::app::log_counted(log_, "challenges_answered", status_.value("challenges_answered"),
                           "drone " + std::to_string(challenger) + " challenged this drone's envelope numbers: answered");
  }

  // A sample the builder refused (it counts it): noted, and logged the first 10 times, then every
  // 100th (refused odometry used to go to the status note only, silently).
  void note_refusal(const std::string& what, int64_t n, const std::string& line) {
    status_.note(line);
    fact::app::log_counted(log_, what, n, line);
  }

  void log_limited(const std::string& line) {
    ++refusals_;
    int64_t p = 1;
    while (p < refusals_) p *= 10;
    if (p == refusals_) log_.event("refused" + std::string(refusals_ > 1 ? " (#" + std::to_string(refusals_) + ")" : "") + ": " + line);
  }

  void on_round_packet(const lcm::ReceiveBuffer* rbuf, const std::string& chan) {
    fact::round_packet_t m;
    if (!fact::app::decode(rbuf, chan, &m, &status_, log_)) return;
    fact::gossip::Packet p;
    std::string err = fact::app::packet_from_message(m, &p);
    if (err.empty()) err = gossip_.add_own_packet(monotonic_us(), p);
    if (err == "duplicate") return;
    if (!err.empty()) reject("own_round_refused", "round packet on " + chan + " refused: " + err);
    else log_.event("own round " + std::to_string(p.round) + " taken from " + chan + " (" +
                    std::to_string(p.data.observations.size()) + " observations)");
  }

  void on_odometry(const lcm::ReceiveBuffer* rbuf, const std::string& chan) {
    fact::odometry_t m;
    if (!fact::app::decode(rbuf, chan, &m, &status_, log_)) return;
    if (m.drone_id != f_.common.drone_id)
      return reject("foreign_drone", "odometry of drone " + std::to_string(m.drone_id) + " on " + chan + " ignored");
    const bool restarted = odometry_seen_ && fact::app::odometry_restarted(odometry_seq_, odometry_utime_, m.seq, m.utime);
    if (restarted) {
      // fact-vio-relay restarts its stream at seq 0 after a VIO clock reset: the builder starts
      // again on the new clock (it refused every earlier-stamped sample, and no round closed again).
      builder_.restart();
      log_.event("odometry seq went back (" + std::to_string(odometry_seq_) + " → " + std::to_string(m.seq) +
                 ", utime " + std::to_string(m.utime) + "): the odometry restarted; round building starts again");
    }
    if (!odometry_seen_ || m.seq > odometry_seq_ || restarted) {  // (a reordered one does not lower it)
      odometry_seq_ = m.seq;
      odometry_utime_ = m.utime;
    }
    odometry_seen_ = true;
    const std::string e = builder_.add_odometry(m.utime, Eigen::Vector3d(m.position[0], m.position[1], m.position[2]), m.yaw);
    if (!e.empty()) note_refusal("rejected_odometry", builder_.counters().rejected_odometry, e);
  }

  void on_detections(const lcm::ReceiveBuffer* rbuf, const std::string& chan) {
    fact::detections_t m;
    if (!fact::app::decode(rbuf, chan, &m, &status_, log_)) return;
    if (m.drone_id != f_.common.drone_id)
      return reject("foreign_drone", "detections of drone " + std::to_string(m.drone_id) + " on " + chan + " ignored");
    for (const auto& d : m.detections) {
      const std::string e = builder_.add_detection(m.utime, d.track_id, Eigen::Vector3d(d.vector[0], d.vector[1], d.vector[2]));
      if (!e.empty())
        note_refusal("refused_detections",
                     builder_.counters().rejected_detections + builder_.counters().late_detections, e);
    }
  }

  Flags f_;
  fact::app::SwarmKey key_;
  lcm::LCM* lcm_;    // the drone's own bus: odometry, detections, swarm rounds, status
  lcm::LCM* swarm_;  // the swarm's bus: the gossip (lcm_ itself without --swarm-url)
  fact::app::Log log_;
  fact::app::Status status_;
  fact::gossip::Gossip gossip_;
  fact::gossip::RoundBuilder builder_;
  int64_t seq_;
  std::map<int, std::deque<fact::gossip::Nonce>> answered_;  // challenger → nonces answered despite old numbers
  const int64_t first_seq_ = seq_;  // our first envelope's number (seq_ is the next one's)
  bool odometry_seen_ = false;
  int64_t odometry_seq_ = 0;        // the newest odometry sample's seq and utime (µs)
  int64_t odometry_utime_ = 0;
  int published_rounds_ = 0;
  std::vector<int> published_drones_;
  int64_t last_status_ = 0;
  int64_t refusals_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  Flags f;
  CLI::App cli{"fact-gossip: exchanges this drone's round packets with the swarm until every drone holds the same "
               "complete data; publishes it as swarm_rounds_t."};
  fact::app::add_common_flags(cli, &f.common, fact::app::DroneIdFlag::required);
  cli.add_option("--key-file", f.key_file,
                 "Swarm key: a file of exactly 32 raw bytes or 64 hex digits (whitespace ignored); required unless "
                 "--insecure")->type_name("FILE");
  cli.add_flag("--insecure", f.insecure, "No authentication: zero macs are sent and nothing is checked");
  cli.add_option("--session", f.session,
                 "This flight's name (1-64 of A-Z a-z 0-9 . _ : -), the same on every drone and new for each flight: "
                 "mixed into the key, so a recording of another flight's gossip fails authentication (needs "
                 "--key-file)")
      ->type_name("NAME");
  cli.add_option("--roster", f.roster, "The swarm's drone ids (comma separated); others are refused. Default: any id "
                                       "0 … --max-drone-id")->delimiter(',')->check(fact::app::decimal_integer());
  cli.add_option("--max-drone-id", f.max_drone_id, "Without a roster, ids above this are refused")->capture_default_str()
      ->check(fact::app::decimal_integer());
  cli.add_option("--min-members", f.min_members, "Publish complete data only with at least this many drones")->capture_default_str()
      ->check(fact::app::decimal_integer());
  cli.add_flag("--rounds-from-channel", f.rounds_from_channel,
               "Take ready-made round packets (round_packet_t, numbered) on --round-channel instead of building them "
               "from detections and odometry (tests, the simulator)");
  cli.add_option("--round-period", f.round_period, "s; > 0: back-to-back rounds of this length instead of detecting spins")
      ->capture_default_str();
  cli.add_option("--spin-angle", f.spin_angle, "rad of net yaw turn that closes a round (spin mode)")->capture_default_str();
  cli.add_option("--max-speed", f.max_speed,
                 "m/s; spin mode: moving faster (over 0.2 s of odometry) restarts the open round, so a round is a turn "
                 "in place (0 = off)")
      ->capture_default_str();
  cli.add_option("--detection-latency", f.detection_latency, "s (odometry time) a closed round waits for late detections")
      ->capture_default_str();
  cli.add_option("--max-odometry-gap", f.max_odometry_gap, "s; odometry is not interpolated across larger gaps")->capture_default_str();
  cli.add_option("--summary-period", f.summary_period, "s between heartbeat summaries")->capture_default_str();
  cli.add_option("--summary-min-interval", f.summary_min_interval, "s; a summary follows a change at most this often")
      ->capture_default_str();
  cli.add_option("--silence-timeout", f.silence_timeout, "s; a drone unheard this long is silent (stops blocking)")
      ->capture_default_str();
  cli.add_option("--request-interval", f.request_interval, "s between requests for one drone's missing rounds")
      ->capture_default_str();
  cli.add_option("--answer-slot", f.answer_slot, "s of answer delay per rank for holders other than the origin")
      ->capture_default_str();
  cli.add_option("--settle", f.settle, "s after start before completing or numbering own rounds (hear the swarm first)")
      ->capture_default_str();
  cli.add_option("--max-rounds", f.max_rounds, "Rounds kept per drone (0 … max-rounds − 1; later ones refused)")
      ->capture_default_str()->check(fact::app::decimal_integer());
  cli.add_option("--max-origins", f.max_origins, "Drone ids tracked")->capture_default_str()
      ->check(fact::app::decimal_integer());
  cli.add_option("--future-window", f.future_window, "A round >= held + this is refused as far in the future")
      ->capture_default_str()->check(fact::app::decimal_integer());
  cli.add_option("--max-observations", f.max_observations, "Observations per round packet")->capture_default_str()
      ->check(fact::app::decimal_integer());
  cli.add_option("--gossip-channel", f.gossip_channel, "Swarm channel (gossip_packet_t)")->capture_default_str();
  cli.add_option("--swarm-url", f.swarm_url,
                 "LCM URL of the swarm's bus for --gossip-channel; everything else stays on --lcm-url, the drone's own "
                 "bus (default: the gossip on --lcm-url too)")->type_name("URL");
  cli.add_option("--detections-channel", f.detections_channel, "Default FACT_DETECTIONS_<id>");
  cli.add_option("--odometry-channel", f.odometry_channel, "Default FACT_ODOMETRY_<id>");
  cli.add_option("--round-channel", f.round_channel, "Default FACT_ROUND_PACKET_<id> (with --rounds-from-channel)");
  cli.add_option("--output-channel", f.output_channel, "Default FACT_SWARM_ROUNDS_<id>");
  cli.footer(
      "A round is one spin: it closes when the odometry yaw (unwrapped) has turned --spin-angle since the previous "
      "round; one observation per tracked drone (the detection nearest the image centre, with the odometry "
      "interpolated at it). Envelopes are authenticated with libsodium crypto_auth (HMAC-SHA512-256) over "
      "kind|sender|seq|payload. Make a key: head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \\n' > swarm.key\n"
      "Exit codes: 0 stopped by SIGINT/SIGTERM; 2 bad flags, key or options; 1 LCM unusable.");
  if (const int code = fact::app::parse_command_line(cli, argc, argv); code >= 0) return code;
  fact::app::Log boot("fact-gossip", f.common.drone_id);
  try {
    fact::app::check_common_flags(f.common, fact::app::DroneIdFlag::required);
  } catch (const fact::app::FlagError& e) {
    boot.event(std::string("error: ") + e.what());
    return 2;
  }
  if (f.detections_channel.empty()) f.detections_channel = channel("FACT_DETECTIONS", f.common.drone_id);
  if (f.odometry_channel.empty()) f.odometry_channel = channel("FACT_ODOMETRY", f.common.drone_id);
  if (f.round_channel.empty()) f.round_channel = channel("FACT_ROUND_PACKET", f.common.drone_id);
  if (f.output_channel.empty()) f.output_channel = channel("FACT_SWARM_ROUNDS", f.common.drone_id);

  fact::app::SwarmKey key;
  if (std::string e = fact::app::init_crypto(); !e.empty()) {
    boot.event(e);
    return 2;
  }
  if (!f.key_file.empty() && f.insecure) {
    boot.event("--key-file and --insecure exclude each other");
    return 2;
  }
  if (f.key_file.empty() && !f.insecure) {
    boot.event("a swarm key is required: --key-file FILE (or --insecure to run without authentication)");
    return 2;
  }
  if (!f.key_file.empty()) {
    if (std::string e = fact::app::load_key(f.key_file, &key); !e.empty()) {
      boot.event("--key-file " + e);
      return 2;
    }
  }
  if (cli.count("--session") > 0) {
    if (std::string e = fact::app::apply_session(f.session, &key); !e.empty()) {
      boot.event("error: --session: " + e);
      return 2;
    }
  }
  try {
    check_times(f);
  } catch (const fact::app::FlagError& e) {
    boot.event(std::string("error: ") + e.what());
    return 2;
  }

  fact::gossip::Options go;
  go.self_id = f.common.drone_id;
  go.roster = f.roster;
  go.max_drone_id = f.max_drone_id;
  go.summary_period_us = us(f.summary_period);
  go.summary_min_interval_us = us(f.summary_min_interval);
  go.silence_timeout_us = us(f.silence_timeout);
  go.request_interval_us = us(f.request_interval);
  go.answer_slot_us = us(f.answer_slot);
  go.settle_us = us(f.settle);
  go.min_members = f.min_members;
  go.max_origins = f.max_origins;
  go.max_rounds = f.max_rounds;
  go.future_window = f.future_window;
  go.max_observations = f.max_observations;
  if (std::string e = fact::gossip::check_options(go); !e.empty()) {
    boot.event("bad option: " + e);
    return 2;
  }
  fact::gossip::BuilderOptions bo;
  bo.spin_angle = f.spin_angle;
  bo.max_speed = f.max_speed;
  bo.round_period_us = us(f.round_period);
  bo.latency_us = us(f.detection_latency);
  bo.max_odometry_gap_us = us(f.max_odometry_gap);
  bo.max_tracks = f.max_observations;
  if (std::string e = fact::gossip::check_builder_options(bo); !e.empty()) {
    boot.event("bad option: " + e);
    return 2;
  }

  lcm::LCM lcm(f.common.lcm_url);
  if (!lcm.good()) {
    boot.event("LCM is not usable with URL '" + f.common.lcm_url + "' (bad URL, or no multicast route for udpm)");
    return 1;
  }
  std::unique_ptr<lcm::LCM> swarm_bus;
  if (!f.swarm_url.empty() && f.swarm_url != f.common.lcm_url) {
    swarm_bus = std::make_unique<lcm::LCM>(f.swarm_url);
    if (!swarm_bus->good()) {
      boot.event("LCM is not usable with --swarm-url '" + f.swarm_url + "' (bad URL, or no multicast route for udpm)");
      return 1;
    }
  }
  lcm::LCM* swarm = swarm_bus ? swarm_bus.get() : &lcm;
  fact::app::install_stop_handler();
  if (!fact::app::start_clock(lcm, f.common, boot)) return 1;
  // The gossip's clock is monotonic_us(); envelope numbers start at the wall (or simulated) time
  // in µs, so a restarted sender's numbers exceed its old ones.
  GossipApp app(f, go, bo, key, &lcm, swarm, monotonic_us(), now_us());
  app.subscribe();
  app.log().event(std::string("started: ") + (key.insecure ? "INSECURE (no authentication)" : "authenticated") +
                  (f.session.empty() ? "" : " in session " + f.session) +
                  ", roster " + (f.roster.empty() ? "open" : ids_text(f.roster)) + ", rounds from " +
                  (f.rounds_from_channel ? f.round_channel
                                         : f.odometry_channel + " + " + f.detections_channel +
                                               (f.round_period > 0 ? " (fixed periods)" : " (spins)")) +
                  ", gossip on " + f.gossip_channel + (swarm_bus ? " at " + f.swarm_url : std::string()) +
                  ", output " + f.output_channel);
  // Waits until the gossip's next deadline (at most 100 ms) for a message on either bus.
  const int rc = fact::app::run_deadline_loop(
      lcm, 100000,
      [&](int64_t now) {
        app.step(now);
        return app.next_deadline(now);
      },
      swarm_bus ? std::vector<lcm::LCM*>{swarm_bus.get()} : std::vector<lcm::LCM*>{}, &monotonic_us);
  if (rc != 0) {
    app.log().event("LCM failed: stopping");
    return 1;
  }
  app.log().event("stopping (signal)");
  return 0;
}
