// fact-run-report: the evaluation math (effective VIO frames, averages on the circle, relative
// frames, error summaries, observation naming, mutual edges) and the app on synthetic LCM logs
// written here with lcm::LogFile: a correct certified result exits 0 with ~0 errors in the JSON, a
// wrong one exits 4, an uncertified one 3, a log without truth or a garbage file 2.
#include "evaluate.h"
#include "fact/odometry_t.hpp"
#include "fact/sim_clock_t.hpp"
#include "fact/swarm_result_t.hpp"
#include "fact/swarm_rounds_t.hpp"
#include "fact/truth_t.hpp"
#include "run_command.h"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>

namespace {

namespace fs = std::filesystem;
using Eigen::Vector3d;
using fact::report::Frame;

TEST(RunReportMath, EffectiveFrameMapsTheVioPoseOntoTheTruePose) {
  const double frame_yaw = 2.0;
  const Vector3d origin(1, -2, 0.1), vio(0.5, 0.3, 1.2);
  const Vector3d world = Eigen::AngleAxisd(frame_yaw, Vector3d::UnitZ()) * vio + origin;
  const Frame f = fact::report::effective_frame(world, frame_yaw + 0.4, vio, 0.4);
  EXPECT_NEAR(f.yaw, frame_yaw, 1e-12);
  EXPECT_NEAR((f.origin - origin).norm(), 0, 1e-12);
}

TEST(RunReportMath, YawsAverageOnTheCircleAndRelativeFrames) {
  fact::report::FrameAverage a;
  a.add({M_PI - 0.1, Vector3d(0, 0, 0)});
  a.add({-M_PI + 0.1, Vector3d(2, 0, 0)});
  EXPECT_NEAR(std::abs(a.mean().yaw), M_PI, 1e-12);  // not 0, the arithmetic mean
  EXPECT_NEAR(a.mean().origin.x(), 1, 1e-12);
  const Frame r{M_PI / 2, Vector3d(1, 1, 0)}, j{M_PI, Vector3d(1, 3, 0.5)};
  const Frame rel = fact::report::relative(r, j);
  EXPECT_NEAR(rel.yaw, M_PI / 2, 1e-12);
  EXPECT_NEAR((rel.origin - Vector3d(2, 0, 0.5)).norm(), 0, 1e-12);  // (0,2) seen from a frame turned 90°
}

TEST(RunReportMath, SummaryLeavesOutTheReference) {
  std::vector<fact::report::DroneError> e = {
      fact::report::compare(0, {0, Vector3d::Zero()}, {0, Vector3d::Zero()}),
      fact::report::compare(1, {0.02, Vector3d(1, 0, 0)}, {0, Vector3d(1.1, 0, 0)}),
      fact::report::compare(2, {-0.04, Vector3d(0, 1, 0)}, {0, Vector3d(0, 1.3, 0)}),
      fact::report::compare(3, {2 * M_PI - 0.01, Vector3d(0, 0, 1)}, {0, Vector3d(0, 0, 1.2)})};
  const auto s = fact::report::summarize(e, 0);
  EXPECT_EQ(s.drones, 3);
  EXPECT_NEAR(s.yaw_mae, (0.02 + 0.04 + 0.01) / 3, 1e-12);  // 2π − 0.01 wraps to 0.01
  EXPECT_NEAR(s.yaw_max, 0.04, 1e-12);
  EXPECT_NEAR(s.position_median, 0.2, 1e-12);
  EXPECT_NEAR(s.position_max, 0.3, 1e-12);
}

TEST(RunReportMath, ObservationsNameTheNearestDroneAndMutualEdges) {
  const std::map<int, Vector3d> pos = {{0, {0, 0, 1}}, {1, {3, 0, 1}}, {2, {0, 4, 1}}};
  double d = 0;
  EXPECT_EQ(fact::report::nearest_drone({2.8, 0.1, 1}, 0, pos, 0.6, &d), 1);
  EXPECT_NEAR(d, std::sqrt(0.05), 1e-12);
  EXPECT_EQ(fact::report::nearest_drone({1.5, 0, 1}, 0, pos, 0.6, &d), -1);   // nobody within the gate
  EXPECT_EQ(fact::report::nearest_drone({0.1, 0, 1}, 0, pos, 0.6, &d), -1);   // only itself
  // (observer, round, target): 0 and 1 saw each other in round 0; 0 saw 2 in round 0 but 2 saw 0
  // only in round 1.
  std::vector<fact::report::Sighting> s;
  for (auto [observer, round, target] : {std::tuple{0, 0, 1}, {1, 0, 0}, {0, 0, 2}, {2, 1, 0}}) {
    fact::report::Sighting x;
    x.observer = observer;
    x.round = round;
    x.target = target;
    s.push_back(x);
  }
  const auto edges = fact::report::mutual_edges(s);
  ASSERT_EQ(edges.size(), 1u);
  EXPECT_EQ(edges[0], std::make_pair(0, 1));
}

// ---------------------------------------------------------------------------------------------- the app

constexpr int64_t kEpoch = 1700000000000000LL;

struct Truth {
  double frame_yaw;
  Vector3d origin;
};
const std::vector<Truth> kFrames = {{0.3, {0, 0, 0}}, {2.0, {3, 1, 0}}, {-1.0, {-1, 4, 0}}};

void write_event(lcm::LogFile& log, int64_t t, const std::string& ch, const std::string& bytes) {
  lcm::LogEvent e;
  e.timestamp = t;
  e.channel = ch;
  e.datalen = static_cast<int32_t>(bytes.size());
  e.data = const_cast<char*>(bytes.data());
  log.writeEvent(&e);
}

template <class T>
std::string encode(const T& m) {
  std::string b(static_cast<size_t>(m.getEncodedSize()), '\0');
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

// A 10 s run of 3 drones hovering at 1.5 m; drone 0 publishes `status` at 8 s with drone 2's
// yaw off by `yaw_error` (no result at all when `status` is "none", a truncated one when "damaged"). With `drift` (rad/s), drone
// 2's VIO yaw drifts at that rate, the result gives its frame as during round 1, and the log has
// the swarm's rounds 0 (closed at 3 s) and 1 (closed at 6 s).
std::string write_log(const std::string& status, double yaw_error, bool with_truth = true, double drift = 0,
                      int result_drones = 3) {
  const std::string path = (fs::temp_directory_path() / ("fact-report-" + std::to_string(getpid()) + "-" + status +
                                                         std::to_string(yaw_error) + "-" + std::to_string(drift) + "-" +
                                                         std::to_string(result_drones) + ".lcm")).string();
  const auto drift_at = [&](int i, double t_s) { return i == 2 ? drift * t_s : 0.0; };
  lcm::LogFile log(path, "w");
  fact::swarm_result_t r{};
  r.utime = kEpoch + 8000000;
  r.drone_id = 0;
  r.mode = "associated";
  r.status = status;
  r.reference = 0;
  r.rounds_used = 2;
  r.num_drones = result_drones;
  for (int i = 0; i < result_drones; ++i) {
    fact::drone_pose_t p{};
    p.id = i;
    const Eigen::Matrix3d R0 = Eigen::AngleAxisd(-kFrames[0].frame_yaw, Vector3d::UnitZ()).toRotationMatrix();
    const Vector3d t = R0 * (kFrames[i].origin - kFrames[0].origin);
    p.yaw = kFrames[i].frame_yaw - kFrames[0].frame_yaw + (i == 2 ? yaw_error : 0) + drift_at(i, 4.5);  // round 1's mean
    for (int k = 0; k < 3; ++k) p.position[k] = t[k];
    p.resolved = true;
    r.drones.push_back(p);
  }
  fact::swarm_rounds_t rounds{};
  rounds.drone_id = 0;
  rounds.complete_rounds = 2;
  rounds.num_drones = 3;
  rounds.drone_ids = {0, 1, 2};
  for (int k = 0; k < 2; ++k)
    for (int i = 0; i < 3; ++i) {
      fact::round_packet_t p{};
      p.utime = kEpoch + (k + 1) * 3000000;
      p.drone_id = i;
      p.round = k;
      rounds.packets.push_back(p);
    }
  rounds.num_packets = static_cast<int32_t>(rounds.packets.size());
  rounds.utime = kEpoch + 6000000;
  for (int64_t t = 0; t <= 10000000; t += 100000) {
    fact::sim_clock_t c;
    c.utime = kEpoch + t;
    c.rate = 0;
    write_event(log, kEpoch + t, "FACT_SIM_CLOCK", encode(c));
    fact::truth_t tr;
    tr.utime = kEpoch + t;
    tr.num_drones = 3;
    for (int i = 0; i < 3; ++i) {
      const Vector3d vio(0.1 * i, 0.2, 1.5);
      const double vio_yaw = 0.5 * i + 0.1 * t * 1e-6;
      fact::odometry_t o{};
      o.utime = kEpoch + t;
      o.drone_id = i;
      for (int k = 0; k < 3; ++k) o.position[k] = vio[k];
      o.yaw = vio_yaw;
      write_event(log, kEpoch + t, "FACT_VIO_RAW_" + std::to_string(i), encode(o));
      const double frame_yaw = kFrames[i].frame_yaw + drift_at(i, t * 1e-6);  // the drifted frame
      const Vector3d world = Eigen::AngleAxisd(frame_yaw, Vector3d::UnitZ()) * vio + kFrames[i].origin;
      tr.drone_ids.push_back(i);
      tr.frame_yaw.push_back(kFrames[i].frame_yaw);
      tr.frame_origin.push_back({kFrames[i].origin.x(), kFrames[i].origin.y(), kFrames[i].origin.z()});
      tr.position.push_back({world.x(), world.y(), world.z()});
      tr.yaw.push_back(frame_yaw + vio_yaw);
    }
    if (with_truth) write_event(log, kEpoch + t, "FACT_TRUTH", encode(tr));
    if (drift != 0 && t == 6000000) write_event(log, kEpoch + t, "FACT_SWARM_ROUNDS_0", encode(rounds));
    if (t == 8000000 && status != "none") {  // in log order; "damaged": cut in half
      std::string bytes = encode(r);
      if (status == "damaged") bytes.resize(bytes.size() / 2);
      write_event(log, kEpoch + t, "FACT_RESULT_0", bytes);
    }
  }
  return path;
}

using fact::test::Ran;

Ran run_report(const std::string& args) { return fact::test::run_command(std::string(FACT_RUN_REPORT_BINARY) + " " + args); }

nlohmann::json read_json(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

// The estimate describes the frames during the latest round; the report judges it against them,
// and also shows the errors against the frames averaged from takeoff, which drift has moved.
TEST(RunReportApp, DriftingFramesAreJudgedDuringTheLatestRound) {
  const std::string log = write_log("certified", 0, true, 0.05);
  const std::string json = log + ".json";
  const Ran r = run_report("--log " + log + " --json " + json);
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("averaged over round 1"), std::string::npos) << r.out;
  const auto j = read_json(json);
  EXPECT_EQ(j["truth_round"], 1);
  EXPECT_NEAR(j["yaw_max_rad"].get<double>(), 0, 1e-3);  // frames over 3 … 6 s: mean drift 0.225 rad
  // Over 0 … 8 s the mean drift is 0.2 rad, so drone 2 is 0.025 rad off those frames.
  EXPECT_NEAR(j["whole_window"]["yaw_max_rad"].get<double>(), 0.025, 2e-3);
  fs::remove(log);
  fs::remove(json);
}

TEST(RunReportApp, CorrectCertifiedResultExitsZeroWithItsNumbers) {
  const std::string log = write_log("certified", 0);
  const std::string json = log + ".json", png = log + ".png";
  const Ran r = run_report("--log " + log + " --json " + json + " --png " + png);
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("certified and correct"), std::string::npos) << r.out;
  const auto j = read_json(json);
  EXPECT_EQ(j["format"], "fact-run-report-v1");
  EXPECT_TRUE(j["certified"].get<bool>());
  EXPECT_NEAR(j["yaw_mae_rad"].get<double>(), 0, 1e-9);
  EXPECT_NEAR(j["position_max_m"].get<double>(), 0, 1e-9);
  EXPECT_NEAR(j["time_to_certified_s"].get<double>(), 8.0, 0.11);  // published at 8 s of sim time
  EXPECT_EQ(j["rounds_used"], 2);
  EXPECT_EQ(j["drones"].size(), 3u);
  std::ifstream in(png, std::ios::binary);
  char sig[8] = {0};
  in.read(sig, 8);
  EXPECT_EQ(std::string(sig + 1, 3), "PNG");
  EXPECT_GT(fs::file_size(png), 5000u);
  for (const auto& f : {log, json, png}) fs::remove(f);
}

// A NaN pose, or a result that leaves out drones of the truth, is not "certified and correct"
// (review, helper-24: a NaN error counted as 0 and a reference-only result passed, exit 0).
TEST(RunReportApp, NanOrIncompleteCertifiedResultExitsFour) {
  const std::string nan = write_log("certified", std::nan("")), only_reference = write_log("certified", 0, true, 0, 1);
  const Ran n = run_report("--log " + nan);
  EXPECT_EQ(n.code, 4) << n.out;
  EXPECT_NE(n.out.find("CERTIFIED BUT WRONG"), std::string::npos) << n.out;
  const Ran o = run_report("--log " + only_reference);
  EXPECT_EQ(o.code, 4) << o.out;
  EXPECT_NE(o.out.find("CERTIFIED BUT INCOMPLETE: the result leaves out drone(s) 1, 2 of the truth"), std::string::npos)
      << o.out;
  for (const auto& f : {nan, only_reference}) fs::remove(f);
}

TEST(RunReportApp, WrongCertifiedResultExitsFourAndUncertifiedThree) {
  const std::string wrong = write_log("certified", 0.1), json = wrong + ".json";
  const Ran r = run_report("--log " + wrong + " --json " + json);
  EXPECT_EQ(r.code, 4) << r.out;
  EXPECT_NE(r.out.find("CERTIFIED BUT WRONG"), std::string::npos) << r.out;
  EXPECT_NEAR(read_json(json)["yaw_max_rad"].get<double>(), 0.1, 1e-9);
  EXPECT_EQ(run_report("--log " + wrong + " --yaw-bound 0.2").code, 0);  // within a looser bound
  const std::string ambiguous = write_log("ambiguous", 0);
  const Ran a = run_report("--log " + ambiguous);
  EXPECT_EQ(a.code, 3) << a.out;
  EXPECT_NE(a.out.find("NOT CERTIFIED"), std::string::npos) << a.out;
  for (const auto& f : {wrong, json, ambiguous}) fs::remove(f);
}

TEST(RunReportApp, NoResultIsNotCertifiedAndJudgesNothing) {
  const std::string log = write_log("none", 0);
  const std::string json = log + ".json", png = log + ".png";
  const Ran r = run_report("--log " + log + " --json " + json + " --png " + png);
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("NOT CERTIFIED: no result on FACT_RESULT_<id>"), std::string::npos) << r.out;
  const auto j = read_json(json);
  EXPECT_FALSE(j["certified"].get<bool>());
  EXPECT_EQ(j["status"], "no_result");
  EXPECT_EQ(j["exit_code"], 3);
  EXPECT_TRUE(j["drones"].empty());
  EXPECT_NEAR(j["sim_duration_s"].get<double>(), 10.0, 1e-9);
  EXPECT_GT(fs::file_size(png), 5000u);  // the true trajectories are still drawn
  for (const auto& f : {log, json, png}) fs::remove(f);
}

