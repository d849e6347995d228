// fact-bench-sdp-sweep: fact::sdp::solve over many seeds of each instance kind, for before/after
// comparisons of a solver change. fact-bench-sdp has one instance per row, and one instance can
// take another path through the solver (a Newton level more, a polish that does not certify) and
// move its row by 2× either way; a change is judged on sums over seeds and kinds, the paper's
// realistic costs among them. Each instance's time is the fastest of --rounds medians of --reps
// solves. With --baseline (CSV files of an earlier run, from the old build; several: the fastest
// per instance) it prints the ratio of the sums per kind and size, and the instances whose
// status or objective changed. Writes kind,noise,n,seed,ms,iterations,status,objective,methods.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "common/cli_checks.h"
#include "csv_fields.h"
#include "fact/sdp.h"
#include "instances.h"
#include "results_file.h"
#include "stats.h"

namespace {

using Clock = std::chrono::steady_clock;

// The kinds: the paper's cost Q (2N × 2N, d = 2) of synthetic rounds with N + 1, 2N or 3N rounds
// (plain, paper2, paper3), the complex form of the first (tight), and random PSD C = B Bᵀ with B
// 2N × 3, 2N × (N + 1) or 2N × 2N of standard normals.
const std::vector<std::string> kKinds = {"plain", "tight", "paper2", "paper3", "rank3", "rank_n1", "fullrank"};

bool is_paper_kind(const std::string& kind) {
  return kind == "plain" || kind == "tight" || kind == "paper2" || kind == "paper3";
}

// Seed s of size N is 7000 + 100·N + s (the instances of BENCHMARKS.md's sweeps since session 40).
std::uint64_t instance_seed(int drones, int s) { return 7000 + 100 * static_cast<std::uint64_t>(drones) + s; }

Eigen::MatrixXd cost_of(const std::string& kind, int drones, double noise, std::uint64_t seed) {
  const int n = 2 * drones;
  if (kind == "rank3") return fact::bench::random_psd(n, 3, seed);
  if (kind == "rank_n1") return fact::bench::random_psd(n, drones + 1, seed);
  if (kind == "fullrank") return fact::bench::random_psd(n, n, seed);
  const int rounds = kind == "paper2" ? 2 * drones : kind == "paper3" ? 3 * drones : drones + 1;
  return fact::bench::synthetic_cost(drones, rounds, noise, kind == "tight", seed);
}

// One instance's line of the CSV.
struct Row {
  std::string kind, noise;  // noise "-" for the random kinds
  int n = 0, seed = 0, iterations = 0;
  double ms = 0, objective = 0;
  std::string status, methods;  // methods: the stages' names joined by '>'
};

const char* kHeader = "kind,noise,n,seed,ms,iterations,status,objective,methods";

// An objective with every digit the comparison reads (std::to_string keeps 6 decimals: 0.000000
// for the zero optima).
std::string objective_text(double objective) {
  char text[40];
  std::snprintf(text, sizeof text, "%.12e", objective);
  return text;
}

std::string csv_line(const Row& r) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "%.5f,%d,", r.ms, r.iterations);
  return r.kind + "," + r.noise + "," + std::to_string(r.n) + "," + std::to_string(r.seed) + "," + buf + r.status + "," +
         objective_text(r.objective) + "," + r.methods;
}

Row solve_row(const std::string& kind, const std::string& noise_text, double noise, int drones, int s, int reps,
              int rounds) {
  const Eigen::MatrixXd C = cost_of(kind, drones, noise, instance_seed(drones, s));
  Row row;
  row.kind = kind;
  row.noise = noise_text;
  row.n = drones;
  row.seed = s;
  fact::sdp::Result result;
  row.ms = INFINITY;
  for (int round = 0; round < rounds; ++round) {
    std::vector<double> ms;
    for (int rep = 0; rep < reps; ++rep) {
      const Clock::time_point start = Clock::now();
      result = fact::sdp::solve(C, 2);
      ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
    }
    row.ms = std::min(row.ms, fact::bench::median(ms));
  }
  row.iterations = result.iterations;
  row.status = fact::sdp::to_string(result.status);
  row.objective = result.objective;
  for (const fact::sdp::Stage& stage : result.stages) row.methods += (row.methods.empty() ? "" : ">") + stage.method;
  return row;
}

