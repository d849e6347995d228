// Unit tests of the gossip state machine (fact::gossip::Gossip), the round builder
// (fact::gossip::RoundBuilder) and fact-gossip's wire layer (envelope authentication, key files,
// message conversions). The swarm tests run several Gossip instances in one process over a
// simulated multicast network with seeded loss, duplication and reordering, in simulated time.
#include "fact/gossip.h"
#include "fact_gossip/wire.h"

#include <algorithm>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <set>

namespace fact::gossip {
namespace {

constexpr int64_t kMs = 1000;
constexpr int64_t kS = 1000000;

Packet make_packet(int origin, int round, int observations = 3) {
  Packet p;
  p.origin = origin;
  p.round = round;
  p.utime = 1000000 + 1000 * round + origin;
  p.data.position = Eigen::Vector3d(origin, round, 1.5);
  p.data.yaw = 0.1 * origin - 0.05 * round;
  for (int k = 0; k < observations; ++k) {
    Observation o;
    o.odom_position = Eigen::Vector3d(origin + 0.01 * k, round, 1.5);
    o.odom_yaw = 0.3 * k;
    o.vector = Eigen::Vector3d(1.0 + k, -0.5 * k + origin * 0.1, 0.2);
    p.data.observations.push_back(o);
  }
  return p;
}

Options base_options(int self) {
  Options o;
  o.self_id = self;
  o.settle_us = 0;
  o.min_members = 1;
  return o;
}

// --------------------------------------------------------------------------------------------
// Digests

TEST(GossipDigest, EqualPacketsEqualDigestsAnyChangeDiffers) {
  const Packet a = make_packet(3, 2);
  EXPECT_EQ(packet_digest(a), packet_digest(make_packet(3, 2)));
  std::vector<Packet> variants(9, a);
  variants[0].origin = 4;
  variants[1].round = 3;
  variants[2].utime += 1;
  variants[3].data.position.z() = std::nextafter(a.data.position.z(), 10.0);
  variants[4].data.yaw = -a.data.yaw;
  variants[5].data.observations[1].vector.x() += 1e-12;
  variants[6].data.observations[2].odom_yaw += 1e-15;
  variants[7].data.observations.pop_back();
  variants[8].data.observations[0].odom_position.y() = -0.0;  // 0.0 → -0.0: other bits
  std::set<uint64_t> seen{packet_digest(a)};
  for (const Packet& v : variants) EXPECT_TRUE(seen.insert(packet_digest(v)).second);
  // The chain depends on every round and on the order.
  const uint64_t d0 = packet_digest(make_packet(1, 0)), d1 = packet_digest(make_packet(1, 1));
  EXPECT_NE(chain_digest(chain_digest(0, d0), d1), chain_digest(chain_digest(0, d1), d0));
}

TEST(GossipDigest, DigestsAgreeWhateverTheArrivalOrder) {
  Gossip in_order(base_options(0), 0), reordered(base_options(1), 0);
  for (int r = 0; r < 5; ++r) EXPECT_EQ(in_order.on_round(kMs, 2, make_packet(2, r)), "");
  for (int r : {4, 2, 0, 3, 1}) EXPECT_EQ(reordered.on_round(kMs, 2, make_packet(2, r)), "");
  EXPECT_EQ(in_order.rounds_held(2), 5);
  EXPECT_EQ(reordered.rounds_held(2), 5);
  EXPECT_EQ(in_order.digest(2), reordered.digest(2));
  uint64_t chain = 0;
  for (int r = 0; r < 5; ++r) chain = chain_digest(chain, packet_digest(make_packet(2, r)));
  EXPECT_EQ(in_order.digest(2), chain);
  Gossip partial(base_options(1), 0);
  for (int r : {0, 1, 3}) partial.on_round(kMs, 2, make_packet(2, r));
  EXPECT_EQ(partial.rounds_held(2), 2);  // consecutive from 0
}

// --------------------------------------------------------------------------------------------
// Bad input

TEST(GossipInput, NanNegativeAndOversizedPacketsAreCountedNotStored) {
  Options o = base_options(0);
  o.max_observations = 4;
  Gossip g(o, 0);
  Packet nan = make_packet(1, 0);
  nan.data.observations[1].vector.y() = std::nan("");
  EXPECT_NE(g.on_round(kMs, 1, nan).find("observations[1].vector[1] is nan"), std::string::npos);
  Packet inf = make_packet(1, 0);
  inf.data.yaw = std::numeric_limits<double>::infinity();
  EXPECT_NE(g.on_round(kMs, 1, inf), "");
  Packet zero = make_packet(1, 0);
  zero.data.observations[0].vector.setZero();
  EXPECT_NE(g.on_round(kMs, 1, zero), "");
  Packet negative = make_packet(1, -1);
  EXPECT_NE(g.on_round(kMs, 1, negative), "");
  EXPECT_NE(g.on_round(kMs, 1, make_packet(1, 0, 5)), "");  // 5 > max_observations
  EXPECT_EQ(g.counters().rejected_invalid, 5);
  EXPECT_EQ(g.stored_packets(), 0u);
  EXPECT_EQ(g.rounds_held(1), 0);
  Packet nan_own = make_packet(0, 0);
  nan_own.data.position.x() = std::nan("");
  EXPECT_NE(g.add_own_packet(kMs, nan_own), "");
  EXPECT_NE(g.add_own_round(kMs, 5, nan_own.data), "");
  EXPECT_EQ(g.counters().rejected_invalid, 7);
}

TEST(GossipInput, DuplicatesAreIgnoredAndCounted) {
  Gossip g(base_options(0), 0);
  EXPECT_EQ(g.on_round(kMs, 1, make_packet(1, 0)), "");
  EXPECT_EQ(g.on_round(2 * kMs, 2, make_packet(1, 0)), "duplicate");
  EXPECT_EQ(g.on_round(3 * kMs, 1, make_packet(1, 0)), "duplicate");
  EXPECT_EQ(g.counters().duplicate_rounds, 2);
  EXPECT_EQ(g.counters().rounds_stored, 1);
  EXPECT_EQ(g.stored_packets(), 1u);
  // A different copy of a held round: the first is kept, the conflict counted.
  Packet other = make_packet(1, 0);
  other.data.yaw += 0.5;
  EXPECT_EQ(g.on_round(4 * kMs, 2, other), "conflicting copy");
  EXPECT_EQ(g.counters().digest_mismatches, 1);
  EXPECT_EQ(g.packet(1, 0)->data.yaw, make_packet(1, 0).data.yaw);
  // Own rounds given twice: same content → duplicate; different → conflict, first kept.
  EXPECT_EQ(g.add_own_packet(kMs, make_packet(0, 0)), "");
  EXPECT_EQ(g.add_own_packet(kMs, make_packet(0, 0)), "duplicate");
  Packet own_other = make_packet(0, 0);
  own_other.utime += 7;
  EXPECT_NE(g.add_own_packet(kMs, own_other), "");
  EXPECT_EQ(g.counters().own_round_conflicts, 1);
  EXPECT_NE(g.add_own_packet(kMs, make_packet(3, 0)), "");  // not our origin
}

TEST(GossipInput, FarFutureRoundsAndRoundsPastTheCapAreRefused) {
  Options o = base_options(0);
  o.future_window = 4;
  o.max_rounds = 10;
  Gossip g(o, 0);
  EXPECT_EQ(g.on_round(kMs, 1, make_packet(1, 3)), "");  // 3 < 0 + 4
  EXPECT_NE(g.on_round(kMs, 1, make_packet(1, 4)), "");  // 4 ≥ 0 + 4
  EXPECT_EQ(g.counters().rejected_future, 1);
  for (int r = 0; r < 3; ++r) g.on_round(kMs, 1, make_packet(1, r));
  EXPECT_EQ(g.rounds_held(1), 4);
  EXPECT_EQ(g.on_round(kMs, 1, make_packet(1, 7)), "");  // 7 < 4 + 4 now
  EXPECT_NE(g.on_round(kMs, 1, make_packet(1, 1000000)), "");
  EXPECT_EQ(g.counters().rejected_round_cap, 1);
  EXPECT_NE(g.add_own_packet(kMs, make_packet(0, 10)), "");  // own rounds obey the cap too
  EXPECT_EQ(g.counters().rejected_round_cap, 2);
}

TEST(GossipInput, UnknownIdsAreRefusedWithARoster) {
  Options o = base_options(0);
  o.roster = {0, 1, 2};
  Gossip g(o, 0);
  EXPECT_EQ(g.screen_envelope(kMs, 7, 1), Screen::unknown_id);
  EXPECT_EQ(g.screen_envelope(kMs, 1, 1), Screen::accept);
  EXPECT_NE(g.on_round(kMs, 1, make_packet(7, 0)), "");
  EXPECT_NE(g.on_summary(kMs, Summary{1, {{7, 1, 5}}}), "");
  EXPECT_NE(g.on_request(kMs, Request{1, 9, {0}}), "");
  EXPECT_NE(g.on_request(kMs, Request{9, 1, {0}}), "");
  EXPECT_EQ(g.counters().rejected_unknown_id, 5);
  EXPECT_EQ(g.tracked_ids(), 3u);
  // Without a roster: ids above max_drone_id, and negative ids.
  Options open = base_options(0);
  open.max_drone_id = 50;
  Gossip h(open, 0);
  EXPECT_EQ(h.screen_envelope(kMs, 51, 1), Screen::unknown_id);
  EXPECT_EQ(h.screen_envelope(kMs, -3, 1), Screen::unknown_id);
  EXPECT_EQ(h.screen_envelope(kMs, 50, 1), Screen::accept);
  EXPECT_EQ(h.screen_envelope(kMs, 0, 1), Screen::self);
}

TEST(GossipInput, MalformedSummariesAndRequestsAreRefused) {
  Options o = base_options(0);
  o.max_rounds = 8;
  o.max_request_rounds = 3;
  Gossip g(o, 0);
  EXPECT_NE(g.on_summary(kMs, Summary{1, {{2, 9, 1}}}), "");            // held > max_rounds
  EXPECT_NE(g.on_summary(kMs, Summary{1, {{2, -1, 1}}}), "");           // negative
  EXPECT_NE(g.on_summary(kMs, Summary{1, {{2, 1, 1}, {2, 1, 1}}}), "");  // twice
  EXPECT_NE(g.on_request(kMs, Request{1, 2, {}}), "");
  EXPECT_NE(g.on_request(kMs, Request{1, 2, {0, 1, 2, 3}}), "");
  EXPECT_NE(g.on_request(kMs, Request{1, 2, {8}}), "");
  EXPECT_EQ(g.counters().rejected_invalid, 6);
  EXPECT_EQ(check_options(Options{}), "");
  Options bad;
  bad.roster = {1, 2};  // self (0) missing
  EXPECT_NE(check_options(bad), "");
  Gossip unusable(bad, 0);
  EXPECT_NE(unusable.on_round(kMs, 1, make_packet(1, 0)), "");
  EXPECT_TRUE(unusable.tick(kMs).empty());
}

// --------------------------------------------------------------------------------------------
// Envelope screening: duplicates and replays

TEST(GossipEnvelope, DuplicatesReplaysAndRestartedSenders) {
  Options o = base_options(0);
  o.replay_window = 64;
  Gossip g(o, 0);
  const int64_t start = 1700000000000000;  // a sender's seq starts at its start time (µs)
  EXPECT_EQ(g.screen_envelope(kMs, 1, start), Screen::accept);
  EXPECT_EQ(g.screen_envelope(kMs, 1, start + 2), Screen::accept);
  EXPECT_EQ(g.screen_envelope(kMs, 1, start + 1), Screen::accept);  // reordered: fine
  EXPECT_EQ(g.screen_envelope(kMs, 1, start + 1), Screen::duplicate);
  EXPECT_EQ(g.screen_envelope(kMs, 1, start + 2), Screen::duplicate);
  EXPECT_EQ(g.screen_envelope(kMs, 1, start + 100), Screen::accept);
  EXPECT_EQ(g.screen_envelope(kMs, 1, start + 3), Screen::replay);  // older than the window
  EXPECT_EQ(g.screen_envelope(kMs, 1, start + 40), Screen::accept);  // within the window, unseen
  EXPECT_EQ(g.counters().duplicate_envelopes, 2);
  EXPECT_EQ(g.counters().replayed, 1);
  // The sender restarts: its numbers start at the new start time, above the old ones.
  EXPECT_EQ(g.screen_envelope(kMs, 1, start + 5 * kS), Screen::accept);
  EXPECT_EQ(g.screen_envelope(kMs, 1, start + 5 * kS + 1), Screen::accept);
  // Replaying a packet captured before the restart.
  EXPECT_EQ(g.screen_envelope(kMs, 1, start + 100), Screen::replay);
  EXPECT_EQ(g.counters().replayed, 2);
}

// A sender restarted with its clock set back numbers its envelopes below its old ones: they screen
// as replays until it answers a challenge with the outstanding nonce; then its new numbers pass,
// and the old run's numbers (a recording of them) stay refused.
TEST(GossipEnvelope, RenumberedSenderIsTakenBackAfterAnsweringAChallenge) {
  Options o = base_options(0);
  o.replay_window = 64;
  Gossip g(o, 0);
  const int64_t old_start = 1700000000000000, new_start = old_start - 3600 * kS;  // clock back an hour
  const Nonce nonce{1, 2, 3}, other{9};
  EXPECT_FALSE(g.open_challenge(kMs, 1, nonce));  // never heard: nothing to challenge
  for (int k = 0; k < 200; ++k) ASSERT_EQ(g.screen_envelope(kMs, 1, old_start + k), Screen::accept);
  EXPECT_EQ(g.screen_envelope(kS, 1, new_start), Screen::replay);
  EXPECT_TRUE(g.open_challenge(kS, 1, nonce));
  EXPECT_FALSE(g.open_challenge(kS + kMs, 1, other));  // one outstanding challenge per sender
  EXPECT_EQ(g.counters().challenges_sent, 1);
  // Answers with the wrong nonce, from another sender, or before any challenge are refused.
  EXPECT_FALSE(g.answer_challenge(kS + 2 * kMs, 1, new_start + 1, other));
  EXPECT_FALSE(g.answer_challenge(kS + 2 * kMs, 2, new_start + 1, nonce));
  EXPECT_EQ(g.counters().challenge_answers_refused, 2);
  EXPECT_TRUE(g.answer_challenge(kS + 3 * kMs, 1, new_start + 1, nonce));
  EXPECT_EQ(g.counters().senders_renumbered, 1);
  EXPECT_FALSE(g.answer_challenge(kS + 4 * kMs, 1, new_start + 2, nonce));  // used up
  EXPECT_EQ(g.screen_envelope(kS + 5 * kMs, 1, new_start + 1), Screen::duplicate);  // the answer itself
  EXPECT_EQ(g.screen_envelope(kS + 5 * kMs, 1, new_start + 2), Screen::accept);
  EXPECT_EQ(g.screen_envelope(kS + 5 * kMs, 1, new_start), Screen::accept);  // reordered, in the window
  // The old run played again: refused, and the sender's new numbers still pass.
  EXPECT_EQ(g.screen_envelope(kS + 6 * kMs, 1, old_start + 150), Screen::replay);
  EXPECT_EQ(g.screen_envelope(kS + 6 * kMs, 1, old_start + 199), Screen::replay);
  EXPECT_EQ(g.screen_envelope(kS + 6 * kMs, 1, new_start + 3), Screen::accept);
  // The old run's numbers below those this receiver heard are refused too (review, session 32: a
  // rule that refused only [lowest heard, highest] let them in and locked the sender out again).
  EXPECT_EQ(g.screen_envelope(kS + 6 * kMs, 1, old_start - 500), Screen::replay);
  EXPECT_EQ(g.screen_envelope(kS + 6 * kMs, 1, new_start + 4), Screen::accept);
  // Numbers past the old run's highest are new again.
  EXPECT_EQ(g.screen_envelope(kS + 7 * kMs, 1, old_start + 1000), Screen::accept);
  EXPECT_EQ(g.screen_envelope(kS + 7 * kMs, 1, new_start + 5), Screen::replay);
  // A challenge not answered in time expires: the late answer is refused, a new challenge may go.
  EXPECT_TRUE(g.open_challenge(2 * kS, 1, other));
  EXPECT_FALSE(g.open_challenge(2 * kS + o.challenge_timeout_us - 1, 1, nonce));
  EXPECT_FALSE(g.answer_challenge(2 * kS + o.challenge_timeout_us + 1, 1, new_start + 5, other));
  EXPECT_TRUE(g.open_challenge(2 * kS + o.challenge_timeout_us, 1, nonce));
  bool logged = false;
  for (const std::string& e : g.take_events()) logged |= e.find("drone 1 answered a challenge") != std::string::npos;
  EXPECT_TRUE(logged);
}

// --------------------------------------------------------------------------------------------
// Summaries, requests, answers

std::vector<Outgoing> of_kind(const std::vector<Outgoing>& outs, Outgoing::Kind k) {
  std::vector<Outgoing> r;
  for (const auto& o : outs)
    if (o.kind == k) r.push_back(o);
  return r;
}

TEST(GossipExchange, SummariesAreHeartbeatsAndFollowChanges) {
  Options o = base_options(0);
  o.summary_period_us = kS;
  o.summary_min_interval_us = 100 * kMs;
  Gossip g(o, 0);
  auto outs = g.tick(0);
  ASSERT_EQ(of_kind(outs, Outgoing::Kind::summary).size(), 1u);
  EXPECT_TRUE(of_kind(g.tick(500 * kMs), Outgoing::Kind::summary).empty());
  EXPECT_EQ(of_kind(g.tick(kS), Outgoing::Kind::summary).size(), 1u);
  g.on_round(kS + 10 * kMs, 1, make_packet(1, 0));
  EXPECT_TRUE(of_kind(g.tick(kS + 50 * kMs), Outgoing::Kind::summary).empty());  // < min interval
  EXPECT_EQ(g.next_deadline(kS + 50 * kMs), kS + 100 * kMs);
  outs = of_kind(g.tick(kS + 100 * kMs), Outgoing::Kind::summary);
  ASSERT_EQ(outs.size(), 1u);
  ASSERT_EQ(outs[0].summary.entries.size(), 1u);
  EXPECT_EQ(outs[0].summary.entries[0].origin, 1);
  EXPECT_EQ(outs[0].summary.entries[0].rounds_held, 1);
  EXPECT_EQ(outs[0].summary.entries[0].digest, chain_digest(0, packet_digest(make_packet(1, 0))));
  EXPECT_EQ(g.counters().summaries_sent, 3);
}

TEST(GossipExchange, MissingRoundsAreRequestedWithinTheWindowAndRetried) {
  Options o = base_options(0);
  o.future_window = 5;
  o.max_request_rounds = 3;
  o.request_interval_us = 200 * kMs;
  Gossip g(o, 0);
  g.tick(0);
  g.on_round(kMs, 1, make_packet(1, 0));
  g.on_round(kMs, 1, make_packet(1, 2));
  ASSERT_EQ(g.screen_envelope(kMs, 2, 1), Screen::accept);
  g.on_summary(kMs, Summary{2, {{1, 10, 0}}});  // drone 2 holds 10 rounds of drone 1
  auto req = of_kind(g.tick(2 * kMs), Outgoing::Kind::request);
  ASSERT_EQ(req.size(), 1u);
  EXPECT_EQ(req[0].request.requester, 0);
  EXPECT_EQ(req[0].request.origin, 1);
  EXPECT_EQ(req[0].request.rounds, (std::vector<int>{1, 3, 4}));  // missing, ≤ 3 per request, < 1 + 5
  EXPECT_TRUE(of_kind(g.tick(100 * kMs), Outgoing::Kind::request).empty());  // not yet
  req = of_kind(g.tick(202 * kMs), Outgoing::Kind::request);
  ASSERT_EQ(req.size(), 1u);  // retried
  g.on_round(210 * kMs, 2, make_packet(1, 1));
  g.on_round(210 * kMs, 2, make_packet(1, 3));
  req = of_kind(g.tick(402 * kMs), Outgoing::Kind::request);
  ASSERT_EQ(req.size(), 1u);
  EXPECT_EQ(req[0].request.rounds, (std::vector<int>{4, 5, 6}));  // window moved: 4 held → < 9
  EXPECT_EQ(g.counters().requests_sent, 3);
  // A silent peer's summary no longer drives requests.
  EXPECT_TRUE(of_kind(g.tick(402 * kMs + o.silence_timeout_us + kMs), Outgoing::Kind::request).empty());
}

TEST(GossipExchange, OriginAnswersAtOnceOthersAfterTheirSlotAndAreSuppressed) {
  Options o = base_options(5);
  o.answer_slot_us = 10 * kMs;
  o.request_interval_us = 200 * kMs;
  Gossip origin(o, 0);
  origin.add_own_packet(0, make_packet(5, 0));
  origin.tick(0);
  origin.screen_envelope(kMs, 1, 1);
  origin.on_request(kMs, Request{1, 5, {0}});
  // Just sent (own broadcast at t = 0): not again within request_interval / 2.
  EXPECT_TRUE(of_kind(origin.tick(2 * kMs), Outgoing::Kind::round).empty());
  origin.on_request(150 * kMs, Request{1, 5, {0}});
  auto rounds = of_kind(origin.tick(150 * kMs), Outgoing::Kind::round);
  ASSERT_EQ(rounds.size(), 1u);
  EXPECT_TRUE(rounds[0].answer);
  EXPECT_EQ(packet_digest(rounds[0].packet), packet_digest(make_packet(5, 0)));

  // Holders other than the origin: members 1 (requester), 2, 3, 4, 5 (origin) are live.
  Options h = base_options(3);
  h.answer_slot_us = 10 * kMs;
  Gossip holder(h, 0);
  for (int id : {1, 2, 4, 5}) holder.screen_envelope(kMs, id, 1);
  holder.on_round(kMs, 5, make_packet(5, 0));
  holder.tick(kMs);
  holder.on_request(10 * kMs, Request{1, 5, {0}});
  // Order after requester 1: 2, 3, 4 → drone 3 has rank 1 → delay 2 slots.
  EXPECT_TRUE(of_kind(holder.tick(29 * kMs), Outgoing::Kind::round).empty());
  EXPECT_EQ(of_kind(holder.tick(30 * kMs), Outgoing::Kind::round).size(), 1u);
  EXPECT_EQ(holder.counters().answers_sent, 1);
  // Again, but another holder's copy arrives first: suppressed.
  holder.on_request(200 * kMs, Request{1, 5, {0}});
  holder.on_round(205 * kMs, 2, make_packet(5, 0));
  EXPECT_TRUE(of_kind(holder.tick(300 * kMs), Outgoing::Kind::round).empty());
  EXPECT_EQ(holder.counters().answers_suppressed, 1);
  EXPECT_EQ(holder.counters().answers_sent, 1);
}

// --------------------------------------------------------------------------------------------
// Membership and completion

TEST(GossipMembership, CompletionWaitsForLiveMembersAndSilentOnesStopBlocking) {
  Options o = base_options(0);
  o.silence_timeout_us = 2 * kS;
  o.min_members = 2;
  Gossip g(o, 0);
  for (int r = 0; r < 3; ++r) g.add_own_packet(0, make_packet(0, r));
  g.screen_envelope(10 * kMs, 1, 1);
  g.screen_envelope(10 * kMs, 2, 1);
  for (int r = 0; r < 3; ++r) g.on_round(10 * kMs, 1, make_packet(1, r));
  g.on_round(10 * kMs, 2, make_packet(2, 0));
  Completion c = g.completion(20 * kMs);
  EXPECT_TRUE(c.ready);
  EXPECT_EQ(c.rounds, 1);  // drone 2 holds only round 0
  EXPECT_EQ(c.drones, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(c.live, (std::vector<int>{0, 1, 2}));
  // Drone 1 keeps talking, drone 2 falls silent.
  g.screen_envelope(1500 * kMs, 1, 2);
  c = g.completion(2 * kS);
  EXPECT_EQ(c.rounds, 1);  // 1.99 s: still live, still blocking
  g.screen_envelope(2500 * kMs, 1, 3);
  const int64_t later = 10 * kMs + 2 * kS + 1;
  c = g.completion(later);
  EXPECT_EQ(c.rounds, 3);
  EXPECT_EQ(c.drones, (std::vector<int>{0, 1}));
  EXPECT_EQ(c.silent, (std::vector<int>{2}));
  g.tick(later);
  EXPECT_EQ(g.counters().members_silenced, 1);
  bool reported = false;
  for (const std::string& e : g.take_events()) reported = reported || e.find("drone 2 silent") != std::string::npos;
  EXPECT_TRUE(reported);
  // Complete data: by drone id, then round.
  auto packets = g.complete_packets(c);
  ASSERT_EQ(packets.size(), 6u);
  for (size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(packets[i]->origin, static_cast<int>(i / 3));
    EXPECT_EQ(packets[i]->round, static_cast<int>(i % 3));
  }
  // Drone 2 comes back: it is live (and blocking) again.
  g.screen_envelope(later + kS, 2, 2);
  EXPECT_EQ(g.completion(later + kS).rounds, 1);
}

TEST(GossipMembership, RosterMembersBlockUntilHeardOrTimedOut) {
  Options o = base_options(0);
  o.roster = {0, 1, 2};
  o.silence_timeout_us = 3 * kS;
  Gossip g(o, 0);
  g.add_own_packet(0, make_packet(0, 0));
  g.screen_envelope(kMs, 1, 1);
  g.on_round(kMs, 1, make_packet(1, 0));
  EXPECT_EQ(g.completion(kS).rounds, 0);  // drone 2 (roster) not heard, start + timeout not passed
  EXPECT_EQ(g.completion(3 * kS).rounds, 0);
  const Completion c = g.completion(3 * kS + 1);  // drone 2 silent since start: no longer blocks
  EXPECT_EQ(c.rounds, 1);
  EXPECT_EQ(c.drones, (std::vector<int>{0, 1}));
  EXPECT_EQ(c.silent, (std::vector<int>{2}));
}

TEST(GossipMembership, NothingIsCompleteBeforeSettlingOrWithTooFewMembers) {
  Options o = base_options(0);
  o.settle_us = kS;
  o.min_members = 2;
  Gossip g(o, 0);
  g.add_own_packet(0, make_packet(0, 0));
  EXPECT_FALSE(g.completion(2 * kS).ready);  // alone
  g.screen_envelope(kMs, 1, 1);
  g.on_round(kMs, 1, make_packet(1, 0));
  EXPECT_FALSE(g.completion(500 * kMs).ready);  // not settled
  EXPECT_TRUE(g.completion(kS).ready);
  EXPECT_TRUE(g.complete_packets(g.completion(500 * kMs)).empty());
}

// --------------------------------------------------------------------------------------------
// Bounded memory

TEST(GossipMemory, IdsAndRoundsStayWithinTheCaps) {
  Options o = base_options(0);
  o.max_origins = 6;
  o.max_rounds = 5;
  o.future_window = 100;
  o.silence_timeout_us = kS;
  Gossip g(o, 0);
  // Many ids talk once (no rounds): the table never exceeds the cap; silent ones are replaced.
  int64_t t = kMs;
  for (int id = 1; id <= 200; ++id, t += 100 * kMs) {
    g.screen_envelope(t, id, 1);
    g.on_summary(t, Summary{id, {{id, 1, 0}}});
    EXPECT_LE(g.tracked_ids(), 6u);
  }
  // Ids holding rounds are kept; once the table is full of them, new ids are refused.
  Gossip h(o, 0);
  for (int id = 1; id <= 20; ++id)
    for (int r = 0; r < 50; ++r) h.on_round(kMs, id, make_packet(id, r));
  EXPECT_EQ(h.tracked_ids(), 6u);
  EXPECT_EQ(h.stored_packets(), 5u * 5u);  // ids 1 … 5 (self holds none), rounds 0 … 4
  EXPECT_EQ(h.counters().rejected_round_cap, 20 * 45);
  EXPECT_EQ(h.counters().rejected_origin_cap, 15 * 5);
  for (int id = 1; id <= 5; ++id) EXPECT_EQ(h.rounds_held(id), 5);
  // Requests and summaries from a flood do not grow anything either.
  for (int k = 0; k < 1000; ++k) h.on_request(kMs, Request{1 + k % 5, 2, {k % 5}});
  EXPECT_EQ(h.tracked_ids(), 6u);
  EXPECT_EQ(h.stored_packets(), 25u);
}

// --------------------------------------------------------------------------------------------
// A simulated swarm: N gossips over a multicast network with loss, duplication, reordering.

class SimSwarm {
 public:
  SimSwarm(std::vector<int> ids, Options base, double loss, double dup, double reorder, uint64_t seed)
      : ids_(std::move(ids)), base_(base), loss_(loss), dup_(dup), reorder_(reorder), rng_(seed) {
    for (int id : ids_) start(id);
  }

  void start(int id) {
    Options o = base_;
    o.self_id = id;
    nodes_[id] = std::make_unique<Gossip>(o, now_);
    seq_[id] = 1700000000000000 + now_;  // as fact-gossip: the start time in µs
  }
  void stop(int id) { nodes_.erase(id); }
  Gossip& at(int id) { return *nodes_.at(id); }
  bool running(int id) const { return nodes_.count(id) > 0; }
  int64_t now() const { return now_; }
  int64_t sent_bytes() const { return sent_; }

  void run_until(int64_t t) {
    while (now_ < t) step();
  }
  // Steps until every running node's completion has `rounds` rounds of `drones`.
  bool run_until_complete(int rounds, const std::vector<int>& drones, int64_t limit) {
    while (now_ < limit) {
      step();
      bool all = true;
      for (auto& [id, g] : nodes_) {
        Completion c = g->completion(now_);
        all = all && c.ready && c.rounds == rounds && c.drones == drones;
      }
      if (all) return true;
    }
    return false;
  }

 private:
  struct Flight {
    int from;
    int64_t seq;
    Outgoing msg;
  };
  double uniform() {
    rng_ ^= rng_ << 13;
    rng_ ^= rng_ >> 7;
    rng_ ^= rng_ << 17;
    return static_cast<double>(rng_ >> 11) * 0x1.0p-53;
  }
  void step() {
    now_ += kMs;
    // Deliver what is due.
    while (!flight_.empty() && flight_.begin()->first.first <= now_) {
      auto [key, f] = *flight_.begin();
      flight_.erase(flight_.begin());
      const int to = key.second;
      auto it = nodes_.find(to);
      if (it == nodes_.end()) continue;
      Gossip& g = *it->second;
      if (g.screen_envelope(now_, f.from, f.seq) != Screen::accept) continue;
      switch (f.msg.kind) {
        case Outgoing::Kind::round: g.on_round(now_, f.from, f.msg.packet); break;
        case Outgoing::Kind::summary: g.on_summary(now_, f.msg.summary); break;
        case Outgoing::Kind::request: g.on_request(now_, f.msg.request); break;
      }
    }
    // Send.
    for (auto& [id, g] : nodes_) {
      for (Outgoing& out : g->tick(now_)) {
        const int64_t seq = seq_[id]++;
        sent_ += out.kind == Outgoing::Kind::round ? 500 : 200;
        for (int to : ids_) {
          if (to == id) continue;
          if (uniform() < loss_) continue;
          int64_t delay = 1 * kMs + (uniform() < reorder_ ? static_cast<int64_t>(uniform() * 30 * kMs) : 0);
          flight_.insert({{now_ + delay, to}, Flight{id, seq, out}});
          if (uniform() < dup_) flight_.insert({{now_ + delay + 3 * kMs, to}, Flight{id, seq, out}});
        }
      }
    }
  }

  std::vector<int> ids_;
  Options base_;
  double loss_, dup_, reorder_;
  uint64_t rng_;
  int64_t now_ = 0;
  int64_t sent_ = 0;
  std::map<int, std::unique_ptr<Gossip>> nodes_;
  std::map<int, int64_t> seq_;
  std::multimap<std::pair<int64_t, int>, Flight> flight_;
};

Options swarm_options() {
  Options o;
  o.summary_period_us = kS;
  o.summary_min_interval_us = 100 * kMs;
  o.silence_timeout_us = 5 * kS;
  o.request_interval_us = 200 * kMs;
  o.settle_us = 500 * kMs;
  o.min_members = 2;
  return o;
}

// Every node's complete data, as digests in order, must be the same.
void expect_identical(SimSwarm& s, const std::vector<int>& ids, int rounds) {
  std::vector<uint64_t> reference;
  for (int id : ids) {
    Gossip& g = s.at(id);
    Completion c = g.completion(s.now());
    std::vector<uint64_t> digests;
    for (const Packet* p : g.complete_packets(c)) digests.push_back(packet_digest(*p));
    EXPECT_EQ(digests.size(), ids.size() * static_cast<size_t>(rounds)) << "drone " << id;
    if (reference.empty()) reference = digests;
    EXPECT_EQ(digests, reference) << "drone " << id;
    for (int o : ids) EXPECT_EQ(g.digest(o), s.at(ids[0]).digest(o)) << "drone " << id << " origin " << o;
  }
  // And the content is what the origins made.
  for (int o : ids)
    for (int r = 0; r < rounds; ++r) EXPECT_EQ(packet_digest(*s.at(ids[0]).packet(o, r)), packet_digest(make_packet(o, r)));
}

TEST(GossipSwarm, EightDronesConvergeWithoutLoss) {
  const std::vector<int> ids{0, 1, 2, 3, 4, 5, 6, 7};
  SimSwarm s(ids, swarm_options(), 0, 0, 0, 1);
  s.run_until(600 * kMs);
  for (int id : ids) s.at(id).add_own_packet(s.now(), make_packet(id, 0));
  ASSERT_TRUE(s.run_until_complete(1, ids, s.now() + 100 * kMs));
  expect_identical(s, ids, 1);
}

TEST(GossipSwarm, LossDuplicationAndReorderingLoseNoRound) {
  const std::vector<int> ids{0, 1, 2, 3, 4, 5};
  SimSwarm s(ids, swarm_options(), 0.2, 0.1, 0.3, 42);
  s.run_until(600 * kMs);
  for (int r = 0; r < 5; ++r) {
    for (int id : ids) s.at(id).add_own_packet(s.now(), make_packet(id, r));
    s.run_until(s.now() + 300 * kMs);
  }
  ASSERT_TRUE(s.run_until_complete(5, ids, s.now() + 5 * kS));
  expect_identical(s, ids, 5);
  int64_t duplicates = 0, requests = 0;
  for (int id : ids) {
    duplicates += s.at(id).counters().duplicate_envelopes;
    requests += s.at(id).counters().requests_sent;
  }
  EXPECT_GT(duplicates, 0);
  EXPECT_GT(requests, 0);
}

TEST(GossipSwarm, ARestartedGossipRecoversEverythingFromItsPeers) {
  const std::vector<int> ids{0, 1, 2, 3, 4};
  SimSwarm s(ids, swarm_options(), 0.2, 0.1, 0.3, 7);
  s.run_until(600 * kMs);
  for (int r = 0; r < 3; ++r) {
    for (int id : ids) s.at(id).add_own_packet(s.now(), make_packet(id, r));
    s.run_until(s.now() + 200 * kMs);
  }
  ASSERT_TRUE(s.run_until_complete(3, ids, s.now() + 5 * kS));
  s.stop(2);
  s.run_until(s.now() + 500 * kMs);
  s.start(2);  // empty: everything, its own rounds included, comes from the peers
  EXPECT_EQ(s.at(2).stored_packets(), 0u);
  ASSERT_TRUE(s.run_until_complete(3, ids, s.now() + 5 * kS));
  expect_identical(s, ids, 3);
  EXPECT_GT(s.at(2).counters().requests_sent, 0);
  // It continues its own numbering after the recovered rounds (round 3, not 0).
  DroneRound next = make_packet(2, 3).data;
  EXPECT_EQ(s.at(2).add_own_round(s.now(), make_packet(2, 3).utime, next), "");
  EXPECT_NE(s.at(2).packet(2, 3), nullptr);
  EXPECT_EQ(packet_digest(*s.at(2).packet(2, 3)), packet_digest(make_packet(2, 3)));
}

TEST(GossipSwarm, OwnRoundsClosedBeforeSettlingAreNumberedAfterThePeersRounds) {
  const std::vector<int> ids{0, 1, 2};
  Options o = swarm_options();
  o.settle_us = 1500 * kMs;
  SimSwarm s(ids, o, 0, 0, 0, 3);
  s.run_until(1600 * kMs);
  for (int r = 0; r < 2; ++r)
    for (int id : ids) s.at(id).add_own_round(s.now(), make_packet(id, r).utime, make_packet(id, r).data);
  ASSERT_TRUE(s.run_until_complete(2, ids, s.now() + 2 * kS));
  s.stop(1);
  s.run_until(s.now() + 300 * kMs);
  s.start(1);
  // Round closed right after the restart, before settling: it must become round 2, not 0.
  EXPECT_EQ(s.at(1).add_own_round(s.now(), make_packet(1, 2).utime, make_packet(1, 2).data), "");
  EXPECT_EQ(s.at(1).stored_packets(), 0u);  // queued
  for (int id : {0, 2}) s.at(id).add_own_round(s.now(), make_packet(id, 2).utime, make_packet(id, 2).data);
  ASSERT_TRUE(s.run_until_complete(3, ids, s.now() + 5 * kS));
  expect_identical(s, ids, 3);
  EXPECT_EQ(s.at(0).counters().own_round_conflicts + s.at(0).counters().digest_mismatches, 0);
}

// --------------------------------------------------------------------------------------------
// Round building

struct SpinScenario {
  // Odometry at 100 Hz: hover 2 s (yaw 0), then spin at 1 rad/s; position moves along x at 0.1 m/s.
  static Eigen::Vector3d position(double t) { return Eigen::Vector3d(0.1 * t, -0.2, 1.5); }
  static double yaw(double t) { return t < 2 ? 0.0 : t - 2; }
};

int64_t at_s(double t) { return static_cast<int64_t>(std::llround(t * 1e6)); }

TEST(RoundBuilder, ASpinMakesOneRoundWithTheMostCentralDetectionPerTrack) {
  BuilderOptions bo;
  bo.latency_us = 300 * kMs;
  RoundBuilder b(bo);
  std::vector<BuiltRound> rounds;
  int i = 0;
  const auto feed_until = [&](double t_end) {
    for (; i * 0.01 <= t_end + 1e-9; ++i) {
      const double t = i * 0.01;
      EXPECT_EQ(b.add_odometry(at_s(t), SpinScenario::position(t), SpinScenario::yaw(t)), "");
      for (auto& r : b.take_rounds()) rounds.push_back(r);
    }
  };
  feed_until(1.0);
  EXPECT_EQ(b.add_detection(at_s(1.0), 5, Eigen::Vector3d(3, 0, 0)), "");  // hover: before the spin
  feed_until(3.5);
  EXPECT_EQ(b.add_detection(at_s(3.005), 5, Eigen::Vector3d(3, 0.3, 0.1)), "");   // bearing 0.0997
  EXPECT_EQ(b.add_detection(at_s(3.2), 5, Eigen::Vector3d(3, -0.1, 0.1)), "");    // bearing 0.0333: best
  EXPECT_EQ(b.add_detection(at_s(3.3), 5, Eigen::Vector3d(3, 0.5, 0.0)), "");
  EXPECT_EQ(b.add_detection(at_s(3.4), 9, Eigen::Vector3d(-1, 2, 0.0)), "");
  feed_until(8.45);
  EXPECT_TRUE(rounds.empty());  // spun at 8.29 s, waiting for late detections until 8.59 s
  EXPECT_EQ(b.add_detection(at_s(8.0), 7, Eigen::Vector3d(2, 0.01, 0.0)), "");  // late but in time
  feed_until(8.6);
  ASSERT_EQ(rounds.size(), 1u);
  const BuiltRound& r = rounds[0];
  // yaw(8.29) − 2π = 0.0068147 rad → t0 = 2.0068147 s (1 µs resolution).
  const double t0 = 2.0 + (6.29 - 2 * M_PI);
  EXPECT_NEAR(r.start_utime, at_s(t0), 2);
  EXPECT_EQ(r.end_utime, at_s(8.29));
  EXPECT_NEAR(r.data.position.x(), 0.1 * t0, 1e-6);
  EXPECT_NEAR(r.data.yaw, t0 - 2, 1e-6);
  ASSERT_EQ(r.data.observations.size(), 3u);  // tracks 5, 7, 9 in that order; not the hover one
  EXPECT_EQ(r.data.observations[0].vector, Eigen::Vector3d(3, -0.1, 0.1));
  EXPECT_NEAR(r.data.observations[0].odom_position.x(), 0.1 * 3.2, 1e-9);
  EXPECT_NEAR(r.data.observations[0].odom_yaw, 1.2, 1e-9);
  EXPECT_EQ(r.data.observations[1].vector, Eigen::Vector3d(2, 0.01, 0.0));
  EXPECT_NEAR(r.data.observations[1].odom_yaw, 6.0 - 2 * M_PI, 1e-9);  // wrapped to (−π, π]
  EXPECT_EQ(r.data.observations[2].vector, Eigen::Vector3d(-1, 2, 0.0));
  EXPECT_NEAR(r.data.observations[2].odom_position.x(), 0.34, 1e-9);
  EXPECT_EQ(b.counters().rounds, 1);
}

// Spin 6.5 rad at A, fly 2 m to B in 2 s while turning 1 rad, spin at B: the second round is
// the turn in place at B only. Without the speed rule it would close 1.2 s earlier and span the
// move, with its start (the round's position) at A.
TEST(RoundBuilder, AMoveRestartsTheOpenRoundSoARoundIsATurnInPlace) {
  const auto position = [](double t) {
    const double f = std::clamp((t - 6.5) / 2.0, 0.0, 1.0);
    return Eigen::Vector3d(1.0, 2.0 * f, 1.5);
  };
  const auto yaw = [](double t) { return t < 6.5 ? t : t < 8.5 ? 6.5 + 0.5 * (t - 6.5) : 7.5 + (t - 8.5); };
  RoundBuilder b;
  std::vector<BuiltRound> rounds;
  for (int i = 0; i * 0.01 <= 16.0 + 1e-9; ++i) {
    const double t = i * 0.01;
    ASSERT_EQ(b.add_odometry(at_s(t), position(t), yaw(t)), "");
    if (std::abs(t - 7.5) < 1e-9) {
      EXPECT_EQ(b.add_detection(at_s(7.5), 3, Eigen::Vector3d(3, 0, 0)), "");  // while moving
    }
    if (std::abs(t - 10.0) < 1e-9) {
      EXPECT_EQ(b.add_detection(at_s(10.0), 3, Eigen::Vector3d(3, 0.2, 0)), "");
    }
    for (auto& r : b.take_rounds()) rounds.push_back(r);
  }
  ASSERT_EQ(rounds.size(), 2u);
  const BuiltRound& r = rounds[1];
  EXPECT_GE(r.start_utime, at_s(8.5));   // after the move
  EXPECT_NEAR(r.end_utime, at_s(8.5 + 2 * M_PI), 0.2 * kS);
  EXPECT_NEAR(r.data.position.y(), 2.0, 0.01);  // at B
  ASSERT_EQ(r.data.observations.size(), 1u);
  EXPECT_EQ(r.data.observations[0].vector, Eigen::Vector3d(3, 0.2, 0));
  EXPECT_NEAR(r.data.observations[0].odom_position.y(), 2.0, 1e-9);
  EXPECT_EQ(b.counters().moves, 1);

  BuilderOptions off;
  off.max_speed = 0;  // the rule off: the round spans the move
  RoundBuilder plain(off);
  std::vector<BuiltRound> spans;
  for (int i = 0; i * 0.01 <= 16.0 + 1e-9; ++i) {
    plain.add_odometry(at_s(i * 0.01), position(i * 0.01), yaw(i * 0.01));
    for (auto& x : plain.take_rounds()) spans.push_back(x);
  }
  ASSERT_EQ(spans.size(), 2u);
  EXPECT_LT(spans[1].start_utime, at_s(6.5));
  EXPECT_EQ(plain.counters().moves, 0);
}

TEST(RoundBuilder, DetectionsAreInterpolatedBetweenOdometrySamples) {
  RoundBuilder b;
  for (int i = 0; i <= 100; ++i) b.add_odometry(at_s(i * 0.1), SpinScenario::position(i * 0.1), 0.05 * i);
  Eigen::Vector3d p;
  double y = 0;
  ASSERT_TRUE(b.odometry_at(at_s(3.025), &p, &y));
  EXPECT_NEAR(p.x(), 0.3025, 1e-12);
  EXPECT_NEAR(y, 0.05 * 30.25, 1e-12);
  EXPECT_FALSE(b.odometry_at(at_s(11.0), &p, &y));
  EXPECT_FALSE(b.odometry_at(-1, &p, &y));
}

// Period mode: back-to-back rounds of 1 s, each closed 100 ms (odometry time) after its end.
BuilderOptions period_mode() {
  BuilderOptions bo;
  bo.round_period_us = kS;
  bo.latency_us = 100 * kMs;
  return bo;
}

TEST(RoundBuilder, PeriodModeAndBadSamples) {
  RoundBuilder b(period_mode());
  std::vector<BuiltRound> rounds;
  for (int i = 0; i <= 305; ++i) {
    const double t = 10 + i * 0.01;
    b.add_odometry(at_s(t), SpinScenario::position(t), 0.0);  // no spin at all
    if (i == 50) {
      EXPECT_EQ(b.add_detection(at_s(t), 1, Eigen::Vector3d(1, 0, 0)), "");
    }
    if (i == 150) {
      EXPECT_EQ(b.add_detection(at_s(t), 1, Eigen::Vector3d(1, 1, 0)), "");
    }
    for (auto& r : b.take_rounds()) rounds.push_back(r);
  }
  ASSERT_EQ(rounds.size(), 2u);  // [10, 11), [11, 12); [12, 13) needs odometry to 13.1 s
  EXPECT_EQ(rounds[0].start_utime, at_s(10));
  EXPECT_EQ(rounds[1].start_utime, at_s(11));
  EXPECT_EQ(rounds[1].end_utime, at_s(12));
  ASSERT_EQ(rounds[0].data.observations.size(), 1u);
  ASSERT_EQ(rounds[1].data.observations.size(), 1u);
  EXPECT_EQ(rounds[1].data.observations[0].vector, Eigen::Vector3d(1, 1, 0));
  // Refused samples are counted.
  EXPECT_NE(b.add_odometry(at_s(12), SpinScenario::position(12), 0.0), "");  // not after the last
  EXPECT_NE(b.add_odometry(at_s(20), Eigen::Vector3d(std::nan(""), 0, 0), 0.0), "");
  EXPECT_NE(b.add_detection(at_s(13.4), 2, Eigen::Vector3d(0, 0, 0)), "");
  EXPECT_NE(b.add_detection(at_s(13.4), 2, Eigen::Vector3d(std::nan(""), 0, 0)), "");
  EXPECT_NE(b.add_detection(at_s(10.5), 2, Eigen::Vector3d(1, 0, 0)), "");  // older than the open round
  EXPECT_EQ(b.counters().rejected_odometry, 2);
  EXPECT_EQ(b.counters().rejected_detections, 2);
  EXPECT_EQ(b.counters().late_detections, 1);
}

// Period mode across a gap in the odometry: the period the gap interrupted closes with its data,
// the empty periods inside the gap are skipped, not closed one by one (one sample 1.7e9 s late
// made 1.7e9 empty rounds and ran out of memory), and the period boundaries stay where they were.
TEST(RoundBuilder, PeriodModeRestartsThePeriodAfterAGap) {
  RoundBuilder b(period_mode());
  std::vector<BuiltRound> rounds;
  const auto feed = [&](double from_s, int samples) {
    for (int i = 0; i < samples; ++i) {
      const double t = from_s + i * 0.01;
      EXPECT_EQ(b.add_odometry(at_s(t), SpinScenario::position(10), 0.0), "") << t;
      for (auto& r : b.take_rounds()) rounds.push_back(r);
    }
  };
  feed(10, 160);  // 10 … 11.59 s: [10, 11) closes
  EXPECT_EQ(b.add_detection(at_s(11.5), 1, Eigen::Vector3d(1, 0, 0)), "");
  // 1.7e6 s (19 days) later, to + 1.99 s: [11, 12) closes with its detection, [1.7e6, 1.7e6 + 1)
  // closes, the next needs + 2.1 s.
  feed(1.7e6 + 0.25, 175);
  ASSERT_EQ(rounds.size(), 3u);
  EXPECT_EQ(rounds[0].start_utime, at_s(10));
  EXPECT_EQ(rounds[1].start_utime, at_s(11));
  EXPECT_EQ(rounds[1].end_utime, at_s(12));
  EXPECT_EQ(rounds[1].data.observations.size(), 1u);
  EXPECT_EQ(rounds[2].start_utime, at_s(1.7e6));
  EXPECT_EQ(rounds[2].end_utime, at_s(1.7e6 + 1));
  EXPECT_EQ(b.counters().odometry_gaps, 1);
  EXPECT_EQ(b.counters().rounds, 3);
}

// restart(): the odometry's clock went back (a VIO reset); the builder takes the new clock's
// samples and builds rounds again, with its counters kept.
TEST(RoundBuilder, RestartTakesANewClock) {
  RoundBuilder b(period_mode());
  for (int i = 0; i < 120; ++i) b.add_odometry(at_s(100 + i * 0.01), SpinScenario::position(100), 0.0);
  EXPECT_EQ(b.take_rounds().size(), 1u);
  EXPECT_NE(b.add_odometry(at_s(5), SpinScenario::position(5), 0.0), "");  // earlier: refused
  b.restart();
  for (int i = 0; i < 120; ++i) EXPECT_EQ(b.add_odometry(at_s(5 + i * 0.01), SpinScenario::position(5), 0.0), "");
  const std::vector<BuiltRound> after = b.take_rounds();
  ASSERT_EQ(after.size(), 1u);
  EXPECT_EQ(after[0].start_utime, at_s(5));
  EXPECT_EQ(b.counters().restarts, 1);
  EXPECT_EQ(b.counters().rejected_odometry, 1);
  EXPECT_EQ(b.counters().rounds, 2);
}

TEST(RoundBuilder, HistoryIsBoundedWhileNoRoundCloses) {
  BuilderOptions bo;
  bo.max_odometry = 1000;
  bo.max_detections = 50;
  RoundBuilder b(bo);
  for (int i = 0; i < 5000; ++i) {
    b.add_odometry(at_s(i * 0.01), Eigen::Vector3d::Zero(), 0.0);
    b.add_detection(at_s(i * 0.01), i % 3, Eigen::Vector3d(1, 0, 0));
  }
  EXPECT_GT(b.counters().dropped_history, 0);
  // Then a spin still makes a round from what is kept.
  int64_t t = at_s(50.0);
  std::vector<BuiltRound> rounds;
  for (int i = 0; i < 800; ++i, t += 10 * kMs) {
    b.add_odometry(t, Eigen::Vector3d::Zero(), 0.01 * i);
    for (auto& r : b.take_rounds()) rounds.push_back(r);
  }
  EXPECT_EQ(rounds.size(), 1u);
}

}  // namespace
}  // namespace fact::gossip

// --------------------------------------------------------------------------------------------
// Wire: key files, envelope authentication, conversions

namespace fact::app {
namespace {

SwarmKey key_of(unsigned char fill) {
  std::string raw(32, static_cast<char>(fill));
  SwarmKey k;
  EXPECT_EQ(parse_key(raw, &k), "");
  return k;
}

TEST(GossipWire, KeyFilesRawOrHex) {
  ASSERT_EQ(init_crypto(), "");
  SwarmKey k;
  EXPECT_EQ(parse_key(std::string(32, 'k'), &k), "");
  EXPECT_FALSE(k.insecure);
  EXPECT_EQ(k.bytes[31], 'k');
  std::string hex = "00112233445566778899aabbccddeeff\n00112233445566778899AABBCCDDEEFF\n";
  EXPECT_EQ(parse_key(hex, &k), "");
  EXPECT_EQ(k.bytes[1], 0x11);
  EXPECT_EQ(k.bytes[31], 0xff);
  EXPECT_NE(parse_key("0011", &k), "");
  EXPECT_NE(parse_key(std::string(64, 'g'), &k), "");
  EXPECT_NE(parse_key(std::string(64, '0'), &k), "");  // all zero
  EXPECT_NE(parse_key(std::string(32, '\0'), &k), "");
  EXPECT_NE(load_key("/nonexistent/swarm.key", &k), "");
}

// --session: the key of a session authenticates that session's envelopes only, so a recording of
// an earlier flight (same swarm key, another session) fails authentication.
TEST(GossipWire, SessionsDeriveDistinctKeys) {
  ASSERT_EQ(init_crypto(), "");
  SwarmKey a = key_of(7), b = key_of(7), same = key_of(7);
  ASSERT_EQ(apply_session("flight-2026-11-27.1", &a), "");
  ASSERT_EQ(apply_session("flight-2026-11-27.2", &b), "");
  ASSERT_EQ(apply_session("flight-2026-11-27.1", &same), "");
  EXPECT_EQ(a.bytes, same.bytes);
  EXPECT_NE(a.bytes, b.bytes);
  EXPECT_NE(a.bytes, key_of(7).bytes);
  const gossip_packet_t m = make_envelope(3, 1700000000000001, gossip_packet_t::SUMMARY, {1, 2, 3, 4}, 55, a);
  EXPECT_TRUE(verify(m, same));
  EXPECT_FALSE(verify(m, b));
  EXPECT_FALSE(verify(m, key_of(7)));  // nor without a session
  SwarmKey k = key_of(7);
  EXPECT_NE(apply_session("", &k).find("0 characters"), std::string::npos);
  EXPECT_NE(apply_session(std::string(65, 'x'), &k).find("65 characters"), std::string::npos);
  EXPECT_NE(apply_session("two words", &k).find("' '"), std::string::npos);
  EXPECT_EQ(k.bytes, key_of(7).bytes);  // refused names leave the key as it was
  SwarmKey none;  // insecure
  EXPECT_NE(apply_session("x", &none).find("--insecure"), std::string::npos);
}

TEST(GossipWire, EnvelopesAuthenticateAndAlterationsFail) {
  ASSERT_EQ(init_crypto(), "");
  const SwarmKey key = key_of(7), other = key_of(8);
  gossip_packet_t m = make_envelope(3, 1700000000000001, gossip_packet_t::SUMMARY, {1, 2, 3, 4}, 55, key);
  EXPECT_EQ(m.payload_size, 4);
  EXPECT_TRUE(verify(m, key));
  EXPECT_FALSE(verify(m, other));  // wrong swarm key
  for (int field = 0; field < 5; ++field) {
    gossip_packet_t t = m;
    if (field == 0) t.kind = gossip_packet_t::ROUND;
    if (field == 1) t.sender_id = 4;
    if (field == 2) t.seq += 1;
    if (field == 3) t.payload[2] ^= 1;
    if (field == 4) t.mac[0] ^= 1;
    EXPECT_FALSE(verify(t, key)) << "field " << field;
  }
  gossip_packet_t u = m;
  u.utime = 99;  // not covered: informative only
  EXPECT_TRUE(verify(u, key));
  // Insecure: zero mac, nothing checked; a keyed receiver refuses it.
  const SwarmKey none;
  gossip_packet_t z = make_envelope(3, 5, gossip_packet_t::SUMMARY, {1}, 0, none);
  for (unsigned char b : z.mac) EXPECT_EQ(b, 0);
  EXPECT_TRUE(verify(z, none));
  EXPECT_FALSE(verify(z, key));
  // The MAC input layout: kind | sender (BE) | seq (BE) | payload.
  const auto in = mac_input(m);
  ASSERT_EQ(in.size(), 13u + 4u);
  EXPECT_EQ(in[0], static_cast<unsigned char>(gossip_packet_t::SUMMARY));
  EXPECT_EQ(in[4], 3);
  EXPECT_EQ(in[12], static_cast<unsigned char>(m.seq & 0xff));
  EXPECT_EQ(in[13], 1);
}

TEST(GossipWire, ConversionsRoundTripAndCheckCounts) {
  gossip::Packet p = gossip::make_packet(4, 2);
  gossip::Packet back;
  const round_packet_t m = packet_to_message(p);
  ASSERT_EQ(packet_from_message(m, &back), "");
  EXPECT_EQ(gossip::packet_digest(back), gossip::packet_digest(p));
  // Through the bytes as well.
  round_packet_t decoded;
  const auto bytes = encode_bytes(m);
  ASSERT_EQ(decoded.decode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  ASSERT_EQ(packet_from_message(decoded, &back), "");
  EXPECT_EQ(gossip::packet_digest(back), gossip::packet_digest(p));
  round_packet_t bad = m;
  bad.observations[0].odom_yaw = std::nan("");
  EXPECT_NE(packet_from_message(bad, &back), "");

  gossip::Summary s{2, {{0, 3, 0xfedcba9876543210ull}, {5, 1, 1}}};
  gossip::Summary s2;
  ASSERT_EQ(summary_from_message(summary_to_message(s, 1), &s2), "");
  ASSERT_EQ(s2.entries.size(), 2u);
  EXPECT_EQ(s2.entries[0].digest, 0xfedcba9876543210ull);
  gossip_summary_t sm = summary_to_message(s, 1);
  sm.count = 3;
  EXPECT_NE(summary_from_message(sm, &s2), "");

  gossip::Request r{1, 4, {2, 3}};
  gossip::Request r2;
  ASSERT_EQ(request_from_message(request_to_message(r, 1), &r2), "");
  EXPECT_EQ(r2.rounds, r.rounds);
  gossip_request_t rm = request_to_message(r, 1);
  rm.count = -1;
  EXPECT_NE(request_from_message(rm, &r2), "");
}

}  // namespace
}  // namespace fact::app
