// apps/common (fact_app_common): every fact LCM type through a real lcm::LCM (memq://) and
// fact::app::decode; garbage (truncated, foreign, crafted counts, mutated bytes) rejected and
// counted, never a crash; the status heartbeat as a real app_status_t; the checked conversions.
#include "common/app.h"
#include "common/convert.h"
#include "lcm_samples.h"

#include "fact/estimator.h"
#include "fact/odometry_t.hpp"
#include "fact/setpoint_t.hpp"
#include "fact/simgen.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <limits>
#include <random>
#include <optional>
#include <string>
#include <vector>

namespace app = fact::app;
namespace samples = fact::samples;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

template <class T>
std::vector<uint8_t> encode(const T& m) {
  std::vector<uint8_t> buf(m.getEncodedSize());
  EXPECT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  return buf;
}

// Writes a big-endian int32 at byte offset `at` of an encoding.
void put_i32(std::vector<uint8_t>& b, size_t at, int32_t v) {
  uint32_t u = static_cast<uint32_t>(v);
  for (int i = 0; i < 4; ++i) b.at(at + i) = static_cast<uint8_t>(u >> (24 - 8 * i));
}

// Receives raw buffers on one channel and decodes them as T through fact::app::decode.
template <class T>
struct Receiver {
  Receiver(lcm::LCM& lcm, const std::string& channel, app::Status* status)
      : channel(channel), status(status), log("fact_lcm_tests", 0) {
    sub = lcm.subscribe(channel, &Receiver::on, this);
  }
  void on(const lcm::ReceiveBuffer* rbuf, const std::string& ch) {
    ++received;
    T m;
    if (app::decode(rbuf, ch, &m, status, log)) decoded.push_back(m);
  }
  std::string channel;
  app::Status* status;
  app::Log log;
  lcm::Subscription* sub = nullptr;
  int received = 0;
  std::vector<T> decoded;
};

// Handles until `count` messages arrived at r (or 2 s pass: a failure, not a hang).
template <class R>
void handle_until(lcm::LCM& lcm, const R& r, int count) {
  for (int i = 0; i < 200 && r.received < count; ++i) lcm.handleTimeout(10);
}

template <class T>
void round_trip(const T& sent, const std::string& channel) {
  SCOPED_TRACE(T::getTypeName());
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  app::Status status(nullptr, "FACT_STATUS", "fact_lcm_tests", 0);
  Receiver<T> r(lcm, channel, &status);
  ASSERT_EQ(lcm.publish(channel, &sent), 0);
  handle_until(lcm, r, 1);
  ASSERT_EQ(r.received, 1);
  ASSERT_EQ(r.decoded.size(), 1u);
  EXPECT_EQ(encode(r.decoded[0]), encode(sent));  // every field, bit for bit
  EXPECT_EQ(status.value("undecodable"), 0);
}

}  // namespace

// ---- every type through memq:// -------------------------------------------------------------

TEST(LcmMessages, EveryTypeRoundTripsThroughMemq) {
  const int64_t t = 1700000000123456;
  round_trip(samples::odometry(t, 3), "FACT_ODOMETRY_3");
  round_trip(samples::setpoint(t, 3), "FACT_SETPOINT_3");
  round_trip(samples::sim_clock(t), "FACT_SIM_CLOCK");
  round_trip(samples::fc_state(t, 3), "FACT_FC_STATE_3");
  round_trip(samples::detections(t, 3), "FACT_DETECTIONS_3");
  round_trip(samples::frame(t, 3), "FACT_FRAMES_3");
  round_trip(samples::gossip_packet(t, 3), "FACT_GOSSIP");
  round_trip(samples::gossip_request(t, 3), "FACT_GOSSIP_REQUEST");
  round_trip(samples::gossip_challenge(t, 3), "FACT_GOSSIP_CHALLENGE");
  round_trip(samples::gossip_summary(t, 3), "FACT_GOSSIP_SUMMARY");
  round_trip(samples::round_packet(t, 3, 2), "FACT_ROUND_PACKET");
  round_trip(samples::swarm_rounds(t, 3), "FACT_SWARM_ROUNDS_3");
  round_trip(samples::swarm_result(t, 3), "FACT_RESULT_3");
  round_trip(samples::app_status(t, 3), "FACT_STATUS");
  round_trip(samples::truth(t), "FACT_TRUTH");
}

