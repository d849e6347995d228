// Tests of the JSON encodings in fact_io: fact-rounds-v1, fact-result-v1, fact-truth-v1.
// Round trips compare every double bit for bit; every decoder error is checked for the JSON
// path and the offending value in its message.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "fact/json_io.h"

namespace {

using fact::FormatError;

std::uint64_t bits(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

#define EXPECT_SAME_DOUBLE(a, b) EXPECT_EQ(bits(a), bits(b)) << (a) << " vs " << (b)

void expect_same(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  for (int c = 0; c < 3; ++c) EXPECT_SAME_DOUBLE(a[c], b[c]);
}

// Doubles that are easy to get wrong in text: shortest-form edge cases, −0, subnormals, extremes.
std::vector<double> awkward_doubles() {
  std::vector<double> v = {0.1, 1.0 / 3.0, -0.0, M_PI, -M_PI, 5e-324, 2.2250738585072014e-308,
                           1.7976931348623157e308, -1e-300, 123456789.123456789, 0.30000000000000004};
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-30, 30);
  for (int i = 0; i < 200; ++i) v.push_back(std::ldexp(mantissa(rng), exponent(rng)));
  return v;
}

// The message of the FormatError that `f` throws ("" and a test failure if it throws none).
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const FormatError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no FormatError was thrown";
  return "";
}

// `text` with its one occurrence of `from` replaced by `to`.
std::string edit(const std::string& text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "test text has no " << from;
  EXPECT_EQ(text.find(from, at + 1), std::string::npos) << "test text has " << from << " twice";
  if (at == std::string::npos) return text;
  return text.substr(0, at) + to + text.substr(at + from.size());
}

// ---------------------------------------------------------------------------------------------
// fact-rounds-v1

const std::string kRounds = R"({"format": "fact-rounds-v1", "drones": [7, 2],
 "rounds": [
  {"index": 0, "drones": {
    "2": {"position": [0, 0, 1], "yaw": 0.5,
          "observations": [{"odom_position": [0.25, 0, 1], "odom_yaw": 0.75, "vector": [1, 2, 0.5]}]},
    "7": {"position": [3, 1, 1.5], "yaw": -1, "observations": []}}},
  {"index": 4, "drones": {
    "7": {"position": [3, 2, 1.5], "yaw": -1.25,
          "observations": [{"odom_position": [3, 2, 1.5], "odom_yaw": -1.25, "vector": [-1, -2, -0.5]},
                           {"odom_position": [3, 2, 1.5], "odom_yaw": -1.5, "vector": [4, 0, 0]}]}}}]})";

std::string rounds_error(const std::string& text) {
  return error_of([&] { fact::rounds_from_json(text); });
}

TEST(RoundsJson, DecodesEveryField) {
  const fact::Rounds r = fact::rounds_from_json(kRounds);
  EXPECT_EQ(r.drones, (std::vector<int>{2, 7}));  // sorted
  ASSERT_EQ(r.rounds.size(), 2u);
  EXPECT_EQ(r.rounds[0].index, 0);
  EXPECT_EQ(r.rounds[1].index, 4);
  ASSERT_EQ(r.rounds[0].drones.size(), 2u);
  const fact::DroneRound& d2 = r.rounds[0].drones.at(2);
  EXPECT_EQ(d2.position, Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(d2.yaw, 0.5);
  ASSERT_EQ(d2.observations.size(), 1u);
  EXPECT_EQ(d2.observations[0].odom_position, Eigen::Vector3d(0.25, 0, 1));
  EXPECT_EQ(d2.observations[0].odom_yaw, 0.75);
  EXPECT_EQ(d2.observations[0].vector, Eigen::Vector3d(1, 2, 0.5));
  EXPECT_TRUE(r.rounds[0].drones.at(7).observations.empty());
  EXPECT_EQ(r.rounds[0].drones.at(7).yaw, -1.0);
  ASSERT_EQ(r.rounds[1].drones.size(), 1u);
  ASSERT_EQ(r.rounds[1].drones.at(7).observations.size(), 2u);
  EXPECT_EQ(r.rounds[1].drones.at(7).observations[1].vector, Eigen::Vector3d(4, 0, 0));
  EXPECT_EQ(r.rounds[1].drones.at(7).observations[1].odom_yaw, -1.5);
}

fact::Rounds awkward_rounds() {
  const std::vector<double> x = awkward_doubles();
  std::size_t next = 0;
  const auto take = [&] { return x[next++ % x.size()]; };
  const auto take3 = [&] { return Eigen::Vector3d(take(), take(), take()); };
  fact::Rounds r;
  r.drones = {0, 3, 11, 250};
  for (int k = 0; k < 4; ++k) {
    fact::Round round;
    round.index = 10 * k - 5;
    for (int id : r.drones) {
      if (k == 2 && id == 11) continue;  // a drone that did not report this round
      fact::DroneRound d{take3(), take(), {}};
      for (int o = 0; o < (id + k) % 4; ++o) d.observations.push_back({take3(), take(), take3()});
      round.drones[id] = d;
    }
    r.rounds.push_back(round);
  }
  return r;
}

void expect_same(const fact::Rounds& a, const fact::Rounds& b) {
  EXPECT_EQ(a.drones, b.drones);
  ASSERT_EQ(a.rounds.size(), b.rounds.size());
  for (std::size_t k = 0; k < a.rounds.size(); ++k) {
    EXPECT_EQ(a.rounds[k].index, b.rounds[k].index);
    ASSERT_EQ(a.rounds[k].drones.size(), b.rounds[k].drones.size());
    for (const auto& [id, da] : a.rounds[k].drones) {
      ASSERT_EQ(b.rounds[k].drones.count(id), 1u) << "round " << k << " drone " << id;
      const fact::DroneRound& db = b.rounds[k].drones.at(id);
      expect_same(da.position, db.position);
      EXPECT_SAME_DOUBLE(da.yaw, db.yaw);
      ASSERT_EQ(da.observations.size(), db.observations.size());
      for (std::size_t o = 0; o < da.observations.size(); ++o) {
        expect_same(da.observations[o].odom_position, db.observations[o].odom_position);
        EXPECT_SAME_DOUBLE(da.observations[o].odom_yaw, db.observations[o].odom_yaw);
        expect_same(da.observations[o].vector, db.observations[o].vector);
      }
    }
  }
}

TEST(RoundsJson, RoundTripIsBitExact) {
  const fact::Rounds original = awkward_rounds();
  const std::string text = fact::rounds_to_json(original);
  const fact::Rounds back = fact::rounds_from_json(text);
  expect_same(original, back);
  EXPECT_EQ(fact::rounds_to_json(back), text);
  EXPECT_TRUE(std::signbit(back.rounds[0].drones.at(0).position[2]) ==
              std::signbit(original.rounds[0].drones.at(0).position[2]));
}

TEST(RoundsJson, EncoderSortsIdsAndEndsWithNewline) {
  fact::Rounds r = fact::rounds_from_json(kRounds);
  r.drones = {7, 2};
  const std::string text = fact::rounds_to_json(r);
  EXPECT_NE(text.find("\"drones\": [2, 7],"), std::string::npos) << text;
  EXPECT_EQ(text.rfind("fact-rounds-v1"), text.find("fact-rounds-v1"));
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.back(), '\n');
  EXPECT_EQ(text.substr(0, 4), "{\n  ");  // 2-space indent
}

