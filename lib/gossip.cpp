// The gossip state machine and the round builder (see fact/gossip.h). No I/O, no clock.
#include "fact/gossip.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>
#include <sstream>

namespace fact::gossip {
namespace {

constexpr uint64_t kFnvOffset = 0xcbf29ce484222325ull;
constexpr uint64_t kFnvPrime = 0x100000001b3ull;

struct Fnv {
  uint64_t h = kFnvOffset;
  void byte(uint8_t b) {
    h ^= b;
    h *= kFnvPrime;
  }
  void u64(uint64_t v) {
    for (int i = 0; i < 8; ++i) byte(static_cast<uint8_t>(v >> (8 * i)));
  }
  void i32(int32_t v) {
    const uint32_t u = static_cast<uint32_t>(v);
    for (int i = 0; i < 4; ++i) byte(static_cast<uint8_t>(u >> (8 * i)));
  }
  void i64(int64_t v) { u64(static_cast<uint64_t>(v)); }
  void f64(double v) {
    uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    u64(bits);
  }
  void vec(const Eigen::Vector3d& v) {
    for (int c = 0; c < 3; ++c) f64(v[c]);
  }
};

std::string number(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

std::string seconds(int64_t us) {
  std::ostringstream s;
  s.precision(3);
  s << std::fixed << static_cast<double>(us) / 1e6 << " s";
  return s.str();
}

double wrap_angle(double a) {
  double w = std::remainder(a, 2 * M_PI);
  if (w <= -M_PI) w += 2 * M_PI;
  return w;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Digests and checks

uint64_t packet_digest(const Packet& p) {
  Fnv f;
  f.i32(p.origin);
  f.i32(p.round);
  f.i64(p.utime);
  f.i32(static_cast<int32_t>(p.data.observations.size()));
  f.vec(p.data.position);
  f.f64(p.data.yaw);
  for (const Observation& o : p.data.observations) {
    f.vec(o.odom_position);
    f.f64(o.odom_yaw);
    f.vec(o.vector);
  }
  return f.h;
}

uint64_t chain_digest(uint64_t prefix, uint64_t packet) {
  Fnv f;
  f.u64(prefix);
  f.u64(packet);
  return f.h;
}

std::string check_packet(const Packet& p) {
  const std::string at = "drone " + std::to_string(p.origin) + " round " + std::to_string(p.round) + ": ";
  if (p.origin < 0) return at + "origin is negative";
  if (p.round < 0) return at + "round is negative";
  const auto vec = [&](const Eigen::Vector3d& v, const std::string& field) -> std::string {
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(v[c])) return at + field + "[" + std::to_string(c) + "] is " + number(v[c]);
    return "";
  };
  std::string e = vec(p.data.position, "position");
  if (!e.empty()) return e;
  if (!std::isfinite(p.data.yaw)) return at + "yaw is " + number(p.data.yaw);
  for (size_t i = 0; i < p.data.observations.size(); ++i) {
    const Observation& o = p.data.observations[i];
    const std::string obs = "observations[" + std::to_string(i) + "].";
    if (!(e = vec(o.odom_position, obs + "odom_position")).empty()) return e;
    if (!std::isfinite(o.odom_yaw)) return at + obs + "odom_yaw is " + number(o.odom_yaw);
    if (!(e = vec(o.vector, obs + "vector")).empty()) return e;
    if (o.vector.norm() < 1e-6) return at + obs + "vector has length " + number(o.vector.norm()) + " m";
  }
  return "";
}

std::string check_options(const Options& o) {
  if (o.self_id < 0) return "self_id " + std::to_string(o.self_id) + " is negative";
  if (o.max_drone_id < 0) return "max_drone_id is negative";
  if (o.max_origins < 1) return "max_origins must be ≥ 1";
  if (o.max_rounds < 1) return "max_rounds must be ≥ 1";
  if (o.future_window < 1) return "future_window must be ≥ 1";
  if (o.max_observations < 0) return "max_observations is negative";
  if (o.max_request_rounds < 1) return "max_request_rounds must be ≥ 1";
  if (o.replay_window < 1 || o.replay_window > 65536) return "replay_window must be in 1 … 65536";
  if (o.challenge_timeout_us <= 0) return "challenge_timeout must be > 0";
  if (o.summary_period_us <= 0) return "summary_period must be > 0";
  if (o.summary_min_interval_us < 0) return "summary_min_interval is negative";
  if (o.silence_timeout_us <= 0) return "silence_timeout must be > 0";
  if (o.request_interval_us <= 0) return "request_interval must be > 0";
  if (o.answer_slot_us < 0) return "answer_slot is negative";
  if (o.settle_us < 0) return "settle is negative";
  if (o.min_members < 1) return "min_members must be ≥ 1";
  std::set<int> ids;
  for (int id : o.roster) {
    if (id < 0) return "roster id " + std::to_string(id) + " is negative";
    if (!ids.insert(id).second) return "roster lists id " + std::to_string(id) + " twice";
  }
  if (!o.roster.empty() && !ids.count(o.self_id))
    return "roster does not list this drone's id " + std::to_string(o.self_id);
  if (o.roster.empty() && o.self_id > o.max_drone_id)
    return "self_id " + std::to_string(o.self_id) + " is above max_drone_id " + std::to_string(o.max_drone_id);
  if (static_cast<int>(ids.size()) > o.max_origins)
    return "roster has " + std::to_string(ids.size()) + " ids, more than max_origins " + std::to_string(o.max_origins);
  return "";
}

const char* to_string(Screen s) {
  switch (s) {
    case Screen::accept: return "accept";
    case Screen::self: return "self";
    case Screen::unknown_id: return "unknown_id";
    case Screen::table_full: return "table_full";
    case Screen::duplicate: return "duplicate";
    case Screen::replay: return "replay";
  }
  return "?";
}

std::vector<std::pair<std::string, int64_t>> Counters::list() const {
  return {{"rounds_received", rounds_received},
          {"rounds_stored", rounds_stored},
          {"duplicate_rounds", duplicate_rounds},
          {"duplicate_envelopes", duplicate_envelopes},
          {"replayed", replayed},
          {"rejected_invalid", rejected_invalid},
          {"rejected_unknown_id", rejected_unknown_id},
          {"rejected_future", rejected_future},
          {"rejected_round_cap", rejected_round_cap},
          {"rejected_origin_cap", rejected_origin_cap},
          {"own_round_conflicts", own_round_conflicts},
          {"digest_mismatches", digest_mismatches},
          {"summaries_received", summaries_received},
          {"requests_received", requests_received},
          {"own_rounds", own_rounds},
          {"rounds_sent", rounds_sent},
          {"answers_sent", answers_sent},
          {"answers_suppressed", answers_suppressed},
          {"summaries_sent", summaries_sent},
          {"requests_sent", requests_sent},
          {"members_silenced", members_silenced},
          {"challenges_sent", challenges_sent},
          {"senders_renumbered", senders_renumbered},
          {"challenge_answers_refused", challenge_answers_refused}};
}

// ---------------------------------------------------------------------------------------------
// Gossip

Gossip::Gossip(const Options& options, int64_t now) : opt_(options), start_(now) {
  const std::string e = check_options(opt_);
  options_ok_ = e.empty();
  if (!options_ok_) {
    event("unusable options (" + e + "): every input is refused");
    return;
  }
  nodes_[opt_.self_id];
  for (int id : opt_.roster) nodes_[id];
}

bool Gossip::on_roster(int id) const {
  return std::find(opt_.roster.begin(), opt_.roster.end(), id) != opt_.roster.end();
}

bool Gossip::known_id(int id) const {
  if (!options_ok_ || id < 0) return false;
  if (!opt_.roster.empty()) return on_roster(id);
  return id <= opt_.max_drone_id;
}

bool Gossip::live(const Node& n, int id, int64_t now) const {
  if (id == opt_.self_id) return true;
  if (n.heard) return now - n.last_heard <= opt_.silence_timeout_us;
  return on_roster(id) && now - start_ <= opt_.silence_timeout_us;
}

Gossip::Node* Gossip::node(int id, int64_t now) {
  auto it = nodes_.find(id);
  if (it != nodes_.end()) return &it->second;
  if (!known_id(id)) return nullptr;
  if (static_cast<int>(nodes_.size()) >= opt_.max_origins) {
    // Replace the longest-silent id that holds no rounds (never self, never a live one).
    const auto heard_at = [](const Node& n) { return n.heard ? n.last_heard : std::numeric_limits<int64_t>::min(); };
    auto victim = nodes_.end();
    for (auto j = nodes_.begin(); j != nodes_.end(); ++j) {
      if (j->first == opt_.self_id || j->second.stored > 0 || live(j->second, j->first, now)) continue;
      if (victim == nodes_.end() || heard_at(j->second) < heard_at(victim->second)) victim = j;
    }
    if (victim == nodes_.end()) return nullptr;
    event("id table full (" + std::to_string(opt_.max_origins) + "): drone " + std::to_string(victim->first) +
          " (silent, no rounds) forgotten for drone " + std::to_string(id));
    for (auto& [other, n] : nodes_) n.summary.erase(victim->first);
    nodes_.erase(victim);
  }
  return &nodes_[id];
}

void Gossip::hear(int id, int64_t now) {
  Node* n = node(id, now);
  if (n == nullptr) return;
  if (!n->heard) event("drone " + std::to_string(id) + " heard: a member");
  else if (n->reported_silent) event("drone " + std::to_string(id) + " heard again after " + seconds(now - n->last_heard));
  n->heard = true;
  n->reported_silent = false;
  n->last_heard = now;
}

Screen Gossip::screen_envelope(int64_t now, int sender, int64_t seq) {
  if (options_ok_ && sender == opt_.self_id) return Screen::self;
  if (!known_id(sender)) {
    ++counters_.rejected_unknown_id;
    return Screen::unknown_id;
  }
  Node* n = node(sender, now);
  if (n == nullptr) {
    ++counters_.rejected_origin_cap;
    return Screen::table_full;
  }
  const uint64_t w = static_cast<uint64_t>(opt_.replay_window);
  if (n->seq_seen.empty()) n->seq_seen.assign((w + 63) / 64, 0);
  if (n->stale && seq > n->seq_high && static_cast<uint64_t>(seq) - static_cast<uint64_t>(n->seq_high) > w &&
      seq <= n->stale_high) {  // a number of the run before the sender's renumbering (or a jump over
                               // the window into its range: one more challenge takes it back)
    ++counters_.replayed;
    return Screen::replay;
  }
  const auto bit = [&](int64_t s) -> std::pair<size_t, uint64_t> {
    const uint64_t i = static_cast<uint64_t>(s) % w;
    return {static_cast<size_t>(i / 64), 1ull << (i % 64)};
  };
  if (!n->seq_init || seq > n->seq_high) {
    if (!n->seq_init || static_cast<uint64_t>(seq) - static_cast<uint64_t>(n->seq_high) >= w) {
      std::fill(n->seq_seen.begin(), n->seq_seen.end(), 0);
    } else {
      for (int64_t s = n->seq_high + 1; s < seq; ++s) {
        auto [word, mask] = bit(s);
        n->seq_seen[word] &= ~mask;
      }
    }
    n->seq_init = true;
    n->seq_high = seq;
    if (n->stale && seq > n->stale_high) n->stale = false;  // the new numbers passed the old ones
  } else {
    if (static_cast<uint64_t>(n->seq_high) - static_cast<uint64_t>(seq) >= w) {
      ++counters_.replayed;
      return Screen::replay;
    }
    auto [word, mask] = bit(seq);
    if (n->seq_seen[word] & mask) {
      ++counters_.duplicate_envelopes;
      return Screen::duplicate;
    }
  }
  auto [word, mask] = bit(seq);
  n->seq_seen[word] |= mask;
  hear(sender, now);
  return Screen::accept;
}

bool Gossip::open_challenge(int64_t now, int sender, const Nonce& nonce) {
  auto it = nodes_.find(sender);
  if (it == nodes_.end() || !it->second.seq_init || sender == opt_.self_id) return false;
  Node& n = it->second;
  if (n.challenged && now - n.challenged_at < opt_.challenge_timeout_us) return false;
  n.challenged = true;
  n.challenge = nonce;
  n.challenged_at = now;
  ++counters_.challenges_sent;
  return true;
}

bool Gossip::answer_challenge(int64_t now, int sender, int64_t seq, const Nonce& nonce) {
  auto it = nodes_.find(sender);
  Node* n = it == nodes_.end() ? nullptr : &it->second;
  if (n == nullptr || !n->challenged || now - n->challenged_at > opt_.challenge_timeout_us || n->challenge != nonce) {
    ++counters_.challenge_answers_refused;
    return false;
  }
  n->challenged = false;
  if (seq < n->seq_high) {  // the previous run's numbers above the new window stay refused
    n->stale_high = n->stale ? std::max(n->stale_high, n->seq_high) : n->seq_high;
    n->stale = true;
  }
  event("drone " + std::to_string(sender) + " answered a challenge: its envelope numbers restart at " +
        std::to_string(seq) + " (they were up to " + std::to_string(n->seq_high) +
        ": restarted with its clock set back)");
  n->seq_high = seq;
  std::fill(n->seq_seen.begin(), n->seq_seen.end(), 0);
  const uint64_t i = static_cast<uint64_t>(seq) % static_cast<uint64_t>(opt_.replay_window);
  n->seq_seen[static_cast<size_t>(i / 64)] |= 1ull << (i % 64);
  ++counters_.senders_renumbered;
  hear(sender, now);
  return true;
}

std::string Gossip::store(Node& n, const Packet& p, int64_t now) {
  if (static_cast<int>(n.rounds.size()) <= p.round) n.rounds.resize(static_cast<size_t>(p.round) + 1);
  Held h;
  h.packet = p;
  h.digest = packet_digest(p);
  n.rounds[static_cast<size_t>(p.round)] = std::move(h);
  ++n.stored;
  ++counters_.rounds_stored;
  while (n.consecutive < static_cast<int>(n.rounds.size()) && n.rounds[static_cast<size_t>(n.consecutive)]) {
    const uint64_t prev = n.consecutive == 0 ? 0 : n.chain.back();
    n.chain.push_back(chain_digest(prev, n.rounds[static_cast<size_t>(n.consecutive)]->digest));
    ++n.consecutive;
  }
  changed_ = true;
  (void)now;
  return "";
}

std::string Gossip::on_round(int64_t now, int sender, const Packet& p) {
  (void)sender;
  ++counters_.rounds_received;
  if (!options_ok_) return "unusable options";
  if (!known_id(p.origin)) {
    ++counters_.rejected_unknown_id;
    return "unknown drone id " + std::to_string(p.origin);
  }
  std::string e = check_packet(p);
  if (e.empty() && static_cast<int>(p.data.observations.size()) > opt_.max_observations)
    e = "drone " + std::to_string(p.origin) + " round " + std::to_string(p.round) + ": " +
        std::to_string(p.data.observations.size()) + " observations, more than " + std::to_string(opt_.max_observations);
  if (!e.empty()) {
    ++counters_.rejected_invalid;
    return e;
  }
  if (p.round >= opt_.max_rounds) {
    ++counters_.rejected_round_cap;
    return "round " + std::to_string(p.round) + " of drone " + std::to_string(p.origin) + " is beyond the cap of " +
           std::to_string(opt_.max_rounds) + " rounds";
  }
  Node* n = node(p.origin, now);
  if (n == nullptr) {
    ++counters_.rejected_origin_cap;
    return "id table full: drone " + std::to_string(p.origin) + " refused";
  }
  if (pending_answers_.erase({p.origin, p.round}) > 0) ++counters_.answers_suppressed;
  if (p.round < static_cast<int>(n->rounds.size()) && n->rounds[static_cast<size_t>(p.round)]) {
    ++counters_.duplicate_rounds;
    if (n->rounds[static_cast<size_t>(p.round)]->digest != packet_digest(p)) {
      ++counters_.digest_mismatches;
      event("drone " + std::to_string(sender) + " sent round " + std::to_string(p.round) + " of drone " +
            std::to_string(p.origin) + " with content different from ours (ours kept)");
      return "conflicting copy";
    }
    return "duplicate";
  }
  if (p.round >= n->consecutive + opt_.future_window) {
    ++counters_.rejected_future;
    return "round " + std::to_string(p.round) + " of drone " + std::to_string(p.origin) + " is too far ahead (" +
           std::to_string(n->consecutive) + " held, window " + std::to_string(opt_.future_window) + ")";
  }
  return store(*n, p, now);
}

std::string Gossip::on_summary(int64_t now, const Summary& s) {
  ++counters_.summaries_received;
  if (!options_ok_) return "unusable options";
  if (!known_id(s.sender)) {
    ++counters_.rejected_unknown_id;
    return "unknown sender " + std::to_string(s.sender);
  }
  if (static_cast<int>(s.entries.size()) > opt_.max_origins) {
    ++counters_.rejected_invalid;
    return "summary of " + std::to_string(s.entries.size()) + " origins, more than " + std::to_string(opt_.max_origins);
  }
  std::set<int> seen;
  for (const SummaryEntry& e : s.entries) {
    if (!known_id(e.origin)) {
      ++counters_.rejected_unknown_id;
      return "summary names unknown drone id " + std::to_string(e.origin);
    }
    if (e.rounds_held < 0 || e.rounds_held > opt_.max_rounds) {
      ++counters_.rejected_invalid;
      return "summary: drone " + std::to_string(e.origin) + " rounds_held " + std::to_string(e.rounds_held) +
             " outside 0 … " + std::to_string(opt_.max_rounds);
    }
    if (!seen.insert(e.origin).second) {
      ++counters_.rejected_invalid;
      return "summary lists drone " + std::to_string(e.origin) + " twice";
    }
  }
  Node* peer = node(s.sender, now);
  if (peer == nullptr) {
    ++counters_.rejected_origin_cap;
    return "id table full: drone " + std::to_string(s.sender) + " refused";
  }
  peer->summary.clear();
  for (const SummaryEntry& e : s.entries) peer->summary[e.origin] = e;
  // Learn of origins we have no rounds of yet (a restarted gossip), and compare digests.
  for (const SummaryEntry& e : s.entries) {
    if (e.rounds_held < 1) continue;
    Node* o = node(e.origin, now);
    if (o == nullptr) continue;
    if (o->consecutive >= e.rounds_held && o->chain[static_cast<size_t>(e.rounds_held - 1)] != e.digest) {
      ++counters_.digest_mismatches;
      auto key = std::make_pair(s.sender, e.origin);
      auto it = mismatch_reported_.find(key);
      if (it == mismatch_reported_.end() || it->second != e.digest) {
        mismatch_reported_[key] = e.digest;
        event("drone " + std::to_string(s.sender) + " holds rounds 0 … " + std::to_string(e.rounds_held - 1) +
              " of drone " + std::to_string(e.origin) + " with a different digest than ours");
      }
    }
  }
  return "";
}

std::vector<int> Gossip::live_ids(int64_t now) const {
  std::vector<int> ids;
  for (const auto& [id, n] : nodes_)
    if (live(n, id, now)) ids.push_back(id);
  return ids;
}

std::string Gossip::on_request(int64_t now, const Request& r) {
  ++counters_.requests_received;
  if (!options_ok_) return "unusable options";
  if (!known_id(r.requester) || !known_id(r.origin)) {
    ++counters_.rejected_unknown_id;
    return "request names unknown drone id " + std::to_string(known_id(r.requester) ? r.origin : r.requester);
  }
  if (r.rounds.empty() || static_cast<int>(r.rounds.size()) > opt_.max_request_rounds) {
    ++counters_.rejected_invalid;
    return "request for " + std::to_string(r.rounds.size()) + " rounds (1 … " + std::to_string(opt_.max_request_rounds) +
           " allowed)";
  }
  for (int k : r.rounds)
    if (k < 0 || k >= opt_.max_rounds) {
      ++counters_.rejected_invalid;
      return "request for round " + std::to_string(k) + " outside 0 … " + std::to_string(opt_.max_rounds - 1);
    }
  auto it = nodes_.find(r.origin);
  if (it == nodes_.end()) return "";
  Node& o = it->second;
  int64_t delay = 0;
  if (r.origin != opt_.self_id) {
    // Rank among the live members other than the requester and the origin, counted upwards from
    // the requester's id (wrapping), so that different requesters spread the first answer.
    std::vector<std::pair<int64_t, int>> order;
    for (int id : live_ids(now)) {
      if (id == r.requester || id == r.origin) continue;
      order.push_back({id > r.requester ? int64_t{id} : int64_t{id} + (int64_t{1} << 32), id});
    }
    std::sort(order.begin(), order.end());
    int rank = 0;
    for (size_t i = 0; i < order.size(); ++i)
      if (order[i].second == opt_.self_id) rank = static_cast<int>(i);
    delay = opt_.answer_slot_us * (1 + rank);
  }
  for (int k : r.rounds) {
    if (k >= static_cast<int>(o.rounds.size()) || !o.rounds[static_cast<size_t>(k)]) continue;
    const Held& h = *o.rounds[static_cast<size_t>(k)];
    if (h.ever_sent && now - h.last_sent < opt_.request_interval_us / 2) continue;  // just sent it
    auto key = std::make_pair(r.origin, k);
    auto p = pending_answers_.find(key);
    if (p == pending_answers_.end()) pending_answers_[key] = now + delay;
    else p->second = std::min(p->second, now + delay);
  }
  return "";
}

int Gossip::next_own_round(int64_t now) const {
  (void)now;
  int next = 0;
  const Node& self = nodes_.at(opt_.self_id);
  for (int k = static_cast<int>(self.rounds.size()) - 1; k >= 0; --k)
    if (self.rounds[static_cast<size_t>(k)]) {
      next = k + 1;
      break;
    }
  for (const auto& [id, n] : nodes_) {
    auto e = n.summary.find(opt_.self_id);
    if (e != n.summary.end()) next = std::max(next, e->second.rounds_held);
  }
  return next;
}

std::string Gossip::add_own_round(int64_t now, int64_t utime, const DroneRound& data) {
  if (!options_ok_) return "unusable options";
  Packet p;
  p.origin = opt_.self_id;
  p.round = 0;
  p.utime = utime;
  p.data = data;
  std::string e = check_packet(p);
  if (e.empty() && static_cast<int>(data.observations.size()) > opt_.max_observations)
    e = std::to_string(data.observations.size()) + " observations, more than " + std::to_string(opt_.max_observations);
  if (!e.empty()) {
    ++counters_.rejected_invalid;
    return e;
  }
  if (now - start_ < opt_.settle_us) {
    if (static_cast<int>(own_queue_.size()) >= opt_.max_rounds) {
      ++counters_.rejected_round_cap;
      return "own round queue full";
    }
    own_queue_.push_back({utime, data});
    return "";
  }
  p.round = next_own_round(now);
  if (p.round >= opt_.max_rounds) {
    ++counters_.rejected_round_cap;
    return "own round " + std::to_string(p.round) + " is beyond the cap of " + std::to_string(opt_.max_rounds) + " rounds";
  }
  store_and_send_own(p, now);
  event("own round " + std::to_string(p.round) + " closed: " + std::to_string(data.observations.size()) + " observations");
  return "";
}

std::string Gossip::add_own_packet(int64_t now, const Packet& p) {
  if (!options_ok_) return "unusable options";
  if (p.origin != opt_.self_id) {
    ++counters_.rejected_invalid;
    return "own round packet names drone " + std::to_string(p.origin) + ", not this drone (" +
           std::to_string(opt_.self_id) + ")";
  }
  std::string e = check_packet(p);
  if (e.empty() && static_cast<int>(p.data.observations.size()) > opt_.max_observations)
    e = std::to_string(p.data.observations.size()) + " observations, more than " + std::to_string(opt_.max_observations);
  if (!e.empty()) {
    ++counters_.rejected_invalid;
    return e;
  }
  if (p.round >= opt_.max_rounds) {
    ++counters_.rejected_round_cap;
    return "own round " + std::to_string(p.round) + " is beyond the cap of " + std::to_string(opt_.max_rounds) + " rounds";
  }
  Node& self = nodes_.at(opt_.self_id);
  if (p.round < static_cast<int>(self.rounds.size()) && self.rounds[static_cast<size_t>(p.round)]) {
    if (self.rounds[static_cast<size_t>(p.round)]->digest == packet_digest(p)) {
      ++counters_.duplicate_rounds;
      return "duplicate";
    }
    ++counters_.own_round_conflicts;
    event("own round " + std::to_string(p.round) + " given again with different content: the first is kept");
    return "own round " + std::to_string(p.round) + " is already held with different content";
  }
  store_and_send_own(p, now);
  return "";
}

// Stores one of this drone's own rounds and queues its first sending.
void Gossip::store_and_send_own(const Packet& p, int64_t now) {
  Node& self = nodes_.at(opt_.self_id);
  store(self, p, now);
  ++counters_.own_rounds;
  Held& h = *self.rounds[static_cast<size_t>(p.round)];
  h.ever_sent = true;
  h.last_sent = now;
  Outgoing out;
  out.kind = Outgoing::Kind::round;
  out.packet = p;
  outbox_.push_back(std::move(out));
  ++counters_.rounds_sent;
}

std::vector<int> Gossip::wanted(int origin, int64_t now) const {
  std::vector<int> out;
  auto it = nodes_.find(origin);
  if (it == nodes_.end()) return out;
  const Node& o = it->second;
  int best = 0;
  for (const auto& [id, n] : nodes_) {
    if (id == opt_.self_id || !live(n, id, now)) continue;
    auto e = n.summary.find(origin);
    if (e != n.summary.end()) best = std::max(best, e->second.rounds_held);
  }
  const int limit = std::min({best, o.consecutive + opt_.future_window, opt_.max_rounds});
  for (int k = o.consecutive; k < limit && static_cast<int>(out.size()) < opt_.max_request_rounds; ++k)
    if (k >= static_cast<int>(o.rounds.size()) || !o.rounds[static_cast<size_t>(k)]) out.push_back(k);
  return out;
}

Summary Gossip::summary() const {
  Summary s;
  s.sender = opt_.self_id;
  for (const auto& [id, n] : nodes_)
    if (n.consecutive > 0) s.entries.push_back({id, n.consecutive, n.chain.back()});
  return s;
}

std::vector<Outgoing> Gossip::tick(int64_t now) {
  std::vector<Outgoing> out;
  if (!options_ok_) return out;
  // Own rounds closed before settling: numbered now.
  if (now - start_ >= opt_.settle_us && !own_queue_.empty()) {
    auto queue = std::move(own_queue_);
    own_queue_.clear();
    for (auto& [utime, data] : queue) add_own_round(now, utime, data);
  }
  out = std::move(outbox_);
  outbox_.clear();
  // Membership.
  for (auto& [id, n] : nodes_) {
    if (id == opt_.self_id || n.reported_silent || (!n.heard && !on_roster(id)) || live(n, id, now)) continue;
    n.reported_silent = true;
    ++counters_.members_silenced;
    if (n.heard)
      event("drone " + std::to_string(id) + " silent for " + seconds(now - n.last_heard) +
            ": reported silent, no longer blocks completion");
    else
      event("roster drone " + std::to_string(id) + " not heard since start (" + seconds(now - start_) +
            "): reported silent, does not block completion");
  }
  // Due answers.
  for (auto it = pending_answers_.begin(); it != pending_answers_.end();) {
    if (it->second > now) {
      ++it;
      continue;
    }
    auto n = nodes_.find(it->first.first);
    if (n != nodes_.end() && it->first.second < static_cast<int>(n->second.rounds.size()) &&
        n->second.rounds[static_cast<size_t>(it->first.second)]) {
      Held& h = *n->second.rounds[static_cast<size_t>(it->first.second)];
      h.ever_sent = true;
      h.last_sent = now;
      Outgoing o;
      o.kind = Outgoing::Kind::round;
      o.packet = h.packet;
      o.answer = true;
      out.push_back(std::move(o));
      ++counters_.answers_sent;
    }
    it = pending_answers_.erase(it);
  }
  // Requests for what live peers hold and we do not.
  for (auto& [id, n] : nodes_) {
    if (n.requested && now - n.last_request < opt_.request_interval_us) continue;
    std::vector<int> w = wanted(id, now);
    if (w.empty()) continue;
    n.requested = true;
    n.last_request = now;
    Outgoing o;
    o.kind = Outgoing::Kind::request;
    o.request.requester = opt_.self_id;
    o.request.origin = id;
    o.request.rounds = std::move(w);
    out.push_back(std::move(o));
    ++counters_.requests_sent;
  }
  // Summary: the heartbeat, or soon after a change.
  if (!ever_summarised_ || now - last_summary_ >= opt_.summary_period_us ||
      (changed_ && now - last_summary_ >= opt_.summary_min_interval_us)) {
    Outgoing o;
    o.kind = Outgoing::Kind::summary;
    o.summary = summary();
    out.push_back(std::move(o));
    ++counters_.summaries_sent;
    ever_summarised_ = true;
    last_summary_ = now;
    changed_ = false;
  }
  return out;
}

int64_t Gossip::next_deadline(int64_t now) const {
  if (!options_ok_) return now + opt_.summary_period_us;
  if (!outbox_.empty() || !ever_summarised_) return now;
  int64_t d = last_summary_ + opt_.summary_period_us;
  if (changed_) d = std::min(d, last_summary_ + opt_.summary_min_interval_us);
  if (!own_queue_.empty()) d = std::min(d, start_ + opt_.settle_us);
  for (const auto& [key, due] : pending_answers_) d = std::min(d, due);
  for (const auto& [id, n] : nodes_) {
    if (live(n, id, now) && id != opt_.self_id) {
      const int64_t base = n.heard ? n.last_heard : start_;
      d = std::min(d, base + opt_.silence_timeout_us + 1);
    }
    if (!wanted(id, now).empty()) d = std::min(d, n.requested ? n.last_request + opt_.request_interval_us : now);
  }
  return std::max(d, now);
}

Completion Gossip::completion(int64_t now) const {
  Completion c;
  if (!options_ok_) return c;
  int k = std::numeric_limits<int>::max();
  for (const auto& [id, n] : nodes_) {
    if (live(n, id, now)) {
      c.live.push_back(id);
      k = std::min(k, n.consecutive);
    } else if (n.heard || on_roster(id)) {
      c.silent.push_back(id);
    }
  }
  c.rounds = k == std::numeric_limits<int>::max() ? 0 : k;
  if (c.rounds > 0)
    for (const auto& [id, n] : nodes_)
      if (n.consecutive >= c.rounds) c.drones.push_back(id);
  c.ready = c.rounds > 0 && now - start_ >= opt_.settle_us && static_cast<int>(c.drones.size()) >= opt_.min_members;
  return c;
}

const Packet* Gossip::packet(int origin, int round) const {
  auto it = nodes_.find(origin);
  if (it == nodes_.end() || round < 0 || round >= static_cast<int>(it->second.rounds.size())) return nullptr;
  const auto& h = it->second.rounds[static_cast<size_t>(round)];
  return h ? &h->packet : nullptr;
}

std::vector<const Packet*> Gossip::complete_packets(const Completion& c) const {
  std::vector<const Packet*> out;
  if (!c.ready) return out;
  for (int id : c.drones)
    for (int k = 0; k < c.rounds; ++k) {
      const Packet* p = packet(id, k);
      if (p) out.push_back(p);
    }
  return out;
}

int Gossip::rounds_held(int origin) const {
  auto it = nodes_.find(origin);
  return it == nodes_.end() ? 0 : it->second.consecutive;
}

uint64_t Gossip::digest(int origin) const {
  auto it = nodes_.find(origin);
  return it == nodes_.end() || it->second.consecutive == 0 ? 0 : it->second.chain.back();
}

std::vector<MemberInfo> Gossip::members(int64_t now) const {
  std::vector<MemberInfo> out;
  for (const auto& [id, n] : nodes_) {
    MemberInfo m;
    m.id = id;
    m.live = live(n, id, now);
    m.heard = n.heard || id == opt_.self_id;
    m.last_heard = id == opt_.self_id ? now : n.last_heard;
    m.rounds_held = n.consecutive;
    out.push_back(m);
  }
  return out;
}

size_t Gossip::stored_packets() const {
  size_t s = 0;
  for (const auto& [id, n] : nodes_) s += n.stored;
  return s;
}

size_t Gossip::tracked_ids() const { return nodes_.size(); }

std::vector<std::string> Gossip::take_events() {
  std::vector<std::string> out(events_.begin(), events_.end());
  events_.clear();
  return out;
}

// ---------------------------------------------------------------------------------------------
// RoundBuilder

std::string check_builder_options(const BuilderOptions& o) {
  if (!(o.spin_angle > 0) || !std::isfinite(o.spin_angle)) return "spin_angle must be > 0";
  if (o.round_period_us < 0) return "round_period is negative";
  if (o.latency_us < 0) return "latency is negative";
  if (o.max_odometry_gap_us <= 0) return "max_odometry_gap must be > 0";
  if (o.max_tracks < 0) return "max_tracks is negative";
  if (o.max_odometry < 2) return "max_odometry must be ≥ 2";
  if (o.max_detections < 1) return "max_detections must be ≥ 1";
  if (!(o.max_speed >= 0) || !std::isfinite(o.max_speed)) return "max_speed must be finite and ≥ 0";
  if (o.max_speed_window_us <= 0) return "max_speed_window must be > 0";
  return "";
}

std::vector<std::pair<std::string, int64_t>> BuilderCounters::list() const {
  return {{"odometry", odometry},
          {"detections", detections},
          {"rejected_odometry", rejected_odometry},
          {"rejected_detections", rejected_detections},
          {"late_detections", late_detections},
          {"unmatched_detections", unmatched_detections},
          {"moves", moves},
          {"dropped_history", dropped_history},
          {"dropped_tracks", dropped_tracks},
          {"odometry_gaps", odometry_gaps},
          {"odometry_restarts", restarts},
          {"rounds_built", rounds}};
}

RoundBuilder::RoundBuilder(const BuilderOptions& options) : opt_(options) {}

bool RoundBuilder::odometry_at(int64_t t, Eigen::Vector3d* position, double* yaw) const {
  if (odo_.empty() || t < odo_.front().t || t > odo_.back().t) return false;
  auto it = std::lower_bound(odo_.begin(), odo_.end(), t, [](const Odo& o, int64_t v) { return o.t < v; });
  if (it->t == t) {
    *position = it->p;
    *yaw = it->yaw;
    return true;
  }
  const Odo& b = *it;
  const Odo& a = *(it - 1);
  if (b.t - a.t > opt_.max_odometry_gap_us) return false;
  const double f = static_cast<double>(t - a.t) / static_cast<double>(b.t - a.t);
  *position = a.p + f * (b.p - a.p);
  *yaw = a.yaw + f * (b.yaw - a.yaw);
  return true;
}

std::string RoundBuilder::add_odometry(int64_t utime, const Eigen::Vector3d& position, double yaw) {
  if (!position.allFinite() || !std::isfinite(yaw)) {
    ++counters_.rejected_odometry;
    return "odometry with a non-finite position or yaw";
  }
  if (!odo_.empty() && utime <= odo_.back().t) {
    ++counters_.rejected_odometry;
    return "odometry time " + std::to_string(utime) + " not after the previous sample's " + std::to_string(odo_.back().t);
  }
  ++counters_.odometry;
  odo_.push_back({utime, position, yaw});
  if (!started_) {
    started_ = true;
    open_start_ = utime;
    min_yaw_ = max_yaw_ = yaw;
  } else if (opt_.round_period_us == 0 && opt_.max_speed > 0 && moving()) {
    counters_.moves += !moving_;  // once per move, when it starts
    moving_ = true;
    open_start_ = utime;  // the open round restarts where the drone stops
    min_yaw_ = max_yaw_ = yaw;
  } else {
    moving_ = false;
    min_yaw_ = std::min(min_yaw_, yaw);
    max_yaw_ = std::max(max_yaw_, yaw);
  }
  close_if_spun();
  while (!closing_.empty() && utime >= closing_.front().t1 + opt_.latency_us) {
    finalize(closing_.front());
    closing_.pop_front();
  }
  trim();
  return "";
}

// True when the newest odometry moved faster than max_speed over the last max_speed_window.
bool RoundBuilder::moving() const {
  const Odo& last = odo_.back();
  for (auto it = odo_.rbegin() + 1; it != odo_.rend(); ++it) {
    if (last.t - it->t > opt_.max_odometry_gap_us) return false;  // a gap: no speed to measure
    if (last.t - it->t >= opt_.max_speed_window_us)
      return (last.p - it->p).norm() > opt_.max_speed * static_cast<double>(last.t - it->t) * 1e-6;
  }
  return false;
}

void RoundBuilder::close_if_spun() {
  const Odo& last = odo_.back();
  if (opt_.round_period_us > 0) {
    // A gap in the odometry: the period it interrupted closes with the data it has, and the empty
    // periods inside the gap are skipped in one step, keeping the period boundaries (closing one
    // empty round per period made millions: a boot clock becoming Unix time ran out of memory).
    if (odo_.size() >= 2 && last.t - odo_[odo_.size() - 2].t > opt_.max_odometry_gap_us) {
      ++counters_.odometry_gaps;
      if (last.t >= open_start_ + opt_.round_period_us) {
        closing_.push_back({open_start_, open_start_ + opt_.round_period_us});
        open_start_ += opt_.round_period_us;
        open_start_ += opt_.round_period_us * ((last.t - open_start_) / opt_.round_period_us);
      }
      return;
    }
    while (last.t >= open_start_ + opt_.round_period_us) {
      closing_.push_back({open_start_, open_start_ + opt_.round_period_us});
      open_start_ += opt_.round_period_us;
    }
    return;
  }
  const double a = opt_.spin_angle;
  if (last.yaw - min_yaw_ < a && max_yaw_ - last.yaw < a) return;
  // The latest t0 ≥ open_start_ with |yaw(last) − yaw(t0)| ≥ a: scan back over the samples, the
  // open round's start point last.
  auto first = std::lower_bound(odo_.begin(), odo_.end(), open_start_, [](const Odo& o, int64_t v) { return o.t < v; });
  Eigen::Vector3d p0;
  double y0 = 0;
  int64_t t0 = open_start_;
  bool found = false;
  // Points from newest to oldest: samples (last − 1 … first), then the start point if it falls
  // between samples.
  int64_t t_next = last.t;
  double y_next = last.yaw;
  const auto crossing = [&](int64_t t, double y) {
    if (std::abs(last.yaw - y) < a) {
      t_next = t;
      y_next = y;
      return false;
    }
    const double target = y < last.yaw ? last.yaw - a : last.yaw + a;
    const double f = (target - y) / (y_next - y);  // y beyond target, y_next within: f ∈ [0, 1)
    t0 = t + static_cast<int64_t>(std::floor(f * static_cast<double>(t_next - t)));
    return true;
  };
  for (auto it = odo_.end() - 1; it != first && !found;) {
    --it;
    found = crossing(it->t, it->yaw);
  }
  if (!found && (first == odo_.end() || first->t != open_start_) && odometry_at(open_start_, &p0, &y0))
    found = crossing(open_start_, y0);
  if (!found) t0 = open_start_;  // (cannot happen: min/max include the start point) whole interval
  closing_.push_back({t0, last.t});
  open_start_ = last.t;
  min_yaw_ = max_yaw_ = last.yaw;
}

void RoundBuilder::finalize(const Closed& c) {
  BuiltRound out;
  out.start_utime = c.t0;
  out.end_utime = c.t1;
  double yaw0 = 0;
  if (!odometry_at(c.t0, &out.data.position, &yaw0)) {
    // t0 lies in a gap or before the history: the nearest later sample.
    auto it = std::lower_bound(odo_.begin(), odo_.end(), c.t0, [](const Odo& o, int64_t v) { return o.t < v; });
    if (it == odo_.end()) return;
    out.data.position = it->p;
    yaw0 = it->yaw;
  }
  out.data.yaw = wrap_angle(yaw0);
  struct Best {
    double bearing;
    int64_t t;
    Eigen::Vector3d v;
  };
  std::map<int, Best> best;
  for (const Det& d : det_) {
    if (d.t < c.t0 || d.t >= c.t1) continue;
    const double b = std::abs(std::atan2(d.v.y(), d.v.x()));
    auto it = best.find(d.track);
    if (it == best.end() || b < it->second.bearing || (b == it->second.bearing && d.t < it->second.t))
      best[d.track] = {b, d.t, d.v};
  }
  int kept = 0;
  for (const auto& [track, b] : best) {
    if (kept >= opt_.max_tracks) {
      ++counters_.dropped_tracks;
      continue;
    }
    Observation o;
    double y = 0;
    if (!odometry_at(b.t, &o.odom_position, &y)) {
      ++counters_.unmatched_detections;
      continue;
    }
    o.odom_yaw = wrap_angle(y);
    o.vector = b.v;
    out.data.observations.push_back(o);
    ++kept;
  }
  ++counters_.rounds;
  ready_.push_back(std::move(out));
}

void RoundBuilder::trim() {
  const int64_t keep_from = closing_.empty() ? open_start_ : std::min(open_start_, closing_.front().t0);
  // Keep the last sample at or before keep_from (for interpolation) and everything after, and
  // the odometry of the last max_speed_window (to tell a move).
  const int64_t keep_odometry_from = std::min(keep_from, odo_.back().t - opt_.max_speed_window_us);
  while (odo_.size() >= 2 && odo_[1].t <= keep_odometry_from) odo_.pop_front();
  while (!det_.empty() && det_.front().t < keep_from) det_.pop_front();
  bool dropped = false;
  while (odo_.size() > opt_.max_odometry) {
    odo_.pop_front();
    ++counters_.dropped_history;
    dropped = true;
  }
  while (det_.size() > opt_.max_detections) {
    det_.pop_front();
    ++counters_.dropped_history;
  }
  if (dropped) {
    // The open round can no longer start before the history kept; closing rounds keep theirs
    // as far as it goes.
    if (open_start_ < odo_.front().t) {
      open_start_ = odo_.front().t;
      min_yaw_ = max_yaw_ = odo_.front().yaw;
      for (const Odo& o : odo_) {
        min_yaw_ = std::min(min_yaw_, o.yaw);
        max_yaw_ = std::max(max_yaw_, o.yaw);
      }
    }
  }
}

std::string RoundBuilder::add_detection(int64_t utime, int track_id, const Eigen::Vector3d& vector) {
  if (!vector.allFinite()) {
    ++counters_.rejected_detections;
    return "detection vector is not finite";
  }
  if (vector.norm() < 1e-6) {
    ++counters_.rejected_detections;
    return "detection vector has zero length";
  }
  const int64_t earliest = closing_.empty() ? open_start_ : std::min(open_start_, closing_.front().t0);
  if (started_ && utime < earliest) {
    ++counters_.late_detections;
    return "detection at " + std::to_string(utime) + " is older than the open round's start " + std::to_string(earliest);
  }
  ++counters_.detections;
  det_.push_back({utime, track_id, vector});
  if (det_.size() > 1 && det_[det_.size() - 2].t > utime) {
    // Keep time order (frames may arrive out of order): insertion from the back.
    for (size_t i = det_.size() - 1; i > 0 && det_[i - 1].t > det_[i].t; --i) std::swap(det_[i - 1], det_[i]);
  }
  while (det_.size() > opt_.max_detections) {
    det_.pop_front();
    ++counters_.dropped_history;
  }
  return "";
}

void RoundBuilder::restart() {
  for (const Closed& c : closing_) finalize(c);  // closed on the old clock: complete as they are
  closing_.clear();
  odo_.clear();
  det_.clear();
  started_ = false;
  moving_ = false;
  open_start_ = 0;
  min_yaw_ = max_yaw_ = 0;
  ++counters_.restarts;
}

std::vector<BuiltRound> RoundBuilder::take_rounds() {
  std::vector<BuiltRound> out = std::move(ready_);
  ready_.clear();
  return out;
}

}  // namespace fact::gossip