// A report or picture that cannot be written whole exits 2 and keeps the earlier file: the write
// goes to a partial file renamed over it (the report was written in place, so a full disk left a
// truncated report behind). Here a file-size limit of 1 KiB (ulimit -f, SIGXFSZ ignored so the
// write fails with EFBIG) stands in for the full disk.
TEST(RunReportApp, AReportThatCannotBeWrittenWholeKeepsTheEarlierOne) {
  const std::string log = write_log("certified", 0);
  const std::string json = log + ".json", png = log + ".png";
  ASSERT_EQ(run_report("--log " + log + " --json " + json + " --png " + png).code, 0);
  const auto read_all = [](const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string report = read_all(json), picture = read_all(png);
  ASSERT_GT(report.size(), 1024u);  // larger than the limit below
  const auto limited = [&](const std::string& args) {
    return fact::test::run_command("bash -c 'trap \"\" XFSZ; ulimit -f 1; exec " + std::string(FACT_RUN_REPORT_BINARY) +
                                   " " + args + "'");
  };
  const Ran r = limited("--log " + log + " --json " + json);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("cannot write the report"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(json), std::string::npos) << r.out;
  EXPECT_TRUE(read_all(json) == report) << "the earlier report was changed";
  const Ran p = limited("--log " + log + " --png " + png);
  EXPECT_EQ(p.code, 2) << p.out;
  EXPECT_NE(p.out.find("cannot write the picture " + png), std::string::npos) << p.out;
  EXPECT_TRUE(read_all(png) == picture) << "the earlier picture was changed";
  for (const auto& entry : fs::directory_iterator(fs::path(log).parent_path()))  // no partial file left
    for (const auto& f : {json, png}) EXPECT_EQ(entry.path().string().rfind(f + ".partial", 0), std::string::npos) << entry.path();
  for (const auto& f : {log, json, png}) fs::remove(f);
}

TEST(RunReportApp, BadInputExitsTwoWithTheReason) {
  const std::string no_truth = write_log("certified", 0, false);
  const Ran r = run_report("--log " + no_truth);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("no ground truth on FACT_TRUTH"), std::string::npos) << r.out;
  fs::remove(no_truth);
  const std::string garbage = (fs::temp_directory_path() / "fact-report-garbage.lcm").string();
  std::ofstream(garbage) << "not an lcm log at all";
  const Ran g = run_report("--log " + garbage);
  EXPECT_EQ(g.code, 2);
  EXPECT_NE(g.out.find("error"), std::string::npos) << g.out;
  fs::remove(garbage);
  EXPECT_EQ(run_report("--log /nonexistent/run.lcm").code, 2);
  const std::string damaged = write_log("damaged", 0);  // its only result cannot be decoded
  const Ran d = run_report("--log " + damaged);
  EXPECT_EQ(d.code, 2) << d.out;
  EXPECT_NE(d.out.find("damaged log: 1 undecodable result(s) on FACT_RESULT_0"), std::string::npos) << d.out;
  fs::remove(damaged);
  const Ran b = run_report("--log x --yaw-bound -1");
  EXPECT_EQ(b.code, 2);
  EXPECT_NE(b.out.find("--yaw-bound"), std::string::npos) << b.out;
}

}  // namespace