TEST(RoundsJson, EncoderRejectsWhatTheDecoderWould) {
  fact::Rounds r = fact::rounds_from_json(kRounds);
  r.rounds[1].drones[7].observations[1].vector[2] = std::numeric_limits<double>::quiet_NaN();
  std::string m = error_of([&] { fact::rounds_to_json(r); });
  EXPECT_NE(m.find(R"(rounds[1].drones["7"].observations[1].vector[2])"), std::string::npos) << m;
  EXPECT_NE(m.find("nan"), std::string::npos) << m;

  r = fact::rounds_from_json(kRounds);
  r.rounds[0].drones[5] = fact::DroneRound{};
  m = error_of([&] { fact::rounds_to_json(r); });
  EXPECT_NE(m.find(R"(rounds[0].drones["5"])"), std::string::npos) << m;

  r = fact::rounds_from_json(kRounds);
  r.drones = {2, 7, 2};
  m = error_of([&] { fact::rounds_to_json(r); });
  EXPECT_NE(m.find("drones[2]"), std::string::npos) << m;
  EXPECT_NE(m.find("duplicate id 2"), std::string::npos) << m;
}

TEST(RoundsJson, FlatValuesStayOnOneLine) {
  const std::string text = fact::rounds_to_json(fact::rounds_from_json(kRounds));
  EXPECT_NE(text.find("\n          \"position\": [0.0, 0.0, 1.0],\n"), std::string::npos) << text;
  EXPECT_NE(text.find("\n            {\"odom_position\": [0.25, 0.0, 1.0], \"odom_yaw\": 0.75, \"vector\": [1.0, 2.0, 0.5]}\n"),
            std::string::npos) << text;
  EXPECT_NE(text.find("\n        \"7\": {\"position\": [3.0, 1.0, 1.5], \"yaw\": -1.0, \"observations\": []}\n"),
            std::string::npos) << text;
}

TEST(RoundsJson, EmptyObservationsAndUnknownTopLevelKeysAreAccepted) {
  const std::string text = edit(kRounds, R"("format": "fact-rounds-v1",)",
                                R"("format": "fact-rounds-v1", "generator": {"seed": 7},)");
  const fact::Rounds r = fact::rounds_from_json(text);
  EXPECT_TRUE(r.rounds[0].drones.at(7).observations.empty());
  EXPECT_EQ(r.rounds[1].drones.at(7).observations.size(), 2u);
}

TEST(RoundsJson, WrongVectorLengthNamesPathAndCount) {
  const std::string m = rounds_error(edit(kRounds, "[-1, -2, -0.5]", "[-1, -2]"));
  EXPECT_EQ(m, R"(rounds[1].drones["7"].observations[0].vector: expected 3 numbers, got 2: [-1,-2])");
}

