// Gossip of round packets: the swarm's data exchange as a pure state machine over plain data
// (no LCM, no I/O, no clock: every call takes `now` in microseconds). fact-gossip wraps it in LCM.
//
// Two parts:
//
// 1. RoundBuilder: one drone's detections + odometry → its round packets (one per spin).
//    A round is one spin. Spin mode (the default): the round closes at the first odometry sample
//    t where the unwrapped yaw has turned by `spin_angle` (2π) since some time t0 after the
//    previous round's end; t0 is taken as late as possible (the shortest interval ending at t
//    with a net turn of 2π), so the round is the spin itself, not the flight before it. Period
//    mode (round_period_us > 0): rounds are back-to-back intervals of that length, whatever the
//    yaw does. The round's position/yaw is the odometry at t0. It keeps one observation per
//    tracked drone (track_id): the detection in [t0, t] closest to the image centre (smallest
//    horizontal |bearing| = |atan2(v_y, v_x)|, ties: the earlier), with the odometry linearly
//    interpolated at that detection's time as odom_position / odom_yaw. Observations are sorted
//    by track_id; yaws are wrapped to (−π, π]. A closed round is released once odometry time has
//    passed its end by `latency_us`, so detections that arrive late (detector latency) still join.
//
// 2. Gossip: what one drone holds of everyone's round packets and what it must send.
//    - Holds the packets per origin (index = round number), the number of consecutive rounds
//      held from 0 and a 64-bit digest of them (FNV-1a 64 of each packet's canonical bytes,
//      chained round by round: see packet_digest / chain_digest).
//    - Sends: its own new rounds at once; a SUMMARY (what it holds: per origin, rounds held and
//      digest) every summary_period (the heartbeat), and also at most summary_min_interval after
//      its holdings change; a REQUEST for the rounds a live peer's summary shows it lacks (at most
//      future_window past what it holds and max_request_rounds per request, repeated at most every
//      request_interval per origin until they arrive); the ANSWER to a request, as ROUND packets:
//      the origin answers at once, any other holder after answer_slot × (1 + its rank among the
//      live members, counted from the requester's id upwards), and cancels when it sees someone
//      else's copy first (multicast suppression); a round it sent less than request_interval / 2
//      ago is not sent again.
//    - Rejects (counts, never stores): NaN/inf or negative fields, more than max_observations
//      observations, an id outside the roster (or outside [0, max_drone_id] without one), a round
//      number ≥ max_rounds (memory cap), a round number ≥ held + future_window (far in the future),
//      an envelope sequence number already seen (duplicate) or older than the replay window
//      (replay).
//    - Renumbered senders: a sender's numbers start at its start time (µs), so a sender restarted
//      with its clock set back numbers its envelopes below its old ones, and they screen as
//      replays. The receiver then challenges it (open_challenge: a random nonce, at most one
//      outstanding per sender, renewed after challenge_timeout); the sender answers with the nonce
//      in an envelope of its new numbers, which a recording cannot forge, and answer_challenge
//      restarts the sender's window at that number. Numbers above the new window up to the
//      highest seen stay refused until the new numbers pass them (so replaying the old run,
//      including numbers sent before this receiver heard the sender, cannot lock the sender out
//      again; a real jump over the window there costs one more challenge). A CHALLENGE to
//      this drone is answered even when its envelope screens as a replay (rate-limited by the
//      app), so two drones that each hold the other's old numbers take each other back.
//    - Bounded memory: at most max_origins drone ids and max_rounds rounds per origin (rounds
//      0 … max_rounds − 1: the session's first rounds are kept, later ones refused and counted,
//      because the estimator works from the first rounds and a restarted peer must find them
//      all). A new id when the table is full replaces the longest-silent id that holds no rounds;
//      if every id holds rounds it is refused and counted. Every per-id table is capped likewise.
//    - Membership from last-heard times: a drone is live while its last authenticated message is
//      at most silence_timeout old (self always; roster members not yet heard count as live for
//      the first silence_timeout after start, so the swarm does not complete without them). A
//      silent drone is reported and stops blocking completion.
//    - Complete rounds K = the largest K such that this drone holds rounds 0 … K−1 of every live
//      member. The complete data is every drone holding ≥ K rounds (the live members and any
//      silent drone whose rounds are all there), rounds 0 … K−1, ordered by drone id then round.
//      It is reported only once `settle_us` has passed since start (a restarted gossip first
//      hears the swarm's summaries) and when it has at least min_members drones.
//    - Own rounds: from RoundBuilder (numbered here: the next number after every own round held
//      here or reported held by any peer, so a restarted gossip continues its numbering) or given with
//      their number (rounds injected by a test or the simulator). Own rounds closed before
//      `settle_us` wait for it. A restarted gossip recovers everything, its own rounds included,
//      from its peers' summaries and answers to its requests.
#pragma once