TEST(LcmMessages, DecodedFieldsAreTheSentValues) {
  lcm::LCM lcm("memq://");
  app::Status status(nullptr, "FACT_STATUS", "fact_lcm_tests", 0);
  Receiver<fact::odometry_t> odo(lcm, "FACT_ODOMETRY_3", &status);
  Receiver<fact::swarm_rounds_t> rounds(lcm, "FACT_SWARM_ROUNDS_3", &status);
  const fact::odometry_t odo_sent = samples::odometry(42, 3);
  const fact::swarm_rounds_t rounds_sent = samples::swarm_rounds(43, 3);
  lcm.publish("FACT_ODOMETRY_3", &odo_sent);
  lcm.publish("FACT_SWARM_ROUNDS_3", &rounds_sent);
  handle_until(lcm, rounds, 1);
  ASSERT_EQ(odo.decoded.size(), 1u);
  ASSERT_EQ(rounds.decoded.size(), 1u);
  const fact::odometry_t& o = odo.decoded[0];
  EXPECT_EQ(o.utime, 42);
  EXPECT_EQ(o.drone_id, 3);
  EXPECT_EQ(o.seq, 41);
  EXPECT_EQ(o.position[1], -2.5);
  EXPECT_EQ(o.yaw, 3.5);
  const fact::swarm_rounds_t& s = rounds.decoded[0];
  EXPECT_EQ(s.num_packets, 6);
  ASSERT_EQ(s.packets.size(), 6u);
  EXPECT_EQ(s.packets[5].drone_id, 4);
  EXPECT_EQ(s.packets[5].round, 1);
  ASSERT_EQ(s.packets[5].observations.size(), 2u);
  EXPECT_EQ(s.packets[5].observations[1].vector[0], 2.0 + 4 + 1 + 1.5);
}

// ---- bad bytes are rejected and counted ----------------------------------------------------

TEST(LcmDecode, TruncatedAndForeignMessagesAreRejectedAndCounted) {
  lcm::LCM lcm("memq://");
  app::Status status(nullptr, "FACT_STATUS", "fact_lcm_tests", 0);
  Receiver<fact::odometry_t> r(lcm, "FACT_ODOMETRY_3", &status);

  std::vector<uint8_t> good = encode(samples::odometry(1, 3));
  lcm.publish("FACT_ODOMETRY_3", good.data(), static_cast<unsigned>(good.size() - 5));  // truncated
  handle_until(lcm, r, 1);
  EXPECT_EQ(r.received, 1);
  EXPECT_TRUE(r.decoded.empty());
  EXPECT_EQ(status.value("undecodable"), 1);

  const fact::setpoint_t foreign = samples::setpoint(2, 3);
  lcm.publish("FACT_ODOMETRY_3", &foreign);  // a foreign type on our channel
  handle_until(lcm, r, 2);
  EXPECT_EQ(r.received, 2);
  EXPECT_TRUE(r.decoded.empty());
  EXPECT_EQ(status.value("undecodable"), 2);

  lcm.publish("FACT_ODOMETRY_3", good.data(), 3);  // shorter than a fingerprint
  std::vector<uint8_t> longer = good;
  longer.push_back(0);  // trailing garbage
  lcm.publish("FACT_ODOMETRY_3", longer.data(), static_cast<unsigned>(longer.size()));
  lcm.publish("FACT_ODOMETRY_3", good.data(), static_cast<unsigned>(good.size()));  // and a good one
  handle_until(lcm, r, 5);
  EXPECT_EQ(r.received, 5);
  ASSERT_EQ(r.decoded.size(), 1u);
  EXPECT_EQ(r.decoded[0].utime, 1);
  EXPECT_EQ(status.value("undecodable"), 4);
}

TEST(LcmDecode, ReasonsNameTheProblem) {
  fact::odometry_t o;
  std::vector<uint8_t> good = encode(samples::odometry(1, 3));
  EXPECT_EQ(app::decode_error(good.data(), static_cast<int>(good.size()), &o), "");
  EXPECT_NE(app::decode_error(good.data(), 4, &o).find("too short"), std::string::npos);
  EXPECT_NE(app::decode_error(good.data(), static_cast<int>(good.size()) - 1, &o).find("truncated"), std::string::npos);
  std::vector<uint8_t> foreign = encode(samples::setpoint(1, 3));
  EXPECT_NE(app::decode_error(foreign.data(), static_cast<int>(foreign.size()), &o).find("foreign fingerprint"),
            std::string::npos);
  EXPECT_NE(app::decode_error(nullptr, 0, &o).find("too short"), std::string::npos);
}