TEST(RoundsJson, VectorThatIsNotAnArray) {
  const std::string m = rounds_error(edit(kRounds, "[3, 1, 1.5]", "\"3 1 1.5\""));
  EXPECT_NE(m.find(R"(rounds[0].drones["7"].position)"), std::string::npos) << m;
  EXPECT_NE(m.find(R"("3 1 1.5")"), std::string::npos) << m;
}

TEST(RoundsJson, VectorElementThatIsNotANumber) {
  const std::string m = rounds_error(edit(kRounds, "[4, 0, 0]", "[4, \"x\", 0]"));
  EXPECT_NE(m.find(R"(rounds[1].drones["7"].observations[1].vector[1]: expected a number, got "x")"),
            std::string::npos) << m;
}

TEST(RoundsJson, MissingKeyNamesPath) {
  const std::string m = rounds_error(edit(kRounds, R"("yaw": 0.5,)", ""));
  EXPECT_NE(m.find(R"(rounds[0].drones["2"].yaw: required key is missing)"), std::string::npos) << m;
  const std::string top = rounds_error(edit(kRounds, R"("drones": [7, 2],)", ""));
  EXPECT_NE(top.find("drones: required key is missing"), std::string::npos) << top;
  const std::string obs = rounds_error(edit(kRounds, R"("odom_yaw": 0.75, )", ""));
  EXPECT_NE(obs.find(R"(rounds[0].drones["2"].observations[0].odom_yaw: required key is missing)"),
            std::string::npos) << obs;
}

TEST(RoundsJson, WrongTypeNamesPathAndValue) {
  std::string m = rounds_error(edit(kRounds, R"("yaw": 0.5)", R"("yaw": "abc")"));
  EXPECT_NE(m.find(R"(rounds[0].drones["2"].yaw: expected a number, got "abc")"), std::string::npos) << m;
  m = rounds_error(edit(kRounds, R"("yaw": 0.5)", R"("yaw": true)"));
  EXPECT_NE(m.find(R"(rounds[0].drones["2"].yaw: expected a number, got true)"), std::string::npos) << m;
  m = rounds_error(edit(kRounds, R"("yaw": 0.5)", R"("yaw": null)"));
  EXPECT_NE(m.find(R"(rounds[0].drones["2"].yaw: expected a number, got null)"), std::string::npos) << m;
  m = rounds_error(edit(kRounds, R"("index": 4)", R"("index": 4.5)"));
  EXPECT_NE(m.find("rounds[1].index: expected an integer, got 4.5"), std::string::npos) << m;
  m = rounds_error(edit(kRounds, R"("index": 4)", R"("index": 3000000000)"));
  EXPECT_NE(m.find("rounds[1].index: integer out of range, got 3000000000"), std::string::npos) << m;
  m = rounds_error(edit(kRounds, R"("observations": [])", R"("observations": {})"));
  EXPECT_NE(m.find(R"(rounds[0].drones["7"].observations: expected an array, got {})"), std::string::npos) << m;
  m = rounds_error(R"({"format": "fact-rounds-v1", "drones": [1, 2], "rounds": [{"index": 0, "drones": []}]})");
  EXPECT_EQ(m, "rounds[0].drones: expected an object, got []");
  m = rounds_error(R"({"format": "fact-rounds-v1", "drones": [1, 2], "rounds": {}})");
  EXPECT_EQ(m, "rounds: expected an array, got {}");
}

TEST(RoundsJson, NumberTooLargeForADoubleNamesPathAndValue) {
  const std::string m = rounds_error(edit(kRounds, R"("yaw": -1.25)", R"("yaw": 1e999)"));
  EXPECT_NE(m.find(R"(rounds[1].drones["7"].yaw)"), std::string::npos) << m;
  EXPECT_NE(m.find("1e999"), std::string::npos) << m;
  const std::string neg = rounds_error(edit(kRounds, "[4, 0, 0]", "[4, -1e400, 0]"));
  EXPECT_NE(neg.find(R"(rounds[1].drones["7"].observations[1].vector[1])"), std::string::npos) << neg;
  EXPECT_NE(neg.find("-1e400"), std::string::npos) << neg;
}

TEST(RoundsJson, BadFormatStringIsNamed) {
  std::string m = rounds_error(edit(kRounds, "fact-rounds-v1", "fact-rounds-v2"));
  EXPECT_EQ(m, R"(format: expected "fact-rounds-v1", got "fact-rounds-v2")");
  m = rounds_error(edit(kRounds, R"("format": "fact-rounds-v1",)", ""));
  EXPECT_EQ(m, "format: required key is missing");
  m = rounds_error(edit(kRounds, R"("fact-rounds-v1")", "1"));
  EXPECT_EQ(m, "format: expected a string, got 1");
}

TEST(RoundsJson, DroneKeyNotListedIsNamed) {
  const std::string m = rounds_error(edit(kRounds, R"("7": {"position": [3, 2, 1.5])", R"("9": {"position": [3, 2, 1.5])"));
  EXPECT_EQ(m, R"(rounds[1].drones["9"]: drone 9 is not listed in "drones")");
}