// --- baselines ---

using Key = std::tuple<std::string, std::string, int, int>;  // kind, noise, n, seed
Key key_of(const Row& r) { return {r.kind, r.noise, r.n, r.seed}; }

// A field as a number, the error naming the file and line (where) and the column.
double number_field(const std::string& text, const std::string& where, const char* name) {
  try {
    return fact::bench::parse_number(text, name);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(where + ": " + e.what());
  }
}

// The rows of baseline files; an instance in several keeps its fastest time.
std::map<Key, Row> read_baselines(const std::vector<std::string>& paths) {
  std::map<Key, Row> rows;
  for (const std::string& path : paths) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error("baseline " + path + ": cannot be read");
    std::string line;
    if (!std::getline(in, line) || line != kHeader)
      throw std::runtime_error("baseline " + path + ": line 1 is '" + line + "', not the header '" + kHeader + "'");
    for (int number = 2; std::getline(in, line); ++number) {
      const std::string where = path + ":" + std::to_string(number);
      const std::vector<std::string> f = fact::bench::split_csv_line(line);
      if (f.size() != 9)
        throw std::runtime_error(where + ": " + std::to_string(f.size()) + " fields, expected 9 (" + kHeader + ")");
      Row r;
      r.kind = f[0];
      r.noise = f[1];
      r.n = static_cast<int>(number_field(f[2], where, "n"));
      r.seed = static_cast<int>(number_field(f[3], where, "seed"));
      r.ms = number_field(f[4], where, "ms");
      r.iterations = static_cast<int>(number_field(f[5], where, "iterations"));
      r.status = f[6];
      r.objective = number_field(f[7], where, "objective");
      r.methods = f[8];
      if (!(r.ms > 0) || !std::isfinite(r.ms)) throw std::runtime_error(where + ": field ms is " + f[4] + ", not a time");
      auto [it, added] = rows.emplace(key_of(r), r);
      if (!added && r.ms < it->second.ms) it->second = r;
    }
  }
  return rows;
}

// An objective that moved by more than this (relative to max(1, |objective|)) counts as changed.
constexpr double kObjectiveChange = 1e-6;