TEST(LcmDecode, CraftedCountsAreRejectedBeforeAnyAllocation) {
  // The right fingerprint with a count no buffer of this size can hold: lcm-gen's decoder would
  // resize the array to the count first (gigabytes); decode_error refuses before it.
  fact::round_packet_t p;
  std::vector<uint8_t> b = encode(samples::round_packet(1, 3, 0));
  const size_t count_at = 8 + 8 + 4 + 4 + 24 + 8;
  for (int32_t bad : {std::numeric_limits<int32_t>::max(), 3, -1, std::numeric_limits<int32_t>::min()}) {
    std::vector<uint8_t> c = b;
    put_i32(c, count_at, bad);
    EXPECT_NE(app::decode_error(c.data(), static_cast<int>(c.size()), &p), "") << bad;
  }

  fact::gossip_packet_t g;
  std::vector<uint8_t> gb = encode(samples::gossip_packet(1, 3));
  put_i32(gb, 8 + 8 + 4 + 8 + 1, std::numeric_limits<int32_t>::max());  // payload_size
  EXPECT_NE(app::decode_error(gb.data(), static_cast<int>(gb.size()), &g).find("array count"), std::string::npos);

  fact::frame_t f;
  std::vector<uint8_t> fb = encode(samples::frame(1, 3));
  put_i32(fb, 8 + 8 + 4 + 8 + 4 + 4 + 32 + 4 + 32, 2000000000);  // depth_size, after the gray bytes
  EXPECT_NE(app::decode_error(fb.data(), static_cast<int>(fb.size()), &f).find("array count"), std::string::npos);

  // A nested count: the second packet of a swarm_rounds_t claims 2^31 − 1 observations.
  fact::swarm_rounds_t s;
  fact::swarm_rounds_t sent = samples::swarm_rounds(1, 3);
  std::vector<uint8_t> sb = encode(sent);
  const size_t packets_at = 8 + 8 + 4 + 4 + 4 + 4 * 3 + 4;
  const size_t packet_bytes = sent.packets[0]._getEncodedSizeNoHash();
  put_i32(sb, packets_at + packet_bytes + (8 + 4 + 4 + 24 + 8), std::numeric_limits<int32_t>::max());
  EXPECT_NE(app::decode_error(sb.data(), static_cast<int>(sb.size()), &s).find("array count"), std::string::npos);

  // Strings of length 0 or negative in an app_status_t: rejected, not a crash.
  fact::app_status_t a;
  std::vector<uint8_t> ab = encode(samples::app_status(1, 3));
  for (int32_t bad : {0, -7, std::numeric_limits<int32_t>::max()}) {
    std::vector<uint8_t> c = ab;
    put_i32(c, 8 + 8 + 4, bad);  // length of `app`
    EXPECT_NE(app::decode_error(c.data(), static_cast<int>(c.size()), &a), "") << bad;
  }
}

template <class T>
void every_prefix_and_mutation_is_safe(const T& sent) {
  SCOPED_TRACE(T::getTypeName());
  const std::vector<uint8_t> b = encode(sent);
  for (size_t n = 0; n < b.size(); ++n) {  // every truncation is rejected
    T m;
    EXPECT_NE(app::decode_error(b.data(), static_cast<int>(n), &m), "") << n << " of " << b.size();
  }
  std::mt19937 rng(7);
  int accepted = 0;
  for (int trial = 0; trial < 3000; ++trial) {  // random bytes changed after the fingerprint
    std::vector<uint8_t> c = b;
    int changes = 1 + static_cast<int>(rng() % 4);
    for (int k = 0; k < changes; ++k) c[8 + rng() % (c.size() - 8)] = static_cast<uint8_t>(rng());
    T m;
    if (app::decode_error(c.data(), static_cast<int>(c.size()), &m).empty()) {
      ++accepted;
      EXPECT_EQ(m.getEncodedSize(), static_cast<int>(c.size()));  // accepted means exactly those bytes
    }
  }
  EXPECT_GT(accepted, 0);  // most changes hit values, which are legal
}

TEST(LcmDecode, EveryPrefixIsRejectedAndMutatedBytesNeverCrash) {
  const int64_t t = 1700000000000000;
  every_prefix_and_mutation_is_safe(samples::odometry(t, 1));
  every_prefix_and_mutation_is_safe(samples::detections(t, 1));
  every_prefix_and_mutation_is_safe(samples::frame(t, 1));
  every_prefix_and_mutation_is_safe(samples::gossip_packet(t, 1));
  every_prefix_and_mutation_is_safe(samples::gossip_request(t, 1));
  every_prefix_and_mutation_is_safe(samples::gossip_challenge(t, 1));
  every_prefix_and_mutation_is_safe(samples::gossip_summary(t, 1));
  every_prefix_and_mutation_is_safe(samples::round_packet(t, 1, 0));
  every_prefix_and_mutation_is_safe(samples::swarm_rounds(t, 1));
  every_prefix_and_mutation_is_safe(samples::swarm_result(t, 1));
  every_prefix_and_mutation_is_safe(samples::app_status(t, 1));
  every_prefix_and_mutation_is_safe(samples::truth(t));
}