TEST(RoundsJson, NonIntegerDroneKeyIsNamed) {
  for (const std::string key : {"x7", "07", "-2", "+2", " 2", "2.0", "", "99999999999"}) {
    const std::string m = rounds_error(edit(kRounds, R"("2": {"position")", "\"" + key + R"(": {"position")"));
    EXPECT_NE(m.find("rounds[0].drones[\"" + key + "\"]: expected a drone id in decimal as the key, got \"" + key + "\""),
              std::string::npos) << m;
  }
}

TEST(RoundsJson, DroneListErrorsAreNamed) {
  std::string m = rounds_error(edit(kRounds, "[7, 2]", "[7, 2, 7]"));
  EXPECT_EQ(m, "drones[2]: duplicate id 7 (also at drones[0])");
  m = rounds_error(edit(kRounds, "[7, 2]", "[7, 2.5]"));
  EXPECT_EQ(m, "drones[1]: expected an integer, got 2.5");
  m = rounds_error(edit(kRounds, "[7, 2]", "[7, 2, -3]"));
  EXPECT_EQ(m, "drones[2]: expected a drone id >= 0, got -3");
  m = rounds_error(edit(kRounds, "[7, 2]", R"([7, "2"])"));
  EXPECT_EQ(m, R"(drones[1]: expected an integer, got "2")");
}

TEST(RoundsJson, UnknownKeysInsideAreNamed) {
  std::string m = rounds_error(edit(kRounds, R"("vector": [1, 2, 0.5])", R"("vector": [1, 2, 0.5], "range": 2.3)"));
  EXPECT_NE(m.find(R"(rounds[0].drones["2"].observations[0].range: unknown key)"), std::string::npos) << m;
  m = rounds_error(edit(kRounds, R"("yaw": 0.5,)", R"("yaw": 0.5, "Yaw": 1,)"));
  EXPECT_NE(m.find(R"(rounds[0].drones["2"].Yaw: unknown key)"), std::string::npos) << m;
  m = rounds_error(edit(kRounds, R"("index": 4,)", R"("index": 4, "time": 12,)"));
  EXPECT_NE(m.find("rounds[1].time: unknown key"), std::string::npos) << m;
}

TEST(RoundsJson, DuplicateKeyIsNamed) {
  std::string m = rounds_error(edit(kRounds, R"("yaw": 0.5,)", R"("yaw": 0.5, "yaw": 0.6,)"));
  EXPECT_EQ(m, R"(rounds[0].drones["2"].yaw: duplicate key "yaw")");
  m = rounds_error(edit(kRounds, R"("7": {"position": [3, 1, 1.5], "yaw": -1, "observations": []})",
                        R"("7": {"position": [3, 1, 1.5], "yaw": -1, "observations": []}, "7": {})"));
  EXPECT_EQ(m, R"(rounds[0].drones["7"]: duplicate key "7")");
}

TEST(RoundsJson, BrokenTextIsReportedWithPosition) {
  const std::string truncated = kRounds.substr(0, kRounds.find("\"odom_yaw\": -1.5"));
  std::string m = rounds_error(truncated);
  EXPECT_NE(m.find("invalid JSON"), std::string::npos) << m;
  EXPECT_NE(m.find("line 10"), std::string::npos) << m;
  EXPECT_NE(m.find(R"(near rounds[1].drones["7"].observations[1].odom_position)"), std::string::npos) << m;
  m = rounds_error("");
  EXPECT_NE(m.find("invalid JSON"), std::string::npos) << m;
  m = rounds_error(kRounds + " x");
  EXPECT_NE(m.find("invalid JSON"), std::string::npos) << m;
  m = rounds_error("[1, 2]");
  EXPECT_EQ(m, "top level: expected an object, got [1,2]");
}

// ---------------------------------------------------------------------------------------------
// fact-result-v1

fact::Estimate certified_estimate() {
  fact::Estimate e;
  e.mode = fact::Mode::complex;
  e.status = fact::EstimateStatus::certified;
  e.reason = "unique optimum, \"quoted\" and ünïcode";
  e.reference = 3;
  e.rounds_used = 4;
  const std::vector<double> x = awkward_doubles();
  e.drones = {{3, 0.0, Eigen::Vector3d::Zero(), true},
              {5, x[0], Eigen::Vector3d(x[1], x[2], x[3]), true},
              {9, x[4], Eigen::Vector3d(x[5], x[6], x[7]), true}};
  e.certificate = {x[8], x[9], 1e-12, -3e-10, 2, 4.5e-13};
  e.timing_us = {{"summed.cost", x[10]}, {"summed.sdp", 812.5}, {"association", 3.0}, {"total", 1000.25}};
  return e;
}

void expect_same(const fact::Estimate& a, const fact::Estimate& b) {
  EXPECT_EQ(a.mode, b.mode);
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.reason, b.reason);
  EXPECT_EQ(a.reference, b.reference);
  EXPECT_EQ(a.rounds_used, b.rounds_used);
  ASSERT_EQ(a.drones.size(), b.drones.size());
  for (std::size_t i = 0; i < a.drones.size(); ++i) {
    EXPECT_EQ(a.drones[i].id, b.drones[i].id);
    EXPECT_SAME_DOUBLE(a.drones[i].yaw, b.drones[i].yaw);
    expect_same(a.drones[i].position, b.drones[i].position);
    EXPECT_EQ(a.drones[i].resolved, b.drones[i].resolved);
  }
  EXPECT_EQ(a.unresolved, b.unresolved);
  EXPECT_SAME_DOUBLE(a.certificate.objective, b.certificate.objective);
  EXPECT_SAME_DOUBLE(a.certificate.dual_objective, b.certificate.dual_objective);
  EXPECT_SAME_DOUBLE(a.certificate.gap, b.certificate.gap);
  EXPECT_SAME_DOUBLE(a.certificate.min_eig, b.certificate.min_eig);
  EXPECT_EQ(a.certificate.rank, b.certificate.rank);
  EXPECT_SAME_DOUBLE(a.certificate.bound_error, b.certificate.bound_error);
  ASSERT_EQ(a.timing_us.size(), b.timing_us.size());
  for (std::size_t i = 0; i < a.timing_us.size(); ++i) {
    EXPECT_EQ(a.timing_us[i].first, b.timing_us[i].first);
    EXPECT_SAME_DOUBLE(a.timing_us[i].second, b.timing_us[i].second);
  }
}

TEST(ResultJson, RoundTripIsBitExactAndKeepsTimingOrder) {
  const fact::Estimate e = certified_estimate();
  const std::string text = fact::estimate_to_json(e);
  expect_same(e, fact::estimate_from_json(text));
  EXPECT_NE(text.find("\"format\": \"fact-result-v1\""), std::string::npos) << text;
  EXPECT_NE(text.find("\"mode\": \"complex\""), std::string::npos) << text;
  EXPECT_NE(text.find("\"status\": \"certified\""), std::string::npos) << text;
  EXPECT_LT(text.find("summed.sdp"), text.find("association"));  // not alphabetical
  EXPECT_EQ(text.back(), '\n');
}

// A result written before "bound_error" existed reads, with the bound's rounding unknown (NaN) and
// everything else as written.
TEST(ResultJson, CertificateWithoutBoundErrorReadsItAsNaN) {
  const fact::Estimate e = certified_estimate();
  const std::string text = fact::estimate_to_json(e);
  const std::string key = "\"bound_error\": 4.5e-13,";
  ASSERT_NE(text.find(key), std::string::npos) << text;
  std::string old = text;
  old.erase(old.find(key), key.size());
  const fact::Estimate back = fact::estimate_from_json(old);
  EXPECT_TRUE(std::isnan(back.certificate.bound_error));
  fact::Estimate expected = e;
  expected.certificate.bound_error = back.certificate.bound_error;
  expect_same(expected, back);
}

TEST(ResultJson, EveryModeAndStatusRoundTrips) {
  for (fact::Mode m : {fact::Mode::paper, fact::Mode::complex, fact::Mode::associated, fact::Mode::automatic})
    for (fact::EstimateStatus s : {fact::EstimateStatus::certified, fact::EstimateStatus::ambiguous,
                                   fact::EstimateStatus::invalid_input}) {
      fact::Estimate e = certified_estimate();
      e.mode = m;
      e.status = s;
      const fact::Estimate back = fact::estimate_from_json(fact::estimate_to_json(e));
      EXPECT_EQ(back.mode, m);
      EXPECT_EQ(back.status, s);
    }
}

TEST(ResultJson, MissingValuesAreNullAndReadBackAsNaN) {
  fact::Estimate e = certified_estimate();
  e.status = fact::EstimateStatus::invalid_input;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  e.certificate = {nan, std::numeric_limits<double>::infinity(), nan, nan, 0, nan};
  e.drones[2] = {9, nan, Eigen::Vector3d(1.5, nan, nan), false};
  e.unresolved = {9};
  e.reference = -1;
  const std::string text = fact::estimate_to_json(e);
  EXPECT_NE(text.find("\"objective\": null"), std::string::npos) << text;
  EXPECT_NE(text.find("\"dual_objective\": null"), std::string::npos) << text;
  const fact::Estimate back = fact::estimate_from_json(text);
  EXPECT_TRUE(std::isnan(back.certificate.objective));
  EXPECT_TRUE(std::isnan(back.certificate.dual_objective));  // inf is not representable: null
  EXPECT_TRUE(std::isnan(back.certificate.gap));
  EXPECT_TRUE(std::isnan(back.certificate.min_eig));
  EXPECT_EQ(back.certificate.rank, 0);
  EXPECT_TRUE(std::isnan(back.certificate.bound_error));
  EXPECT_NE(text.find("\"bound_error\": null"), std::string::npos) << text;
  EXPECT_TRUE(std::isnan(back.drones[2].yaw));
  EXPECT_EQ(back.drones[2].position[0], 1.5);
  EXPECT_TRUE(std::isnan(back.drones[2].position[1]));
  EXPECT_FALSE(back.drones[2].resolved);
  EXPECT_EQ(back.unresolved, std::vector<int>{9});
  EXPECT_EQ(back.reference, -1);
}

TEST(ResultJson, ResolvedDroneWithoutAPoseIsRejected) {
  fact::Estimate e = certified_estimate();
  e.drones[1].yaw = std::numeric_limits<double>::quiet_NaN();
  std::string m = error_of([&] { fact::estimate_to_json(e); });
  EXPECT_NE(m.find("drones[1].yaw"), std::string::npos) << m;
  EXPECT_NE(m.find("nan"), std::string::npos) << m;
  const std::string text = fact::estimate_to_json(certified_estimate());
  const std::string yaw = "\"yaw\": 0.0,";
  m = error_of([&] { fact::estimate_from_json(edit(text, yaw, "\"yaw\": null,")); });
  EXPECT_EQ(m, "drones[0].yaw: expected a number, got null");
}

TEST(ResultJson, EncoderRejectsWhatTheDecoderWould) {
  fact::Estimate e = certified_estimate();
  e.drones[2].id = 3;
  std::string m = error_of([&] { fact::estimate_to_json(e); });
  EXPECT_NE(m.find("drones[2]: duplicate id 3"), std::string::npos) << m;
  e = certified_estimate();
  e.rounds_used = -1;
  m = error_of([&] { fact::estimate_to_json(e); });
  EXPECT_NE(m.find("rounds_used: it is -1"), std::string::npos) << m;
  e = certified_estimate();
  e.timing_us.push_back({"total", 5.0});
  m = error_of([&] { fact::estimate_to_json(e); });
  EXPECT_NE(m.find("timing_us.total: the stage name appears twice"), std::string::npos) << m;
}

TEST(ResultJson, DecoderErrorsNameTheField) {
  const std::string text = fact::estimate_to_json(certified_estimate());
  const auto error = [](const std::string& t) { return error_of([&] { fact::estimate_from_json(t); }); };
  EXPECT_EQ(error(edit(text, R"("complex")", R"("fast")")),
            R"(mode: expected one of "paper", "complex", "associated", "auto", got "fast")");
  EXPECT_EQ(error(edit(text, R"("certified")", R"("sure")")),
            R"(status: expected one of "certified", "ambiguous", "invalid_input", got "sure")");
  EXPECT_EQ(error(edit(text, R"("rank": 2)", R"("rank": null)")), "certificate.rank: expected an integer, got null");
  EXPECT_EQ(error(edit(text, R"("total": 1000.25)", R"("total": "1ms")")),
            R"(timing_us.total: expected a number, got "1ms")");
  EXPECT_EQ(error(edit(text, R"("rounds_used": 4)", R"("rounds_used": -4)")), "rounds_used: expected a count >= 0, got -4");
  EXPECT_EQ(error(edit(text, R"("id": 9)", R"("id": 5)")), "drones[2].id: duplicate id 5 (also at drones[1])");
  EXPECT_EQ(error(edit(text, R"("gap": 1e-12)", R"("gap": 1e-12, "eig_gap": 0)")),
            R"(certificate.eig_gap: unknown key (allowed: "objective", "dual_objective", "bound_error", "gap", "min_eig", "rank"))");
  EXPECT_EQ(error(edit(text, R"("bound_error": 4.5e-13)", R"("bound_error": "small")")),
            R"(certificate.bound_error: expected a number or null, got "small")");
  EXPECT_EQ(error(edit(text, "fact-result-v1", "fact-rounds-v1")), R"(format: expected "fact-result-v1", got "fact-rounds-v1")");
}

// ---------------------------------------------------------------------------------------------
// fact-truth-v1

fact::Truth awkward_truth() {
  const std::vector<double> x = awkward_doubles();
  std::size_t next = 0;
  const auto take = [&] { return x[next++ % x.size()]; };
  const auto take3 = [&] { return Eigen::Vector3d(take(), take(), take()); };
  fact::Truth t;
  t.ids = {5, 1, 30};  // not sorted: the order is kept
  for (std::size_t i = 0; i < t.ids.size(); ++i) {
    t.frame_yaw.push_back(take());
    t.frame_origin.push_back(take3());
  }
  for (int k = 0; k < 3; ++k) {
    t.positions.push_back({take3(), take3(), take3()});
    t.targets.push_back({{1, 30}, k == 0 ? std::vector<int>{-1, 5, 30, -1} : std::vector<int>{30, -1}, {}});
  }
  t.obstacles.push_back({take3(), take(), take()});
  t.obstacles.push_back({Eigen::Vector3d(1, 2, 0), 0.4, 3.0});
  return t;
}

void expect_same(const fact::Truth& a, const fact::Truth& b) {
  EXPECT_EQ(a.ids, b.ids);
  ASSERT_EQ(a.frame_yaw.size(), b.frame_yaw.size());
  ASSERT_EQ(a.frame_origin.size(), b.frame_origin.size());
  for (std::size_t i = 0; i < a.frame_yaw.size(); ++i) {
    EXPECT_SAME_DOUBLE(a.frame_yaw[i], b.frame_yaw[i]);
    expect_same(a.frame_origin[i], b.frame_origin[i]);
  }
  ASSERT_EQ(a.positions.size(), b.positions.size());
  for (std::size_t k = 0; k < a.positions.size(); ++k) {
    ASSERT_EQ(a.positions[k].size(), b.positions[k].size());
    for (std::size_t i = 0; i < a.positions[k].size(); ++i) expect_same(a.positions[k][i], b.positions[k][i]);
  }
  EXPECT_EQ(a.targets, b.targets);
  ASSERT_EQ(a.obstacles.size(), b.obstacles.size());
  for (std::size_t i = 0; i < a.obstacles.size(); ++i) {
    expect_same(a.obstacles[i].center, b.obstacles[i].center);
    EXPECT_SAME_DOUBLE(a.obstacles[i].radius, b.obstacles[i].radius);
    EXPECT_SAME_DOUBLE(a.obstacles[i].height, b.obstacles[i].height);
  }
}

TEST(TruthJson, RoundTripIsBitExact) {
  const fact::Truth t = awkward_truth();
  const std::string text = fact::truth_to_json(t);
  const fact::Truth back = fact::truth_from_json(text);
  expect_same(t, back);
  EXPECT_EQ(fact::truth_to_json(back), text);
  EXPECT_NE(text.find("\"format\": \"fact-truth-v1\""), std::string::npos) << text;
}

// A drifting scenario's truth carries each round's drifted frames, so that a result (which
// describes the latest round's drifted frames) can be checked against the file (review, session
// 34: fact-simgen --drift-* wrote only the undrifted frames). Both or neither per drone, every
// round alike.
TEST(TruthJson, DriftedFramesRoundTripAndMustBeComplete) {
  fact::SimOptions o;
  o.drones = 3;
  o.rounds = 3;
  o.drift_yaw = 0.05;
  o.drift_position = 0.1;
  o.seed = 4;
  const fact::Truth t = fact::generate_scenario(o).truth;
  const std::string text = fact::truth_to_json(t);
  const fact::Truth back = fact::truth_from_json(text);
  ASSERT_EQ(back.drifted_yaw.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k)
    for (std::size_t i = 0; i < 3; ++i) {
      EXPECT_SAME_DOUBLE(back.drifted_yaw[k][i], t.drifted_yaw[k][i]);
      expect_same(back.drifted_origin[k][i], t.drifted_origin[k][i]);
    }
  EXPECT_NE(back.drifted_yaw[2][1], back.frame_yaw[1]);  // the drift is there
  EXPECT_EQ(fact::truth_to_json(back), text);
  const std::vector<fact::TruePose> poses = fact::true_poses_in_round(back, back.ids[0], 2);
  const std::vector<fact::TruePose> want = fact::true_poses_in_round(t, t.ids[0], 2);
  ASSERT_EQ(poses.size(), want.size());
  for (std::size_t i = 0; i < poses.size(); ++i) EXPECT_SAME_DOUBLE(poses[i].yaw, want[i].yaw);

  const auto error = [](const std::string& s) { return error_of([&] { fact::truth_from_json(s); }); };
  const std::size_t last = text.rfind("\"frame_yaw\"");
  ASSERT_NE(last, std::string::npos);
  const std::string no_yaw = text.substr(0, last) + "\"frame_yew\"" + text.substr(last + 11);
  EXPECT_NE(error(no_yaw).find("frame_yew"), std::string::npos) << error(no_yaw);  // unknown key, named
  fact::Truth partial = t;
  partial.drifted_yaw.pop_back();
  EXPECT_NE(error_of([&] { fact::truth_to_json(partial); }).find("drifted_yaw has 2 entries, expected 3"),
            std::string::npos);
  // The first round without them, the next with them: named where they appear.
  fact::Truth plain = t;
  plain.drifted_yaw.clear();
  plain.drifted_origin.clear();
  const std::string without = fact::truth_to_json(plain);
  EXPECT_EQ(without.find("frame_origin\": [", without.find("\"rounds\"")), std::string::npos);
  const std::string key = "\"position\": [";
  const std::string round_key = "\"drones\": {";
  const std::size_t second_round = without.find(round_key, without.find(round_key) + 1);
  ASSERT_NE(second_round, std::string::npos) << without;
  const std::size_t at = without.find(key, second_round);
  const std::string mixed = without.substr(0, at) + "\"frame_yaw\": 0, \"frame_origin\": [0, 0, 0], " + without.substr(at);
  EXPECT_NE(error(mixed).find("rounds[1]"), std::string::npos) << error(mixed);
  EXPECT_NE(error(mixed).find("given here only"), std::string::npos) << error(mixed);
}

TEST(TruthJson, EmptyTruthRoundTrips) {
  const fact::Truth back = fact::truth_from_json(fact::truth_to_json(fact::Truth{}));
  EXPECT_TRUE(back.ids.empty());
  EXPECT_TRUE(back.positions.empty());
  EXPECT_TRUE(back.obstacles.empty());
}

TEST(TruthJson, DecoderErrorsNameTheField) {
  const std::string text = fact::truth_to_json(awkward_truth());
  const auto error = [](const std::string& t) { return error_of([&] { fact::truth_from_json(t); }); };
  // The first round's targets of drone 1 are [-1, 5, 30, -1]; make one of them unknown.
  EXPECT_EQ(error(edit(text, "[-1, 5, 30, -1]", "[-1, 6, 30, -1]")), R"(rounds[0].drones["1"].targets[1]: expected a listed drone id or -1 (false positive), got 6)");

  const std::string first_id = "\"id\": 1,";
  EXPECT_EQ(error(edit(text, first_id, "\"id\": 5,")), "drones[1].id: duplicate id 5 (also at drones[0])");
  EXPECT_EQ(error(edit(text, "fact-truth-v1", "fact-truth")), R"(format: expected "fact-truth-v1", got "fact-truth")");
  EXPECT_EQ(error(edit(text, "\"obstacles\": [", "\"obstacles\": [{\"center\": [0, 0, 0], \"radius\": 1}, ")),
            "obstacles[0].height: required key is missing");
}

TEST(TruthJson, RoundDroneKeysMustBeListedIds) {
  fact::Truth t = awkward_truth();
  t.ids = {5, 1};
  t.frame_yaw.pop_back();
  t.frame_origin.pop_back();
  for (auto& p : t.positions) p.pop_back();
  for (auto& g : t.targets) {
    g.pop_back();
    g[0] = {1};
    g[1] = {5, -1};
  }
  const std::string two = fact::truth_to_json(t);
  // Rename drone 1 in the third round's "drones" to an unknown key and to nothing.
  const std::string key = "\"1\": {";
  const std::size_t third = two.find(key, two.find(key, two.find(key) + 1) + 1);
  ASSERT_NE(third, std::string::npos) << two;
  const std::string unknown = two.substr(0, third) + "\"4\": {" + two.substr(third + key.size());
  EXPECT_EQ(error_of([&] { fact::truth_from_json(unknown); }), R"(rounds[2].drones["4"]: drone 4 is not listed in "drones")");
  const std::string dropped = two.substr(0, third) + "\"x\": {" + two.substr(third + key.size());
  EXPECT_EQ(error_of([&] { fact::truth_from_json(dropped); }),
            R"(rounds[2].drones["x"]: expected a drone id in decimal as the key, got "x")");
}

TEST(TruthJson, MissingDroneInARoundIsNamed) {
  const std::string text = R"({"format": "fact-truth-v1",
    "drones": [{"id": 0, "frame_yaw": 0, "frame_origin": [0, 0, 0]},
               {"id": 1, "frame_yaw": 1, "frame_origin": [1, 0, 0]}],
    "rounds": [{"drones": {"0": {"position": [0, 0, 1], "targets": [1]}}}],
    "obstacles": []})";
  EXPECT_EQ(error_of([&] { fact::truth_from_json(text); }),
            R"(rounds[0].drones["1"]: drone 1 is missing (truth has every drone in every round))");
}

