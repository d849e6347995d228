// fact-bench-e2e --summarize: batches of e2e_runs.csv (seed ranges run apart) merged into one
// e2e_runs.csv and summarised per swarm size, run as a process on CSV files written here.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "run_command.h"
#include "temp_dir.h"

namespace fs = std::filesystem;

namespace {

const std::string kHeader =
    "drones,seed,exit,certified,correct,certified_wrong,time_to_certified_s,rounds,yaw_mae_rad,yaw_max_rad,"
    "position_median_m,position_max_m,sim_s,wall_s,fact-detector_cpu_percent,fact-vio-relay_cpu_percent,"
    "fact-gossip_cpu_percent,fact-solver_cpu_percent,fact-planner_cpu_percent,fact-fc-bridge_cpu_percent";

// N = 4 seeds 1–3 (two certified and correct, one not certified after 8 rounds) ...
const std::vector<std::string> kBatchA = {
    "4,1,0,1,1,0,10,1,0.004,0.01,0.03,0.05,12,15,6,1,2,1,3,2",
    "4,2,0,1,1,0,20,2,0.006,0.01,0.05,0.08,22,25,6,1,2,1,3,2",
    "4,3,3,0,0,0,nan,8,nan,nan,nan,nan,150,160,6,1,2,1,3,2",
};
// ... and N = 4 seeds 4–5 (one correct, one certified but wrong) with N = 2 seed 1.
const std::vector<std::string> kBatchB = {
    "4,4,0,1,1,0,30,3,0.008,0.02,0.04,0.06,32,35,8,1,2,1,3,2",
    "4,5,4,1,0,1,15,2,0.3,0.5,1.2,2,18,20,6,1,2,1,3,2",
    "2,1,0,1,1,0,9.8,1,0.005,0.01,0.02,0.03,12,14,5,1,1,1,2,1",
};

class E2eBenchSummary : public fact::test::TempDirTest {
 protected:
  E2eBenchSummary() : TempDirTest("fact-e2e-summary") {}

  std::string write_csv(const std::string& name, const std::string& header, const std::vector<std::string>& rows) {
    const fs::path path = dir_ / name;
    std::ofstream out(path);
    out << header << '\n';
    for (const std::string& r : rows) out << r << '\n';
    return path.string();
  }

