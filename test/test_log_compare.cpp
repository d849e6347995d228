// fact-log-compare: a replay's log against its recorded run (scripts/replay.sh). The app runs as a
// process on logs written here with lcm::LogFile from the real lcm-gen types; exit codes and the
// lines it prints are checked.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "fact/app_status_t.hpp"
#include "fact/swarm_result_t.hpp"
#include "fact/swarm_rounds_t.hpp"
#include "lcm_log_files.h"
#include "run_command.h"

namespace fs = std::filesystem;

namespace {

using Event = fact::test::LoggedEvent;
using fact::test::write_log;

template <typename Msg>
Event event(int64_t timestamp, const std::string& channel, const Msg& m) {
  std::string data(static_cast<size_t>(m.getEncodedSize()), '\0');
  m.encode(data.data(), 0, static_cast<int>(data.size()));
  return {timestamp, channel, data};
}

fact::swarm_result_t result(int drone, int64_t utime, int rounds, const std::string& status) {
  fact::swarm_result_t m{};
  m.utime = utime;
  m.drone_id = drone;
  m.mode = "associated";
  m.status = status;
  m.rounds_used = rounds;
  m.num_drones = 0;
  return m;
}

fact::swarm_rounds_t rounds(int drone, int64_t utime, int complete) {
  fact::swarm_rounds_t m{};
  m.utime = utime;
  m.drone_id = drone;
  m.complete_rounds = complete;
  return m;
}

fact::app_status_t status(int drone, const std::string& app, const std::string& state, const std::string& counter,
                          int64_t value) {
  fact::app_status_t m{};
  m.drone_id = drone;
  m.app = app;
  m.state = state;
  m.num_counters = 1;
  m.counter_names = {counter};
  m.counter_values = {value};
  return m;
}

// Drone `id`'s run: two complete rounds from its gossip, two results from its solver, the planner's
// decisions, and each app's counters in a heartbeat before and after. Without result_1 (or
// rounds_1) it is a log that lost them.
std::vector<Event> run_of_drone(int id, bool with_result_1 = true, bool with_rounds_1 = true) {
  const std::string s = std::to_string(id);
  std::vector<Event> v;
  v.push_back(event(1, "FACT_STATUS", status(id, "fact-solver", "running", "results_published", 0)));
  v.push_back(event(2, "FACT_STATUS", status(id, "fact-gossip", "running", "swarm_rounds_published", 0)));
  if (with_rounds_1) v.push_back(event(10, "FACT_SWARM_ROUNDS_" + s, rounds(id, 10, 1)));
  if (with_result_1) v.push_back(event(11, "FACT_RESULT_" + s, result(id, 10, 1, "ambiguous")));
  v.push_back(event(12, "FACT_STATUS", status(id, "fact-planner", "move round 1: ambiguous", "x", 0)));
  v.push_back(event(20, "FACT_SWARM_ROUNDS_" + s, rounds(id, 20, 2)));
  v.push_back(event(21, "FACT_RESULT_" + s, result(id, 20, 2, "certified")));
  v.push_back(event(22, "FACT_STATUS", status(id, "fact-planner", "done round 2: certified", "x", 0)));
  v.push_back(event(30, "FACT_STATUS", status(id, "fact-solver", "running", "results_published", 2)));
  v.push_back(event(31, "FACT_STATUS", status(id, "fact-gossip", "running", "swarm_rounds_published", 2)));
  return v;
}

std::vector<Event> run_of_drone_0(bool with_result_1 = true, bool with_rounds_1 = true) {
  return run_of_drone(0, with_result_1, with_rounds_1);
}

using fact::test::Ran;

class LogCompare : public fact::test::TempDirTest {
 protected:
  LogCompare() : TempDirTest("fact-log-compare") {}
  Ran compare(const std::vector<Event>& original, const std::vector<Event>& replay, const std::string& flags = "") {
    write_log(dir_ / "run.lcm", original);
    write_log(dir_ / "replay.lcm", replay);
    return fact::test::run_command(std::string(FACT_LOG_COMPARE_BINARY) + " " + (dir_ / "run.lcm").string() + " " +
                                   (dir_ / "replay.lcm").string() + " " + flags);
  }
};

TEST_F(LogCompare, SameResultsAndDecisionsMatch) {
  const Ran r = compare(run_of_drone_0(), run_of_drone_0());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("== the replay matches the recorded run"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("move round 1 → done round 2"), std::string::npos) << r.out;
}

TEST_F(LogCompare, DifferentDecisionsDiffer) {
  std::vector<Event> replay = run_of_drone_0();
  ASSERT_EQ(replay[4].channel, "FACT_STATUS");  // the planner's "move round 1"
  replay[4] = event(12, "FACT_STATUS", status(0, "fact-planner", "spin round 1: spin", "x", 0));
  const Ran r = compare(run_of_drone_0(), replay);
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("DIFFERENT"), std::string::npos) << r.out;
}