#include "fact/rounds.h"

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace fact::gossip {

// ---------------------------------------------------------------------------------------------
// Round packets and digests

// One origin's round, immutable once made (the content of fact::round_packet_t).
struct Packet {
  int origin = -1;      // drone id of the drone that observed
  int round = -1;       // round number, from 0
  int64_t utime = 0;    // µs, when the origin closed the round
  DroneRound data;      // position/yaw at the round's start and the observations
};

// FNV-1a 64 over the packet's canonical bytes: origin, round (int32), utime (int64), count
// (int32), then position, yaw and each observation's odom_position, odom_yaw, vector as IEEE-754
// bits (uint64), every field little-endian. Equal packets (bit for bit) ⇔ equal digests (up to
// collisions). Not a MAC: authentication is the envelope's job.
uint64_t packet_digest(const Packet& p);
// Digest of rounds 0 … k from the digest of rounds 0 … k−1 (`prefix`; 0 for k = 0) and round
// k's packet digest: FNV-1a 64 over the 16 bytes prefix | packet (little-endian).
uint64_t chain_digest(uint64_t prefix, uint64_t packet);

// "" if the packet's numbers are usable, else the first bad field and its value.
std::string check_packet(const Packet& p);

// ---------------------------------------------------------------------------------------------
// Gossip messages (plain data; fact-gossip maps them to gossip_summary_t / gossip_request_t)

struct SummaryEntry {
  int origin = -1;
  int rounds_held = 0;   // rounds 0 … rounds_held − 1 of origin are held
  uint64_t digest = 0;   // chain digest of those rounds (0 when rounds_held = 0)
};
struct Summary {
  int sender = -1;
  std::vector<SummaryEntry> entries;  // ascending origin
};
struct Request {
  int requester = -1;
  int origin = -1;
  std::vector<int> rounds;  // ascending
};

struct Outgoing {
  enum class Kind { round, summary, request };
  Kind kind = Kind::summary;
  Packet packet;    // kind round
  Summary summary;  // kind summary
  Request request;  // kind request
  bool answer = false;  // a round sent in answer to a request (not a first broadcast)
};

// ---------------------------------------------------------------------------------------------
// The gossip state machine

struct Options {
  int self_id = 0;
  std::vector<int> roster;        // the swarm's ids; empty = any id in [0, max_drone_id]
  int max_drone_id = 9999;        // without a roster, ids above this are unknown
  int64_t summary_period_us = 1000000;      // heartbeat summary period (µs)
  int64_t summary_min_interval_us = 100000; // event summary after a change, at most this often (µs)
  int64_t silence_timeout_us = 5000000;     // a drone unheard this long is silent (µs)
  int64_t request_interval_us = 200000;     // re-request one origin's rounds at most this often (µs)
  int64_t answer_slot_us = 15000;           // answer delay per rank for non-origin holders (µs)
  int64_t settle_us = 1500000;              // no completion, no own-round numbering before this (µs)
  int min_members = 2;            // complete data is reported with at least this many drones
  int max_origins = 32;           // drone ids tracked (memory cap)
  int max_rounds = 128;           // rounds kept per origin: 0 … max_rounds − 1 (memory cap)
  int future_window = 16;         // a round ≥ held + future_window is refused as far in the future
  int max_observations = 64;      // observations per packet
  int max_request_rounds = 16;    // rounds per request
  int replay_window = 256;        // envelope sequence numbers remembered per sender
  int64_t challenge_timeout_us = 2000000;   // a challenge's answer is taken this long (µs)
};

// "" if usable, else which option and why.
std::string check_options(const Options& o);

// Everything counted, never a crash. Names as reported in app_status_t: see Counters::list.
struct Counters {
  int64_t rounds_received = 0;      // round packets from peers (first copies and duplicates)
  int64_t rounds_stored = 0;        // new round packets stored (peers' and own)
  int64_t duplicate_rounds = 0;     // a round already held, received again
  int64_t duplicate_envelopes = 0;  // an envelope sequence number already seen (network duplicate)
  int64_t replayed = 0;             // an envelope sequence number older than the replay window
  int64_t rejected_invalid = 0;     // NaN/inf, negative round, too many observations, bad summary/request
  int64_t rejected_unknown_id = 0;  // a sender, origin or requester outside the roster / id range
  int64_t rejected_future = 0;      // round ≥ held + future_window
  int64_t rejected_round_cap = 0;   // round ≥ max_rounds
  int64_t rejected_origin_cap = 0;  // a new id while max_origins ids hold rounds
  int64_t own_round_conflicts = 0;  // an own round given again with different content (first kept)
  int64_t digest_mismatches = 0;    // a peer's digest or copy differs from ours for the same rounds
  int64_t summaries_received = 0;
  int64_t requests_received = 0;
  int64_t own_rounds = 0;           // own rounds added
  int64_t rounds_sent = 0;          // own rounds broadcast
  int64_t answers_sent = 0;         // rounds sent in answer to requests
  int64_t answers_suppressed = 0;   // scheduled answers cancelled: another holder answered first
  int64_t summaries_sent = 0;
  int64_t requests_sent = 0;
  int64_t members_silenced = 0;     // live → silent transitions
  int64_t challenges_sent = 0;      // challenges to senders whose numbers went back
  int64_t senders_renumbered = 0;   // such a sender answered: its window restarts at its new numbers
  int64_t challenge_answers_refused = 0;  // an answer to no outstanding challenge, or a wrong or late nonce
  // (name, value) in a fixed order, e.g. ("duplicate_rounds", 3).
  std::vector<std::pair<std::string, int64_t>> list() const;
};

struct Completion {
  bool ready = false;       // K ≥ 1, settled, at least min_members drones
  int rounds = 0;           // K
  std::vector<int> drones;  // ascending: the drones whose rounds 0 … K−1 make the complete data
  std::vector<int> live;    // ascending, self included
  std::vector<int> silent;  // ascending: heard (or on the roster) but silent now
};

struct MemberInfo {
  int id = -1;
  bool live = false;
  bool heard = false;        // an authenticated message from it was received
  int64_t last_heard = 0;    // µs (0 if never)
  int rounds_held = 0;       // consecutive rounds of this origin held here
};

// Result of screening an envelope's sender and sequence number (after authentication).
// self: our own message looped back by multicast (ignore, not an error); table_full: a new id
// while max_origins ids hold rounds (counted as rejected_origin_cap).
enum class Screen { accept, self, unknown_id, table_full, duplicate, replay };
const char* to_string(Screen s);

// A challenge's random nonce (the app draws it from a cryptographic source).
using Nonce = std::array<uint8_t, 16>;

class Gossip {
 public:
  // `now`: start time (µs). Options must pass check_options (else every input is refused).
  Gossip(const Options& options, int64_t now);

  const Options& options() const { return opt_; }

  // An authenticated envelope from `sender` with sequence number `seq`: screens the id and the
  // sequence (duplicate within the replay window, or older than it). Only accepted envelopes
  // should be passed on. Marks the sender heard.
  Screen screen_envelope(int64_t now, int sender, int64_t seq);
  // After Screen::replay from `sender`: true when a challenge carrying `nonce` should go to it now
  // (it was heard before, and no challenge to it is outstanding: none, or the last one older than
  // challenge_timeout). The nonce is then the outstanding one.
  bool open_challenge(int64_t now, int sender, const Nonce& nonce);
  // An authenticated answer from `sender` in its envelope numbered `seq`, carrying `nonce`: true
  // when it is the outstanding challenge's nonce, within challenge_timeout; the sender's window
  // then restarts at seq (seq counts as seen, the sender as heard). False (counted) otherwise.
  bool answer_challenge(int64_t now, int sender, int64_t seq, const Nonce& nonce);

  // Messages from peers (their envelope accepted). Each returns "" or the reason it was refused.
  std::string on_round(int64_t now, int sender, const Packet& p);
  std::string on_summary(int64_t now, const Summary& s);
  std::string on_request(int64_t now, const Request& r);

  // Own rounds. add_own_round numbers the round itself (see the header comment); add_own_packet
  // takes the number given (origin must be self). Both broadcast it (at once, or after settle).
  std::string add_own_round(int64_t now, int64_t utime, const DroneRound& data);
  std::string add_own_packet(int64_t now, const Packet& p);

  // What to send now (own rounds, due answers, requests, the summary), and membership updates.
  std::vector<Outgoing> tick(int64_t now);
  // The next time tick has something to do (≥ now), for the app's wait.
  int64_t next_deadline(int64_t now) const;

  Completion completion(int64_t now) const;
  // The stored packet, or nullptr.
  const Packet* packet(int origin, int round) const;
  // The complete data's packets: drones ascending, rounds 0 … K−1 (empty unless ready).
  std::vector<const Packet*> complete_packets(const Completion& c) const;

  Summary summary() const;                   // what this drone holds now
  int rounds_held(int origin) const;         // consecutive rounds held from 0
  uint64_t digest(int origin) const;         // chain digest of them (0 when none)
  std::vector<MemberInfo> members(int64_t now) const;  // every id tracked, ascending
  size_t stored_packets() const;             // packets held in memory, all origins
  size_t tracked_ids() const;
  const Counters& counters() const { return counters_; }
  // Notable events since the last call, one line each (a new member, a silent one, a conflict).
  std::vector<std::string> take_events();

 private:
  struct Held {
    Packet packet;
    uint64_t digest = 0;
    int64_t last_sent = 0;
    bool ever_sent = false;
  };
  struct Node {
    std::vector<std::optional<Held>> rounds;  // index = round number (size ≤ max_rounds)
    int consecutive = 0;
    std::vector<uint64_t> chain;              // chain[k] = digest of rounds 0 … k, k < consecutive
    size_t stored = 0;
    bool heard = false;
    int64_t last_heard = 0;
    bool reported_silent = false;
    bool seq_init = false;
    int64_t seq_high = 0;
    std::vector<uint64_t> seq_seen;           // bitmap of seq_high − replay_window + 1 … seq_high
    bool stale = false;                       // renumbered: numbers in (seq_high + replay_window,
    int64_t stale_high = 0;                   //   stale_high] may be the previous run's: refused
    bool challenged = false;                  // a challenge is outstanding:
    Nonce challenge{};                        //   its nonce
    int64_t challenged_at = 0;                //   and when it was sent (µs)
    std::map<int, SummaryEntry> summary;      // its last summary, by origin
    int64_t last_request = 0;                 // our last request for this origin's rounds
    bool requested = false;
  };

  bool known_id(int id) const;
  bool on_roster(int id) const;
  bool live(const Node& n, int id, int64_t now) const;
  Node* node(int id, int64_t now);            // creates (or refuses: nullptr) under the cap
  void hear(int id, int64_t now);
  std::string store(Node& n, const Packet& p, int64_t now);
  void store_and_send_own(const Packet& p, int64_t now);
  std::vector<int> live_ids(int64_t now) const;
  std::vector<int> wanted(int origin, int64_t now) const;
  int next_own_round(int64_t now) const;
  void event(std::string line) { events_.push_back(std::move(line)); if (events_.size() > 256) events_.pop_front(); }

  Options opt_;
  bool options_ok_ = true;
  int64_t start_;
  std::map<int, Node> nodes_;
  std::map<std::pair<int, int>, int64_t> pending_answers_;  // (origin, round) → due time
  std::vector<Outgoing> outbox_;                            // own rounds to broadcast
  std::vector<std::pair<int64_t, DroneRound>> own_queue_;   // builder rounds waiting for settle
  bool changed_ = true;   // holdings changed since the last summary
  int64_t last_summary_ = 0;
  bool ever_summarised_ = false;
  Counters counters_;
  std::deque<std::string> events_;
  std::map<std::pair<int, int>, uint64_t> mismatch_reported_;  // (peer, origin) → their digest
};

// ---------------------------------------------------------------------------------------------
// Round building from detections and odometry

struct BuilderOptions {
  double spin_angle = 6.283185307179586;  // rad of net yaw turn that makes a round (spin mode)
  // Spin mode: a round is a turn in place. Faster than this (m/s, over the last max_speed_window
  // of odometry), the drone is moving and the open round starts again when it stops, so that a
  // round's detections all come from one spot (the mutual-pair geometry needs it). 0 = off.
  double max_speed = 0.25;
  int64_t max_speed_window_us = 200000;
  int64_t round_period_us = 0;            // > 0: period mode, rounds of this length (µs)
  int64_t latency_us = 300000;            // wait this long (odometry time) past a round's end (µs)
  int64_t max_odometry_gap_us = 500000;   // no interpolation across a larger gap between samples (µs)
  int max_tracks = 64;                    // observations per round (the lowest track ids are kept)
  size_t max_odometry = 20000;            // samples kept (oldest dropped)
  size_t max_detections = 20000;          // detections kept (oldest dropped)
};

std::string check_builder_options(const BuilderOptions& o);

struct BuilderCounters {
  int64_t odometry = 0, detections = 0;
  int64_t rejected_odometry = 0;     // NaN, or time not after the previous sample
  int64_t rejected_detections = 0;   // NaN, zero vector
  int64_t late_detections = 0;       // older than the open round's start
  int64_t unmatched_detections = 0;  // no odometry around its time (gap, or before the first sample)
  int64_t moves = 0;                 // times the open round restarted because the drone moved
  int64_t dropped_history = 0;       // samples or detections dropped at the caps
  int64_t dropped_tracks = 0;        // tracks beyond max_tracks
  int64_t odometry_gaps = 0;         // period mode: gaps over max_odometry_gap (empty periods skipped)
  int64_t restarts = 0;              // restart() calls (the odometry's clock was reset)
  int64_t rounds = 0;
  std::vector<std::pair<std::string, int64_t>> list() const;
};

struct BuiltRound {
  int64_t start_utime = 0;  // t0 (µs)
  int64_t end_utime = 0;    // t (µs): the packet's utime
  DroneRound data;
};

class RoundBuilder {
 public:
  explicit RoundBuilder(const BuilderOptions& options = {});
  // Each returns "" or the reason the sample was refused (counted).
  std::string add_odometry(int64_t utime, const Eigen::Vector3d& position, double yaw_unwrapped);
  std::string add_detection(int64_t utime, int track_id, const Eigen::Vector3d& vector);
  // The odometry restarted on a new clock (fact-vio-relay's seq went back after a VIO clock
  // reset): the rounds waiting for late detections are finalized as they are (no late detection
  // can reach them any more), the history and the open round are dropped, the counters kept.
  // Rounds already taken stay numbered; the next one follows them.
  void restart();
  // Rounds closed and past their latency, oldest first.
  std::vector<BuiltRound> take_rounds();
  const BuilderCounters& counters() const { return counters_; }
  // Odometry at time t (linear interpolation), false when t is outside the samples or in a gap.
  bool odometry_at(int64_t t, Eigen::Vector3d* position, double* yaw) const;

 private:
  struct Odo {
    int64_t t;
    Eigen::Vector3d p;
    double yaw;
  };
  struct Det {
    int64_t t;
    int track;
    Eigen::Vector3d v;
  };
  struct Closed {
    int64_t t0, t1;
  };
  void close_if_spun();
  bool moving() const;
  void finalize(const Closed& c);
  void trim();

  BuilderOptions opt_;
  std::deque<Odo> odo_;
  std::deque<Det> det_;
  bool started_ = false;
  bool moving_ = false;         // the newest odometry was moving (see max_speed)
  int64_t open_start_ = 0;      // the open round may start here at the earliest
  double min_yaw_ = 0, max_yaw_ = 0;  // over samples since open_start_ (spin mode)
  std::deque<Closed> closing_;  // closed, waiting for latency
  std::vector<BuiltRound> ready_;
  BuilderCounters counters_;
};

}  // namespace fact::gossip