  fact::test::Ran summarize(const std::vector<std::string>& files, const fs::path& out_dir) {
    std::string cmd = std::string(FACT_BENCH_E2E_BINARY) + " --summarize";
    for (const std::string& f : files) cmd += " '" + f + "'";
    return fact::test::run_command(cmd + " --out-dir '" + out_dir.string() + "'");
  }

};

std::vector<std::string> lines_of(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

// e2e.csv rows by swarm size: column name -> value.
std::map<int, std::map<std::string, double>> read_summary(const fs::path& path) {
  const std::vector<std::string> lines = lines_of(path);
  std::map<int, std::map<std::string, double>> out;
  if (lines.empty()) return out;
  std::vector<std::string> columns;
  std::stringstream header(lines[0]);
  for (std::string c; std::getline(header, c, ',');) columns.push_back(c);
  for (size_t i = 1; i < lines.size(); ++i) {
    std::stringstream row(lines[i]);
    std::map<std::string, double> values;
    size_t k = 0;
    for (std::string v; std::getline(row, v, ',') && k < columns.size(); ++k) values[columns[k]] = std::stod(v);
    out[static_cast<int>(values["drones"])] = values;
  }
  return out;
}

TEST_F(E2eBenchSummary, MergesBatchesInSizeAndSeedOrderAndSummarisesEachSize) {
  const std::string a = write_csv("a.csv", kHeader, kBatchA), b = write_csv("b.csv", kHeader, kBatchB);
  const fs::path out = dir_ / "out";
  const fact::test::Ran ran = summarize({a, b}, out);
  ASSERT_EQ(ran.code, 0) << ran.out;

  const std::vector<std::string> merged = lines_of(out / "e2e_runs.csv");
  ASSERT_EQ(merged.size(), 7u);
  EXPECT_EQ(merged[0], kHeader);
  EXPECT_EQ(merged[1], kBatchB[2]);  // N = 2 first, then N = 4 by seed, values as read
  EXPECT_EQ(merged[2], kBatchA[0]);
  EXPECT_EQ(merged[4], kBatchA[2]);
  EXPECT_EQ(merged[5], kBatchB[0]);
  EXPECT_EQ(merged[6], kBatchB[1]);

  const auto summary = read_summary(out / "e2e.csv");
  ASSERT_EQ(summary.size(), 2u);
  const auto& n4 = summary.at(4);
  EXPECT_EQ(n4.at("runs"), 5);
  EXPECT_DOUBLE_EQ(n4.at("success_percent"), 60);
  EXPECT_EQ(n4.at("certified_wrong"), 1);
  EXPECT_DOUBLE_EQ(n4.at("time_median_s"), 20);  // of the correct runs: 10, 20, 30
  EXPECT_DOUBLE_EQ(n4.at("time_p90_s"), 30);
  EXPECT_DOUBLE_EQ(n4.at("rounds_median"), 2);
  EXPECT_NEAR(n4.at("yaw_mae_rad"), 0.006, 1e-12);      // mean over the correct runs
  EXPECT_NEAR(n4.at("position_median_m"), 0.04, 1e-12);  // median over the correct runs
  EXPECT_NEAR(n4.at("cpu_per_drone_percent"), (4 * 15 + 17) / 5.0, 1e-9);  // every run, all apps
  const auto& n2 = summary.at(2);
  EXPECT_EQ(n2.at("runs"), 1);
  EXPECT_DOUBLE_EQ(n2.at("success_percent"), 100);
  EXPECT_DOUBLE_EQ(n2.at("time_median_s"), 9.8);
  EXPECT_NEAR(n2.at("cpu_per_drone_percent"), 11, 1e-9);

  const std::vector<std::string> text = lines_of(out / "e2e_summary.txt");
  ASSERT_EQ(text.size(), 4u);
  EXPECT_NE(text[0].find("summary of 6 runs"), std::string::npos) << text[0];
}

TEST_F(E2eBenchSummary, ARunInTwoBatchesIsRefusedNamingBothAndNothingIsWritten) {
  const std::string a = write_csv("a.csv", kHeader, kBatchA);
  const std::string b = write_csv("b.csv", kHeader, {kBatchB[0], kBatchA[1]});
  const fs::path out = dir_ / "out";
  const fact::test::Ran ran = summarize({a, b}, out);
  EXPECT_EQ(ran.code, 2) << ran.out;
  EXPECT_NE(ran.out.find("b.csv:3: N=4 seed 2 is already in " + a + ":3"), std::string::npos) << ran.out;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(E2eBenchSummary, AMalformedRowNamesFileLineColumnAndValue) {
  const fs::path out = dir_ / "out";
  const std::string bad_number = write_csv("n.csv", kHeader, {kBatchA[0], "4,2,0,1,1,0,20,2,abc,0.01,0.05,0.08,22,25,6,1,2,1,3,2"});
  fact::test::Ran ran = summarize({bad_number}, out);
  EXPECT_EQ(ran.code, 2);
  EXPECT_NE(ran.out.find("n.csv:3: column yaw_mae_rad: 'abc' is not a number"), std::string::npos) << ran.out;

  const std::string short_row = write_csv("s.csv", kHeader, {"4,2,0,1,1,0,20"});
  ran = summarize({short_row}, out);
  EXPECT_EQ(ran.code, 2);
  EXPECT_NE(ran.out.find("s.csv:2: 7 fields, expected 20"), std::string::npos) << ran.out;

  const std::string bad_size = write_csv("z.csv", kHeader, {"1,2,0,1,1,0,20,2,0.004,0.01,0.05,0.08,22,25,6,1,2,1,3,2"});
  ran = summarize({bad_size}, out);
  EXPECT_EQ(ran.code, 2);
  EXPECT_NE(ran.out.find("z.csv:2: column drones: '1' is not an integer in 2..32"), std::string::npos) << ran.out;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(E2eBenchSummary, AForeignOrMissingFileExits2AndAnUnwritableOutDirExits1) {
  const std::string foreign = write_csv("f.csv", "drones,runs,success_percent", {"4,5,100"});
  fact::test::Ran ran = summarize({foreign}, dir_ / "out");
  EXPECT_EQ(ran.code, 2);
  EXPECT_NE(ran.out.find("f.csv: line 1: not an e2e_runs.csv header: 'drones,runs,success_percent'"), std::string::npos)
      << ran.out;

  ran = summarize({(dir_ / "missing.csv").string()}, dir_ / "out");
  EXPECT_EQ(ran.code, 2);
  EXPECT_NE(ran.out.find("missing.csv: cannot be read"), std::string::npos) << ran.out;

  const std::string a = write_csv("a.csv", kHeader, kBatchA);
  ran = summarize({a}, fs::path(a) / "under-a-file");
  EXPECT_EQ(ran.code, 1);
  EXPECT_NE(ran.out.find("--out-dir: cannot write"), std::string::npos) << ran.out;

  ran = fact::test::run_command(std::string(FACT_BENCH_E2E_BINARY) + " --drones 2 --seeds 1");
  EXPECT_EQ(ran.code, 2);
  EXPECT_NE(ran.out.find("--repo and --build are required"), std::string::npos) << ran.out;
}

// A value a flag's check refuses, an unknown flag and an empty value exit 2 like every app's bad
// flag (CLI11_PARSE exited 105, 109 and 105), naming the flag; --help exits 0.
TEST_F(E2eBenchSummary, BadFlagsExit2AndHelpExits0) {
  const std::string bench = FACT_BENCH_E2E_BINARY;
  fact::test::Ran ran = fact::test::run_command(bench + " --seeds 010");
  EXPECT_EQ(ran.code, 2) << ran.out;
  EXPECT_NE(ran.out.find("--seeds"), std::string::npos) << ran.out;
  ran = fact::test::run_command(bench + " --no-such-flag");
  EXPECT_EQ(ran.code, 2) << ran.out;
  EXPECT_NE(ran.out.find("--no-such-flag"), std::string::npos) << ran.out;
  ran = fact::test::run_command(bench + " --seeds ''");
  EXPECT_EQ(ran.code, 2) << ran.out;
  EXPECT_NE(ran.out.find("empty"), std::string::npos) << ran.out;
  ran = fact::test::run_command(bench + " --help");
  EXPECT_EQ(ran.code, 0) << ran.out;
  EXPECT_NE(ran.out.find("--seeds"), std::string::npos) << ran.out;
}

}  // namespace