// A recorder that missed a result or a round the apps published (their FACT_STATUS counters grew by
// more than the log holds): exit 2, naming the log, the drone, the channel and the counts,
// whichever log it is.
TEST_F(LogCompare, LogThatLostAResultIsRefused) {
  const Ran r = compare(run_of_drone_0(false), run_of_drone_0());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("run.lcm: drone 0: FACT_RESULT_0 lacks 1 message(s): fact-solver counted 2 published "
                       "(results_published, from its first to its last FACT_STATUS in the log), the log holds 1"),
            std::string::npos)
      << r.out;
  EXPECT_EQ(r.out.find("== the replay"), std::string::npos) << r.out;
}

TEST_F(LogCompare, LogThatLostARoundIsRefused) {
  const Ran r = compare(run_of_drone_0(), run_of_drone_0(true, false), "--no-planner");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("replay.lcm: drone 0: FACT_SWARM_ROUNDS_0 lacks 1 message(s): fact-gossip counted 2"),
            std::string::npos)
      << r.out;
}

// A recording that began after the apps had published (their first heartbeat in it already
// counts 5) is complete from there on: not refused.
TEST_F(LogCompare, LogStartedLateIsNotRefused) {
  std::vector<Event> late = run_of_drone_0();
  late[0] = event(1, "FACT_STATUS", status(0, "fact-solver", "running", "results_published", 5));
  late[late.size() - 2] = event(30, "FACT_STATUS", status(0, "fact-solver", "running", "results_published", 7));
  const Ran r = compare(late, run_of_drone_0());
  EXPECT_EQ(r.code, 0) << r.out;
  // One more counted than recorded after that first heartbeat is a loss again.
  late[late.size() - 2] = event(30, "FACT_STATUS", status(0, "fact-solver", "running", "results_published", 8));
  const Ran lost = compare(late, run_of_drone_0());
  EXPECT_EQ(lost.code, 2) << lost.out;
  EXPECT_NE(lost.out.find("FACT_RESULT_0 lacks 1 message(s): fact-solver counted 3"), std::string::npos) << lost.out;
}

// Only the drones compared are checked: drone 1's loss does not refuse --drones 0.
TEST_F(LogCompare, OnlyComparedDronesAreChecked) {
  std::vector<Event> original = run_of_drone(0), replay = run_of_drone(0);
  for (const Event& e : run_of_drone(1, false)) original.push_back(e);
  for (const Event& e : run_of_drone(1)) replay.push_back(e);
  const Ran zero = compare(original, replay, "--drones 0");
  EXPECT_EQ(zero.code, 0) << zero.out;
  const Ran both = compare(original, replay);
  EXPECT_EQ(both.code, 2) << both.out;
  EXPECT_NE(both.out.find("drone 1: FACT_RESULT_1 lacks 1 message(s)"), std::string::npos) << both.out;
}

// Without the apps' counters (a log recorded by other tools) nothing can be said to be lost.
TEST_F(LogCompare, NoCountersNoCheck) {
  const auto without_counters = [](std::vector<Event> v) {
    std::vector<Event> kept;
    for (const Event& e : v) {
      fact::app_status_t m;
      if (e.channel == "FACT_STATUS" && m.decode(e.data.data(), 0, static_cast<int>(e.data.size())) > 0 &&
          m.app != "fact-planner")
        continue;  // the solver's and the gossip's heartbeats
      kept.push_back(e);
    }
    return kept;
  };
  const Ran r = compare(without_counters(run_of_drone_0(false)), without_counters(run_of_drone_0()), "--no-planner");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("1 replay results for inputs the recording missed"), std::string::npos) << r.out;
}

}  // namespace

// Several results for one input (fact-rounds-publish --incremental stamps its rounds with one
// utime): each recorded result must be in the replay. Before, only the last result of an input was
// kept and compared, and a replay whose first result differed matched (review, session 32).
TEST_F(LogCompare, EveryResultOfOneInputIsCompared) {
  const auto run = [](const std::string& first_status) {
    std::vector<Event> v;
    v.push_back(event(11, "FACT_RESULT_0", result(0, 10, 1, first_status)));
    v.push_back(event(21, "FACT_RESULT_0", result(0, 10, 2, "certified")));
    v.push_back(event(31, "FACT_RESULT_0", result(0, 10, 3, "certified")));
    return v;
  };
  const Ran same = compare(run("ambiguous"), run("ambiguous"), "--no-planner");
  EXPECT_EQ(same.code, 0) << same.out;
  std::vector<Event> replay = run("ambiguous");
  replay[0] = event(11, "FACT_RESULT_0", result(0, 10, 3, "certified"));  // the first replaced by the third
  const Ran r = compare(run("ambiguous"), replay, "--no-planner");
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("1 recorded results differ, 0 are missing from the replay"), std::string::npos) << r.out;
}

// Comparing planner decisions in a log that has none is an error (2) naming the drone, not a
// difference (1): a log compared with itself "differed".
TEST_F(LogCompare, NoPlannerDecisionsToCompareIsAnError) {
  const std::vector<Event> results_only = {event(11, "FACT_RESULT_0", result(0, 10, 1, "certified"))};
  const Ran r = compare(results_only, results_only);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("no planner decisions for drone 0 on FACT_STATUS"), std::string::npos) << r.out;
  EXPECT_EQ(compare(results_only, results_only, "--no-planner").code, 0);
}