TEST(LcmDecode, FailuresAreLoggedWithChannelAndSize) {
  app::Status status(nullptr, "FACT_STATUS", "fact_lcm_tests", 0);
  app::Log log("fact-test", 2);
  std::vector<uint8_t> b = encode(samples::setpoint(1, 3));
  lcm::ReceiveBuffer rbuf{b.data(), static_cast<uint32_t>(b.size()), 0};
  fact::odometry_t o;
  testing::internal::CaptureStderr();
  EXPECT_FALSE(app::decode(&rbuf, "FACT_ODOMETRY_2", &o, &status, log));
  std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("fact-test[2] undecodable message on FACT_ODOMETRY_2 (" + std::to_string(b.size()) + " bytes"),
            std::string::npos) << err;
  EXPECT_NE(err.find("odometry_t"), std::string::npos) << err;
  EXPECT_EQ(status.value("undecodable"), 1);
}

// ---- status, log, channel, loop -------------------------------------------------------------

TEST(AppStatus, PublishesCountersAsAppStatus) {
  lcm::LCM lcm("memq://");
  app::Status heartbeat(&lcm, "FACT_STATUS", "fact-gossip", 4);
  app::Status mine(nullptr, "FACT_STATUS", "fact_lcm_tests", 0);
  Receiver<fact::app_status_t> r(lcm, "FACT_STATUS", &mine);

  heartbeat.set_state("waiting for peers");
  heartbeat.count("rejected_nan");
  heartbeat.count("foreign_messages", 5);
  heartbeat.count("rejected_nan", 2);
  heartbeat.note("drone 7 joined");
  EXPECT_EQ(heartbeat.value("rejected_nan"), 3);
  EXPECT_EQ(heartbeat.value("never"), 0);

  const int64_t t0 = 1700000000000000;
  heartbeat.tick(t0);             // first tick publishes
  heartbeat.tick(t0 + 500000);    // 0.5 s later: not yet
  heartbeat.count("foreign_messages");
  heartbeat.tick(t0 + 1000000);   // 1 s: again
  handle_until(lcm, r, 2);
  lcm.handleTimeout(20);
  EXPECT_EQ(heartbeat.published(), 2);
  ASSERT_EQ(r.decoded.size(), 2u);
  EXPECT_EQ(mine.value("undecodable"), 0);
  const fact::app_status_t& a = r.decoded[0];
  EXPECT_EQ(a.utime, t0);
  EXPECT_EQ(a.app, "fact-gossip");
  EXPECT_EQ(a.drone_id, 4);
  EXPECT_EQ(a.state, "waiting for peers");
  EXPECT_EQ(a.message, "drone 7 joined");
  ASSERT_EQ(a.num_counters, 2);
  EXPECT_EQ(a.counter_names, (std::vector<std::string>{"rejected_nan", "foreign_messages"}));
  EXPECT_EQ(a.counter_values, (std::vector<int64_t>{3, 5}));
  EXPECT_EQ(r.decoded[1].utime, t0 + 1000000);
  EXPECT_EQ(r.decoded[1].counter_values, (std::vector<int64_t>{3, 6}));
  // The reading side: counter_value finds a counter by name in the received message.
  EXPECT_EQ(app::counter_value(r.decoded[1], "foreign_messages"), std::optional<int64_t>(6));
  EXPECT_EQ(app::counter_value(r.decoded[1], "rejected_nan"), std::optional<int64_t>(3));
  EXPECT_EQ(app::counter_value(r.decoded[1], "undecodable"), std::nullopt);
  fact::app_status_t short_arrays = r.decoded[1];
  short_arrays.num_counters = 5;  // more than the arrays hold (a message built in code): no read past them
  EXPECT_EQ(app::counter_value(short_arrays, "foreign_messages"), std::optional<int64_t>(6));
  EXPECT_EQ(app::counter_value(short_arrays, "missing"), std::nullopt);

  heartbeat.set_period_us(100);
  heartbeat.tick(t0 + 1000050);  // 50 µs: no
  heartbeat.tick(t0 + 1000100);  // 100 µs: yes
  EXPECT_EQ(heartbeat.published(), 3);
  // The wall clock set back an hour: the heartbeat goes on from there instead of waiting an hour
  // for the clock to catch up (review, session 30).
  heartbeat.tick(t0 - 3600000000);
  EXPECT_EQ(heartbeat.published(), 4);
  heartbeat.tick(t0 - 3600000000 + 50);  // and keeps its period on the new time
  EXPECT_EQ(heartbeat.published(), 4);
  heartbeat.tick(t0 - 3600000000 + 100);
  EXPECT_EQ(heartbeat.published(), 5);
}