// Sums per (kind, noise, N), against the baselines when given; the changed instances, one line each.
void print_summary(const std::vector<Row>& rows, const std::map<Key, Row>& base) {
  struct Sum {
    double ms = 0, base_ms = 0;
    int instances = 0, compared = 0;
  };
  std::map<std::tuple<std::string, std::string, int>, Sum> sums;
  std::vector<std::string> changes;
  for (const Row& r : rows) {
    Sum& s = sums[{r.kind, r.noise, r.n}];
    s.ms += r.ms;
    ++s.instances;
    const auto b = base.find(key_of(r));
    if (b == base.end()) continue;
    s.base_ms += b->second.ms;
    ++s.compared;
    const double scale = std::max(1.0, std::abs(b->second.objective));
    if (b->second.status != r.status || std::abs(b->second.objective - r.objective) > kObjectiveChange * scale)
      changes.push_back(r.kind + " noise " + r.noise + " N = " + std::to_string(r.n) + " seed " + std::to_string(r.seed) +
                        ": " + b->second.status + " " + objective_text(b->second.objective) + " -> " + r.status + " " +
                        objective_text(r.objective));
  }
  std::printf("\n%-9s %6s %4s %9s %6s", "kind", "noise", "N", "sum_ms", "seeds");
  if (!base.empty()) std::printf(" %9s %7s", "base_ms", "ratio");
  std::printf("\n");
  for (const auto& [key, s] : sums) {
    const auto& [kind, noise, n] = key;
    std::printf("%-9s %6s %4d %9.4f %6d", kind.c_str(), noise.c_str(), n, s.ms, s.instances);
    if (!base.empty() && s.compared == s.instances) std::printf(" %9.4f %7.3f", s.base_ms, s.ms / s.base_ms);
    else if (!base.empty()) std::printf("   (%d of %d seeds in the baseline)", s.compared, s.instances);
    std::printf("\n");
  }
  if (base.empty()) return;
  std::printf("\n%zu instance(s) with another status or objective than the baseline%s\n", changes.size(),
              changes.empty() ? "" : ":");
  for (const std::string& c : changes) std::printf("  %s\n", c.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> kinds{"plain", "paper2", "rank_n1", "fullrank"};
  std::vector<int> sizes{5, 8, 12, 16};
  std::vector<double> noises{0.05};
  std::vector<std::string> baselines;
  int seeds = 6, reps = 20, rounds = 3;
  std::string out = "bench/results/sdp_sweep.csv";
  CLI::App cli{"fact-bench-sdp-sweep: fact::sdp::solve over seeds of each instance kind (instance s of size N:\n"
               "seed 7000 + 100N + s); each time the fastest of --rounds medians of --reps solves. Sums per kind\n"
               "and size, against --baseline files of an earlier run when given. Writes --out."};
  cli.add_option("--kinds", kinds, "plain, tight, paper2, paper3 (the paper's cost, N + 1 / 2N / 3N rounds; tight: "
                                   "its complex form), rank3, rank_n1, fullrank (random PSD of that rank)")
      ->delimiter(',')
      ->check(CLI::IsMember(kKinds))
      ->capture_default_str();
  cli.add_option("--sizes", sizes, "swarm sizes N (C is 2N × 2N)")
      ->delimiter(',')
      ->check(CLI::Range(2, 400))
      ->capture_default_str();
  cli.add_option("--noise", noises, "noise levels of the paper's kinds (per-axis σ / range)")
      ->delimiter(',')
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cli.add_option("--seeds", seeds, "seeds per kind, noise and size")
      ->check(fact::app::decimal_integer())
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cli.add_option("--reps", reps, "solves per median")
      ->check(fact::app::decimal_integer())
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cli.add_option("--rounds", rounds, "medians per instance (the fastest is kept)")
      ->check(fact::app::decimal_integer())
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cli.add_option("--baseline", baselines, "CSV files of an earlier run to compare against (fastest per instance)")
      ->delimiter(',')
      ->check(CLI::ExistingFile);
  cli.add_option("--out", out, "CSV file written")->capture_default_str();
  if (const int code = fact::app::parse_command_line(cli, argc, argv); code >= 0) return code;

  std::map<Key, Row> base;
  try {
    base = read_baselines(baselines);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fact-bench-sdp-sweep: %s\n", e.what());
    return 2;
  }
  struct Job {
    std::string kind, noise_text;
    double noise;
  };
  std::vector<Job> jobs;
  for (const std::string& kind : kinds) {
    if (!is_paper_kind(kind)) {
      jobs.push_back({kind, "-", 0.0});
      continue;
    }
    for (double noise : noises) {
      char text[32];
      std::snprintf(text, sizeof text, "%g", noise);
      jobs.push_back({kind, text, noise});
    }
  }
  std::vector<Row> rows;
  const std::size_t total = jobs.size() * sizes.size() * static_cast<std::size_t>(seeds);
  std::string csv = std::string(kHeader) + "\n";
  for (const Job& job : jobs)
    for (int drones : sizes)
      for (int s = 0; s < seeds; ++s) {
        std::fprintf(stderr, "[%zu/%zu] %s noise %s N = %d seed %d\n", rows.size() + 1, total, job.kind.c_str(),
                     job.noise_text.c_str(), drones, s);
        rows.push_back(solve_row(job.kind, job.noise_text, job.noise, drones, s, reps, rounds));
        csv += csv_line(rows.back()) + "\n";
      }
  print_summary(rows, base);
  try {
    fact::bench::write_results_file(out, csv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fact-bench-sdp-sweep: %s\n", e.what());
    return 1;
  }
  std::printf("\nwrote %s\n", out.c_str());
  return 0;
}