TEST(TruthJson, EncoderRejectsMismatchedSizes) {
  fact::Truth t = awkward_truth();
  t.positions[1].pop_back();
  std::string m = error_of([&] { fact::truth_to_json(t); });
  EXPECT_NE(m.find("positions[1] has 2 entries, expected 3"), std::string::npos) << m;
  t = awkward_truth();
  t.targets[0][0] = {7};
  m = error_of([&] { fact::truth_to_json(t); });
  EXPECT_NE(m.find(R"(rounds[0].drones["5"].targets[0])"), std::string::npos) << m;
  EXPECT_NE(m.find("target 7"), std::string::npos) << m;
}

// A camera's intrinsics.json (fact-detector's and fact-preflight's --png-dir): the six keys, each
// error naming its key and value; other keys ignored; intrinsics_error's checks applied.
TEST(IntrinsicsJson, ReadsTheSixKeysAndNamesWhatIsWrong) {
  const fact::CameraIntrinsics k =
      fact::intrinsics_from_json(R"({"width": 64, "height": 48, "fx": 213, "fy": 212.5, "cx": 32, "cy": 24, "note": 1})");
  EXPECT_EQ(k.width, 64);
  EXPECT_EQ(k.height, 48);
  EXPECT_EQ(k.fy, 212.5);
  EXPECT_EQ(error_of([&] { fact::intrinsics_from_json("not json"); }).rfind("invalid JSON", 0), 0u);
  EXPECT_EQ(error_of([&] { fact::intrinsics_from_json(R"({"width": 64, "height": 48, "fy": 1, "cx": 1, "cy": 1})"); }),
            "fx: required key is missing");
  EXPECT_EQ(error_of([&] { fact::intrinsics_from_json(R"({"width": 0, "height": 48, "fx": 1, "fy": 1, "cx": 1, "cy": 1})"); }),
            "width: 0 is not a whole number 1 … 8192");
  EXPECT_EQ(error_of([&] { fact::intrinsics_from_json(R"({"width": 6.5, "height": 48, "fx": 1, "fy": 1, "cx": 1, "cy": 1})"); }),
            "width: expected an integer, got 6.5");
  EXPECT_NE(error_of([&] { fact::intrinsics_from_json(R"({"width": 64, "height": 48, "fx": -1, "fy": 1, "cx": 1, "cy": 1})"); })
                .find("fx"),
            std::string::npos);
}

}  // namespace