// An odometry stream restarts (fact-vio-relay's seq 0 after a VIO clock reset, or a restarted
// relay) when its seq goes back to 0, by more than 64, or with a time over 1 s earlier; one
// datagram reordered by UDP is not a restart.
TEST(AppCommon, OdometryRestartIsNotAReorderedDatagram) {
  using fact::app::odometry_restarted;
  const int64_t t = 5000000000;  // µs
  EXPECT_FALSE(odometry_restarted(500, t, 501, t + 10000));     // the next one
  EXPECT_FALSE(odometry_restarted(500, t, 499, t - 10000));     // reordered
  EXPECT_FALSE(odometry_restarted(500, t, 437, t - 630000));    // reordered by 63
  EXPECT_TRUE(odometry_restarted(500, t, 0, t + 10000));        // seq 0, whatever the time
  EXPECT_TRUE(odometry_restarted(500, t, 400, t + 10000));      // back by 100
  EXPECT_TRUE(odometry_restarted(500, t, 499, t - 7200000000)); // the time 2 h earlier (seq 0 … lost)
  EXPECT_FALSE(odometry_restarted(500, t, 500, t - 7200000000)); // not back: out of order, not a restart
}

TEST(AppCommon, ChannelNames) {
  EXPECT_EQ(app::channel("FACT_ODOMETRY", 3), "FACT_ODOMETRY_3");
  EXPECT_EQ(app::channel("FACT_RESULT", 0), "FACT_RESULT_0");
  EXPECT_EQ(app::channel("FACT_STATUS", -1), "FACT_STATUS");
}

TEST(AppCommon, LogLineHasTimeAppAndDrone) {
  app::Log log("fact-solver", 5);
  testing::internal::CaptureStderr();
  log.event("certified: 4 drones");
  std::string line = testing::internal::GetCapturedStderr();
  // 2024-05-01T12:00:00.123Z fact-solver[5] certified: 4 drones
  ASSERT_GE(line.size(), 25u);
  EXPECT_EQ(line[4], '-');
  EXPECT_EQ(line[10], 'T');
  EXPECT_EQ(line[23], 'Z');
  EXPECT_EQ(line.substr(24), " fact-solver[5] certified: 4 drones\n");
}

TEST(AppCommon, NowIsMicrosecondsSinceEpoch) {
  int64_t t = app::now_us();
  EXPECT_GT(t, int64_t{1600000000} * 1000000);  // after 2020
  EXPECT_LT(t, int64_t{4100000000} * 1000000);  // before 2100
}

// The schedules' clock is the steady clock (the wall clock's steps do not move it), in µs.
TEST(AppCommon, MonotonicClockIsTheSteadyClock) {
  using std::chrono::duration_cast;
  using std::chrono::microseconds;
  using std::chrono::steady_clock;
  const int64_t steady = duration_cast<microseconds>(steady_clock::now().time_since_epoch()).count();
  const int64_t t = app::monotonic_us();
  EXPECT_GE(t, steady);
  EXPECT_LT(t - steady, 100000);
  EXPECT_GE(app::monotonic_us(), t);
}

TEST(AppCommon, RunLoopHandlesMessagesAndStops) {
  app::clear_stop();
  lcm::LCM lcm("memq://");
  app::Status status(nullptr, "FACT_STATUS", "fact_lcm_tests", 0);
  Receiver<fact::odometry_t> r(lcm, "FACT_ODOMETRY_1", &status);
  int calls = 0;
  const fact::odometry_t sent = samples::odometry(9, 1);
  int rc = app::run_loop(lcm, 5, [&](int64_t now) {
    EXPECT_GT(now, 0);
    if (++calls == 1) lcm.publish("FACT_ODOMETRY_1", &sent);
    if (calls == 4) app::request_stop();
  });
  EXPECT_EQ(rc, 0);
  EXPECT_EQ(calls, 4);
  EXPECT_TRUE(app::stop_requested());
  ASSERT_EQ(r.decoded.size(), 1u);
  EXPECT_EQ(r.decoded[0].utime, 9);
  app::clear_stop();
  EXPECT_FALSE(app::stop_requested());
}

TEST(AppCommon, SigtermRequestsStop) {
  app::clear_stop();
  app::install_stop_handler();
  std::raise(SIGTERM);
  EXPECT_TRUE(app::stop_requested());
  app::clear_stop();
}

TEST(AppCommon, RunLoopFailsOnBadLcm) {
  lcm::LCM bad("nosuchprovider://x");
  testing::internal::CaptureStderr();
  EXPECT_EQ(app::run_loop(bad, 5, nullptr), 1);
  EXPECT_NE(testing::internal::GetCapturedStderr().find("LCM"), std::string::npos);
}

// ---- conversions ----------------------------------------------------------------------------

namespace {

fact::DroneRound drone_round(double s, int observations) {
  fact::DroneRound r;
  r.position = Eigen::Vector3d(s, -s, 1.5);
  r.yaw = 0.1 * s;
  for (int i = 0; i < observations; ++i) {
    fact::Observation o;
    o.odom_position = Eigen::Vector3d(s + i, 2 * s, 1.0);
    o.odom_yaw = -0.2 * i;
    o.vector = Eigen::Vector3d(1.0 + i, -0.5, 0.25 * s);
    r.observations.push_back(o);
  }
  return r;
}

void expect_same(const fact::DroneRound& a, const fact::DroneRound& b) {
  EXPECT_EQ(a.position, b.position);
  EXPECT_EQ(a.yaw, b.yaw);
  ASSERT_EQ(a.observations.size(), b.observations.size());
  for (size_t i = 0; i < a.observations.size(); ++i) {
    EXPECT_EQ(a.observations[i].odom_position, b.observations[i].odom_position);
    EXPECT_EQ(a.observations[i].odom_yaw, b.observations[i].odom_yaw);
    EXPECT_EQ(a.observations[i].vector, b.observations[i].vector);
  }
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

}  // namespace

TEST(Convert, RoundPacketRoundTrip) {
  const fact::DroneRound r = drone_round(1.25, 3);
  fact::round_packet_t m = app::to_message(7, 2, r, 55);
  EXPECT_EQ(m.utime, 55);
  EXPECT_EQ(m.drone_id, 7);
  EXPECT_EQ(m.round, 2);
  EXPECT_EQ(m.count, 3);
  fact::DroneRound back;
  ASSERT_EQ(app::from_message(m, &back), "");
  expect_same(back, r);

  fact::DroneRound empty_back;  // a round with no observations is legal
  ASSERT_EQ(app::from_message(app::to_message(1, 0, drone_round(2, 0), 1), &empty_back), "");
  EXPECT_TRUE(empty_back.observations.empty());
}

TEST(Convert, RoundPacketErrorsNameFieldAndValue) {
  const fact::round_packet_t good = app::to_message(3, 1, drone_round(1, 2), 1);
  fact::DroneRound out = drone_round(9, 1);
  const fact::DroneRound untouched = out;

  fact::round_packet_t m = good;
  m.observations[1].vector[2] = kNaN;
  std::string e = app::from_message(m, &out);
  EXPECT_TRUE(contains(e, "drone 3 round 1")) << e;
  EXPECT_TRUE(contains(e, "observations[1].vector[2] is nan")) << e;

  m = good;
  m.position[0] = kInf;
  EXPECT_TRUE(contains(app::from_message(m, &out), "position[0] is inf"));
  m = good;
  m.yaw = -kInf;
  EXPECT_TRUE(contains(app::from_message(m, &out), "yaw is -inf"));
  m = good;
  m.observations[0].odom_yaw = kNaN;
  EXPECT_TRUE(contains(app::from_message(m, &out), "observations[0].odom_yaw is nan"));
  m = good;
  m.observations[0].odom_position[1] = kNaN;
  EXPECT_TRUE(contains(app::from_message(m, &out), "observations[0].odom_position[1] is nan"));
  m = good;
  m.count = 5;
  e = app::from_message(m, &out);
  EXPECT_TRUE(contains(e, "count is 5 but observations has 2")) << e;
  m = good;
  m.drone_id = -2;
  EXPECT_TRUE(contains(app::from_message(m, &out), "drone_id is -2"));
  m = good;
  m.round = -1;
  EXPECT_TRUE(contains(app::from_message(m, &out), "round is -1"));
  expect_same(out, untouched);  // never half-written
}

namespace {

fact::Rounds three_drones_two_rounds() {
  fact::Rounds r;
  r.drones = {1, 2, 4};
  for (int k = 0; k < 2; ++k) {
    fact::Round round;
    round.index = k;
    for (int d : r.drones) round.drones[d] = drone_round(d + 0.5 * k, 1 + (d + k) % 3);
    r.rounds.push_back(round);
  }
  return r;
}

void expect_same(const fact::Rounds& a, const fact::Rounds& b) {
  EXPECT_EQ(a.drones, b.drones);
  ASSERT_EQ(a.rounds.size(), b.rounds.size());
  for (size_t k = 0; k < a.rounds.size(); ++k) {
    EXPECT_EQ(a.rounds[k].index, b.rounds[k].index);
    ASSERT_EQ(a.rounds[k].drones.size(), b.rounds[k].drones.size());
    for (const auto& [id, r] : a.rounds[k].drones) {
      ASSERT_TRUE(b.rounds[k].drones.count(id)) << id;
      expect_same(r, b.rounds[k].drones.at(id));
    }
  }
}

}  // namespace

TEST(Convert, SwarmRoundsRoundTrip) {
  const fact::Rounds rounds = three_drones_two_rounds();
  fact::swarm_rounds_t m = app::rounds_to_message(rounds, 2, 99);
  EXPECT_EQ(m.utime, 99);
  EXPECT_EQ(m.drone_id, 2);
  EXPECT_EQ(m.complete_rounds, 2);
  EXPECT_EQ(m.num_drones, 3);
  EXPECT_EQ(m.num_packets, 6);
  fact::Rounds back;
  ASSERT_EQ(app::rounds_from_message(m, &back), "");
  expect_same(back, rounds);
  EXPECT_EQ(fact::validate_rounds(back), "");

  // Packet order does not matter; drone_ids need not be sorted.
  std::swap(m.packets[0], m.packets[5]);
  std::swap(m.drone_ids[0], m.drone_ids[2]);
  fact::Rounds shuffled;
  ASSERT_EQ(app::rounds_from_message(m, &shuffled), "");
  expect_same(shuffled, rounds);

  // Through a real LCM encoding too (the bytes the gossip publishes).
  fact::swarm_rounds_t decoded;
  std::vector<uint8_t> b = encode(m);
  ASSERT_EQ(app::decode_error(b.data(), static_cast<int>(b.size()), &decoded), "");
  fact::Rounds from_wire;
  ASSERT_EQ(app::rounds_from_message(decoded, &from_wire), "");
  expect_same(from_wire, rounds);
}

TEST(Convert, SwarmRoundsErrors) {
  const fact::swarm_rounds_t good = app::rounds_to_message(three_drones_two_rounds(), 2, 1);
  const fact::Rounds sentinel = three_drones_two_rounds();
  fact::Rounds out = sentinel;
  auto error = [&](const fact::swarm_rounds_t& m) { return app::rounds_from_message(m, &out); };

  fact::swarm_rounds_t m = good;
  m.packets[3].drone_id = 9;  // unknown id
  std::string e = error(m);
  EXPECT_TRUE(contains(e, "packets[3]")) << e;
  EXPECT_TRUE(contains(e, "unknown drone id 9")) << e;

  m = good;
  m.packets[4] = m.packets[1];  // duplicate (drone 2, round 0); round 1 of drone 2 now missing
  e = error(m);
  EXPECT_TRUE(contains(e, "duplicate packet: drone 2 round 0")) << e;

  m = good;
  m.packets[2].round = 1000000;  // far in the future
  e = error(m);
  EXPECT_TRUE(contains(e, "round 1000000 outside 0 .. complete_rounds - 1 = 1")) << e;

  m = good;
  m.packets[0].round = -3;
  EXPECT_TRUE(contains(error(m), "round -3 outside"));

  m = good;
  m.packets.pop_back();  // drone 4 missing from round 1
  m.num_packets = 5;
  e = error(m);
  EXPECT_TRUE(contains(e, "round 1 has no packet from drone 4")) << e;

  m = good;
  m.complete_rounds = 2000000000;  // claims far more rounds than it carries: no allocation per round
  e = error(m);
  EXPECT_TRUE(contains(e, "round 2 has no packet from drone 1")) << e;

  m = good;
  m.num_drones = 4;
  EXPECT_TRUE(contains(error(m), "num_drones is 4 but drone_ids has 3"));
  m = good;
  m.num_packets = 7;
  EXPECT_TRUE(contains(error(m), "num_packets is 7 but packets has 6"));
  m = good;
  m.drone_ids[2] = 1;
  EXPECT_TRUE(contains(error(m), "drone_ids[2] is 1, listed twice"));
  m = good;
  m.drone_ids[0] = -1;
  EXPECT_TRUE(contains(error(m), "drone_ids[0] is -1"));
  m = good;
  m.complete_rounds = -1;
  EXPECT_TRUE(contains(error(m), "complete_rounds is -1"));
  m = good;
  m.packets[5].observations[0].vector[1] = kNaN;
  e = error(m);
  EXPECT_TRUE(contains(e, "packets[5]: round_packet drone 4 round 1: observations[0].vector[1] is nan")) << e;
  m = good;
  m.packets[1].count = 0;
  EXPECT_TRUE(contains(error(m), "count is 0 but observations has"));

  expect_same(out, sentinel);  // never half-written
}

TEST(Convert, ResultToMessageCarriesTheEstimate) {
  fact::SimOptions o;
  o.drones = 4;
  o.rounds = 3;
  o.seed = 3;
  const fact::Scenario s = fact::generate_scenario(o);
  const fact::Estimate e = fact::estimate_poses(s.rounds);
  ASSERT_TRUE(e.certified()) << e.reason;
  ASSERT_EQ(e.drones.size(), 4u);

  const fact::swarm_result_t m = app::result_to_message(e, 2, 777);
  EXPECT_EQ(m.utime, 777);
  EXPECT_EQ(m.drone_id, 2);
  EXPECT_EQ(m.mode, fact::to_string(e.mode));
  EXPECT_EQ(m.status, fact::to_string(e.status));
  EXPECT_EQ(m.reason, e.reason);
  EXPECT_EQ(m.reference, e.reference);
  EXPECT_EQ(m.rounds_used, e.rounds_used);
  ASSERT_EQ(m.num_drones, 4);
  ASSERT_EQ(m.drones.size(), 4u);
  for (size_t i = 0; i < e.drones.size(); ++i) {
    EXPECT_EQ(m.drones[i].id, e.drones[i].id);
    EXPECT_EQ(m.drones[i].yaw, e.drones[i].yaw);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(m.drones[i].position[k], e.drones[i].position[k]);
    EXPECT_EQ(m.drones[i].resolved, e.drones[i].resolved);
  }
  EXPECT_EQ(m.objective, e.certificate.objective);
  EXPECT_EQ(m.dual_objective, e.certificate.dual_objective);
  EXPECT_EQ(m.gap, e.certificate.gap);
  EXPECT_EQ(m.min_eig, e.certificate.min_eig);
  EXPECT_EQ(m.rank, e.certificate.rank);
  double total = -1;
  for (const auto& [stage, us] : e.timing_us)
    if (stage == "total") total = us;
  EXPECT_EQ(m.solve_us, total);

  fact::Estimate back;
  ASSERT_EQ(app::result_from_message(m, &back), "");
  EXPECT_EQ(back.mode, e.mode);
  EXPECT_EQ(back.status, e.status);
  EXPECT_EQ(back.reason, e.reason);
  EXPECT_EQ(back.unresolved, e.unresolved);
  ASSERT_EQ(back.drones.size(), e.drones.size());
  for (size_t i = 0; i < e.drones.size(); ++i) EXPECT_EQ(back.drones[i].position, e.drones[i].position);
  EXPECT_EQ(back.certificate.dual_objective, e.certificate.dual_objective);
  EXPECT_TRUE(std::isnan(back.certificate.bound_error));  // the message does not carry it
}

TEST(Convert, InvalidInputResultAndResultErrors) {
  fact::Rounds bad = three_drones_two_rounds();
  bad.rounds[0].drones[2].observations[0].vector[0] = kNaN;
  const fact::Estimate e = fact::estimate_poses(bad);
  ASSERT_EQ(e.status, fact::EstimateStatus::invalid_input);
  fact::swarm_result_t m = app::result_to_message(e, 1, 5);
  EXPECT_EQ(m.status, "invalid_input");
  EXPECT_EQ(m.reason, e.reason);
  fact::Estimate back;
  EXPECT_EQ(app::result_from_message(m, &back), "");  // NaN certificate is allowed: it does not exist

  fact::swarm_result_t r = samples::swarm_result(1, 1);
  fact::Estimate out;
  r.mode = "magic";
  EXPECT_TRUE(contains(app::result_from_message(r, &out), "mode is \"magic\""));
  r = samples::swarm_result(1, 1);
  r.status = "sure";
  EXPECT_TRUE(contains(app::result_from_message(r, &out), "status is \"sure\""));
  r = samples::swarm_result(1, 1);
  r.num_drones = 2;
  EXPECT_TRUE(contains(app::result_from_message(r, &out), "num_drones is 2 but drones has 3"));
  r = samples::swarm_result(1, 1);
  r.drones[0].yaw = kNaN;  // resolved
  EXPECT_TRUE(contains(app::result_from_message(r, &out), "drones[0].yaw is nan but resolved is true"));
  r = samples::swarm_result(1, 1);
  r.drones[2].yaw = kNaN;  // unresolved: allowed
  EXPECT_EQ(app::result_from_message(r, &out), "");
  EXPECT_EQ(out.unresolved, std::vector<int>{4});
  r = samples::swarm_result(1, 1);
  r.drones[1].id = 1;
  EXPECT_TRUE(contains(app::result_from_message(r, &out), "drones[1].id is 1, listed twice"));
  r = samples::swarm_result(1, 1);
  r.solve_us = -std::numeric_limits<double>::infinity();
  EXPECT_TRUE(contains(app::result_from_message(r, &out), "solve_us is -inf"));
  // A "certified" result that certifies nothing (review, session 33: it passed, and the planner
  // holds on a certified result).
  fact::swarm_result_t c = samples::swarm_result(1, 1);
  c.status = "certified";
  c.drones[2].resolved = true;
  c.drones[2].yaw = 0.5;
  ASSERT_EQ(app::result_from_message(c, &out), "");
  r = c;
  r.mode = "auto";
  EXPECT_TRUE(contains(app::result_from_message(r, &out), "status is certified but mode is \"auto\""));
  r = c;
  r.drones[1].resolved = false;
  EXPECT_TRUE(contains(app::result_from_message(r, &out), "status is certified but drone"));
  r = c;
  r.reference = -7;
  EXPECT_TRUE(contains(app::result_from_message(r, &out), "the reference -7 is not among its drones"));
  r = c;
  r.num_drones = 0;
  r.drones.clear();
  EXPECT_TRUE(contains(app::result_from_message(r, &out), "status is certified but drones is empty"));
}
