// fact-bench-e2e: whole simulated initializations, headless and faster than real time. For each
// swarm size and seed it runs the main job (scripts/run-sim.sh --fast --quiet --no-build: fact-sim
// plus every drone's full app set in private network namespaces, then fact-run-report against the
// ground truth), and collects per run: the verdict (certified and correct, not certified, or
// certified but wrong), the simulated time to the certified result, the rounds used, the yaw and
// position errors, and the CPU time of every app of every drone. It writes one CSV row per run
// (e2e_runs.csv), a summary per size (e2e.csv, e2e_summary.txt) and prints progress per run.
// With --summarize it runs nothing: it merges the e2e_runs.csv of several batches (seed ranges
// run apart, e.g. on different days) into one e2e_runs.csv and summarises them the same way.
// scripts/bench-e2e.sh builds it, runs it and draws the PNG (bench/plots/e2e.gp).
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <tuple>
#include <utility>
#include <vector>

#include "common/cli_checks.h"
#include "csv_fields.h"
#include "results_file.h"
#include "stats.h"

namespace {

namespace fs = std::filesystem;

struct Options {
  std::vector<int> drones = {2, 4, 6, 8};
  int seeds = 50;
  int first_seed = 1;
  std::string repo;        // the source tree (for scripts/run-sim.sh and the world)
  std::string build;       // the build tree run-sim.sh uses (BUILD_DIR)
  std::string world;       // "" = the default world (with obstacles)
  std::string out_dir = "bench/results";
  std::string work_dir;    // per-run folders; "" = <out_dir>/e2e-runs
  double max_sim_time = 150;
  double fast_rate = 8;
  bool keep_runs = false;  // keep every run's folder (logs, LCM log, picture)
  std::vector<std::string> summarize;  // e2e_runs.csv files to merge instead of running
};

// The CPU of one app kind, summed over a run's drones (s), and the run's length.
struct Run {
  int drones = 0, seed = 0, exit_code = -1;
  bool certified = false, correct = false, certified_wrong = false;
  double time_to_certified = NAN;  // simulated s
  int rounds = 0;
  double yaw_mae = NAN, yaw_max = NAN, position_median = NAN, position_max = NAN;
  double sim_seconds = NAN, wall_seconds = NAN;
  std::map<std::string, double> cpu_s;  // app -> CPU s summed over the drones
  std::string reason;
};

const std::vector<std::string> kApps = {"fact-detector", "fact-vio-relay", "fact-gossip",
                                        "fact-solver",   "fact-planner",   "fact-fc-bridge"};

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

double number_or_nan(const nlohmann::json& j, const char* key) {
  auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : NAN;
}

// Reads run-sim.sh's report.json (fact-run-report-v1) into *r; false (with r->reason) if unusable.
bool read_report(const fs::path& path, Run* r) {
  std::ifstream in(path);
  if (!in) {
    r->reason = "no report.json";
    return false;
  }
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    r->reason = std::string("report.json: ") + e.what();
    return false;
  }
  r->certified = j.value("certified", false);
  r->time_to_certified = number_or_nan(j, "time_to_certified_s");
  r->rounds = j.value("rounds_used", 0);
  r->yaw_mae = number_or_nan(j, "yaw_mae_rad");
  r->yaw_max = number_or_nan(j, "yaw_max_rad");
  r->position_median = number_or_nan(j, "position_median_m");
  r->position_max = number_or_nan(j, "position_max_m");
  r->sim_seconds = number_or_nan(j, "sim_duration_s");
  if (j.contains("reason") && j["reason"].is_string()) r->reason = j["reason"].get<std::string>();
  return true;
}

// Reads run-sim.sh's cpu.csv (app,drone,cpu_s,wall_s,cpu_percent) into r->cpu_s.
void read_cpu(const fs::path& path, Run* r) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string app, drone, cpu, wall;
    if (!std::getline(ss, app, ',') || !std::getline(ss, drone, ',') || !std::getline(ss, cpu, ',') ||
        !std::getline(ss, wall, ','))
      continue;
    try {
      r->cpu_s[app] += std::stod(cpu);
      r->wall_seconds = std::stod(wall);
    } catch (const std::exception&) {
    }
  }
}

Run run_one(const Options& o, int drones, int seed) {
  Run r;
  r.drones = drones;
  r.seed = seed;
  const fs::path dir = fs::path(o.work_dir) / ("n" + std::to_string(drones) + "-s" + std::to_string(seed));
  fs::remove_all(dir);
  std::string cmd = "BUILD_DIR=" + shell_quote(o.build) + " " + shell_quote(o.repo + "/scripts/run-sim.sh") +
                    " --no-build --quiet --fast --drones " + std::to_string(drones) + " --seed " +
                    std::to_string(seed) + " --max-sim-time " + std::to_string(o.max_sim_time) +
                    " --fast-rate " + std::to_string(o.fast_rate) + " --out " + shell_quote(dir.string());
  if (!o.world.empty()) cmd += " --world " + shell_quote(o.world);
  cmd += " > " + shell_quote((dir.string() + ".out")) + " 2>&1";
  fs::create_directories(dir);
  const int status = std::system(cmd.c_str());
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  read_report(dir / "report.json", &r);
  read_cpu(dir / "cpu.csv", &r);
  r.correct = r.exit_code == 0;
  r.certified_wrong = r.exit_code == 4;
  if (r.reason.empty() && !r.correct) r.reason = "run-sim.sh exit " + std::to_string(r.exit_code);
  if (!o.keep_runs && r.correct) {
    fs::remove_all(dir);
    fs::remove(dir.string() + ".out");
  }
  return r;
}

// The header of e2e_runs.csv: the run columns, then one CPU column per app.
std::string runs_header() {
  std::string h =
      "drones,seed,exit,certified,correct,certified_wrong,time_to_certified_s,rounds,yaw_mae_rad,yaw_max_rad,"
      "position_median_m,position_max_m,sim_s,wall_s";
  for (const std::string& a : kApps) h += "," + a + "_cpu_percent";
  return h;
}

using fact::bench::parse_number;
using fact::bench::split_csv_line;

int parse_count(const std::string& field, const std::string& column, int lo, int hi) {
  const double v = parse_number(field, column);
  if (!(v >= lo && v <= hi) || v != std::floor(v))
    throw std::invalid_argument("column " + column + ": '" + field + "' is not an integer in " + std::to_string(lo) +
                                ".." + std::to_string(hi));
  return static_cast<int>(v);
}

// One e2e_runs.csv row back into a Run (CPU columns: % of a core per drone → CPU s).
Run parse_run_row(const std::vector<std::string>& f, const std::vector<std::string>& columns) {
  if (f.size() != columns.size())
    throw std::invalid_argument(std::to_string(f.size()) + " fields, expected " + std::to_string(columns.size()));
  Run r;
  r.drones = parse_count(f[0], columns[0], 2, 32);
  r.seed = parse_count(f[1], columns[1], 0, 1 << 30);
  r.exit_code = parse_count(f[2], columns[2], 0, 255);
  r.certified = parse_count(f[3], columns[3], 0, 1);
  r.correct = parse_count(f[4], columns[4], 0, 1);
  r.certified_wrong = parse_count(f[5], columns[5], 0, 1);
  r.time_to_certified = parse_number(f[6], columns[6]);
  r.rounds = parse_count(f[7], columns[7], 0, 1 << 20);
  double* numbers[] = {&r.yaw_mae, &r.yaw_max, &r.position_median, &r.position_max, &r.sim_seconds, &r.wall_seconds};
  for (size_t k = 0; k < 6; ++k) *numbers[k] = parse_number(f[8 + k], columns[8 + k]);
  for (size_t k = 0; k < kApps.size(); ++k) {
    const double pct = parse_number(f[14 + k], columns[14 + k]);
    if (std::isfinite(pct) && r.sim_seconds > 0) r.cpu_s[kApps[k]] = pct / 100 * r.drones * r.sim_seconds;
  }
  if (!r.correct) r.reason = "run-sim.sh exit " + std::to_string(r.exit_code);
  return r;
}

// Every run of the e2e_runs.csv files, in (drones, seed) order. Throws std::invalid_argument
// naming the file, line and column on a missing file, a foreign header, a malformed row or a
// (drones, seed) pair that two rows share.
std::vector<Run> read_runs_files(const std::vector<std::string>& paths) {
  const std::vector<std::string> columns = split_csv_line(runs_header());
  std::map<std::pair<int, int>, std::string> where;  // (drones, seed) -> file:line
  std::vector<Run> runs;
  for (const std::string& path : paths) {
    std::ifstream in(path);
    if (!in) throw std::invalid_argument(path + ": cannot be read");
    std::string line;
    if (!std::getline(in, line) || line != runs_header())
      throw std::invalid_argument(path + ": line 1: not an e2e_runs.csv header: '" + line + "'");
    for (int number = 2; std::getline(in, line); ++number) {
      if (line.empty()) continue;
      const std::string at = path + ":" + std::to_string(number);
      Run r;
      try {
        r = parse_run_row(split_csv_line(line), columns);
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(at + ": " + e.what());
      }
      const auto [it, fresh] = where.emplace(std::make_pair(r.drones, r.seed), at);
      if (!fresh)
        throw std::invalid_argument(at + ": N=" + std::to_string(r.drones) + " seed " + std::to_string(r.seed) +
                                    " is already in " + it->second);
      runs.push_back(r);
    }
  }
  std::sort(runs.begin(), runs.end(),
            [](const Run& a, const Run& b) { return std::tie(a.drones, a.seed) < std::tie(b.drones, b.seed); });
  return runs;
}

// The median of the finite values.
double median(std::vector<double> v) { return fact::bench::median(fact::bench::finite_values(std::move(v))); }

double mean(const std::vector<double>& v) {
  double s = 0;
  int n = 0;
  for (double x : v)
    if (std::isfinite(x)) s += x, ++n;
  return n ? s / n : NAN;
}

void write_run_row(std::ostream& out, const Run& r) {
  out << r.drones << ',' << r.seed << ',' << r.exit_code << ',' << r.certified << ',' << r.correct << ','
      << r.certified_wrong << ',' << r.time_to_certified << ',' << r.rounds << ',' << r.yaw_mae << ',' << r.yaw_max
      << ',' << r.position_median << ',' << r.position_max << ',' << r.sim_seconds << ',' << r.wall_seconds;
  for (const std::string& a : kApps) {
    const auto it = r.cpu_s.find(a);
    // % of one core per drone, at real time: CPU s / (drones × simulated s).
    const double pct = it == r.cpu_s.end() || !(r.sim_seconds > 0) ? NAN : 100 * it->second / (r.drones * r.sim_seconds);
    out << ',' << pct;
  }
  out << '\n';
}

// Per-drone CPU of all apps, % of one core at real time.
double drone_cpu_percent(const Run& r) {
  if (!(r.sim_seconds > 0)) return NAN;
  double s = 0;
  for (const std::string& a : kApps) {
    const auto it = r.cpu_s.find(a);
    if (it != r.cpu_s.end()) s += it->second;
  }
  return 100 * s / (r.drones * r.sim_seconds);
}

// e2e.csv and e2e_summary.txt in out_dir from the runs of each size; the summary is also printed.
void write_summaries(const std::string& out_dir, const std::map<int, std::vector<Run>>& by_size,
                     const std::string& title) {
  std::ostringstream csv;
  csv << "drones,runs,success_percent,certified_wrong,time_median_s,time_p90_s,rounds_median,yaw_mae_rad,"
         "position_median_m,cpu_per_drone_percent\n";
  std::ostringstream summary;
  summary << "fact-bench-e2e: " << title << "\n";
  summary << "  N  runs  success  cert-wrong  t_cert median / p90 (sim s)  rounds  yaw MAE (rad)  pos err median (m)"
             "  CPU/drone (% core)\n";
  for (const auto& [n, runs] : by_size) {
    int ok = 0, wrong = 0;
    std::vector<double> times, rounds, yaw, pos, cpu;
    for (const Run& r : runs) {
      ok += r.correct;
      wrong += r.certified_wrong;
      if (r.correct) {
        times.push_back(r.time_to_certified);
        rounds.push_back(r.rounds);
        yaw.push_back(r.yaw_mae);
        pos.push_back(r.position_median);
      }
      cpu.push_back(drone_cpu_percent(r));
    }
    // Nearest rank, ⌈0.9 n⌉ (it was index ⌊0.9 n⌋: the maximum of 10 runs)
    const double p90 = fact::bench::nearest_rank(times, 90);
    const double success = 100.0 * ok / static_cast<double>(runs.size());
    csv << n << ',' << runs.size() << ',' << success << ',' << wrong << ',' << median(times) << ',' << p90 << ','
        << median(rounds) << ',' << mean(yaw) << ',' << median(pos) << ',' << mean(cpu) << '\n';
    char line[256];
    std::snprintf(line, sizeof line, "%3d  %4zu  %6.1f%%  %10d  %13.1f / %-13.1f  %6.1f  %13.4f  %18.3f  %18.1f\n", n,
                  runs.size(), success, wrong, median(times), p90, median(rounds), mean(yaw), median(pos), mean(cpu));
    summary << line;
  }
  fact::bench::write_results_file(out_dir + "/e2e.csv", csv.str());
  fact::bench::write_results_file(out_dir + "/e2e_summary.txt", summary.str());
  std::cout << summary.str();
}

// --summarize: reads every file before writing anything, so a bad file leaves out_dir as it was
// (and out_dir's own e2e_runs.csv may be one of the inputs).
int summarize(const Options& o) {
  std::vector<Run> runs;
  try {
    runs = read_runs_files(o.summarize);
  } catch (const std::invalid_argument& e) {
    std::cerr << "fact-bench-e2e: error: --summarize: " << e.what() << "\n";
    return 2;
  }
  std::map<int, std::vector<Run>> by_size;
  for (const Run& r : runs) by_size[r.drones].push_back(r);
  std::ostringstream runs_csv;
  runs_csv << runs_header() << '\n';
  for (const Run& r : runs) write_run_row(runs_csv, r);
  std::string title = "summary of " + std::to_string(runs.size()) + " runs from";
  for (const std::string& f : o.summarize) title += " " + f;
  try {
    fact::bench::write_results_file(o.out_dir + "/e2e_runs.csv", runs_csv.str());
    write_summaries(o.out_dir, by_size, title);
  } catch (const std::exception& e) {
    std::cerr << "fact-bench-e2e: error: --out-dir: cannot write " << o.out_dir << ": " << e.what() << "\n";
    return 1;
  }
  std::cout << "wrote " << o.out_dir << "/e2e_runs.csv, e2e.csv, e2e_summary.txt\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App cli{"fact-bench-e2e: whole simulated initializations (scripts/run-sim.sh --fast) per swarm size and seed:\n"
               "success rate, certified-wrong count, time to the certified result, rounds, errors, CPU per app."};
  cli.add_option("--drones", o.drones, "Swarm sizes (comma separated)")->delimiter(',')->capture_default_str();
  cli.add_option("--seeds", o.seeds, "Seeds per size")->capture_default_str()->check(fact::app::decimal_integer());
  cli.add_option("--first-seed", o.first_seed, "First seed (>= 0)")->capture_default_str()
      ->check(fact::app::decimal_integer())->check(CLI::Range(0, 1 << 30));
  cli.add_option("--repo", o.repo, "Source tree (scripts/run-sim.sh); required unless --summarize");
  cli.add_option("--build", o.build, "Build tree with the apps (BUILD_DIR of run-sim.sh); required unless --summarize");
  cli.add_option("--world", o.world, "fact-world-v1 world (default: run-sim.sh's, the default world with obstacles)");
  cli.add_option("--out-dir", o.out_dir, "Where e2e_runs.csv, e2e.csv and e2e_summary.txt go")->capture_default_str();
  cli.add_option("--work-dir", o.work_dir, "Per-run folders (default <out-dir>/e2e-runs; failed runs are kept)");
  cli.add_option("--max-sim-time", o.max_sim_time, "Simulated s before a run gives up")->capture_default_str();
  cli.add_option("--fast-rate", o.fast_rate, "Cap of the simulation speed (x real time)")->capture_default_str();
  cli.add_flag("--keep-runs", o.keep_runs, "Keep every run's folder, not only the failed ones");
  cli.add_option("--summarize", o.summarize,
                 "Run nothing: merge these e2e_runs.csv files (batches of seeds) into <out-dir>/e2e_runs.csv\n"
                 "and write e2e.csv and e2e_summary.txt from them");
  if (const int code = fact::app::parse_command_line(cli, argc, argv); code >= 0) return code;
  if (!o.summarize.empty()) return summarize(o);
  // (NaN passes CLI11's ranges; a rate of 0 or a missing run-sim.sh made every run fail, and the
  // benchmark wrote a 0 % success table and exited 0; review, session 34)
  for (const auto& [flag, v] : {std::pair<const char*, double>{"--max-sim-time", o.max_sim_time}, {"--fast-rate", o.fast_rate}})
    if (!(v > 0 && std::isfinite(v))) {
      std::cerr << "fact-bench-e2e: error: " << flag << ": expected a finite number > 0, got " << v << "\n";
      return 2;
    }
  if (o.repo.empty() || o.build.empty()) {
    std::cerr << "fact-bench-e2e: error: --repo and --build are required to run (or give --summarize FILE...)\n";
    return 2;
  }
  for (int n : o.drones)
    if (n < 2 || n > 32) {
      std::cerr << "fact-bench-e2e: error: --drones: expected sizes 2..32, got " << n << "\n";
      return 2;
    }
  if (o.seeds < 1) {
    std::cerr << "fact-bench-e2e: error: --seeds: expected >= 1, got " << o.seeds << "\n";
    return 2;
  }
  if (access((o.repo + "/scripts/run-sim.sh").c_str(), X_OK) != 0) {
    std::cerr << "fact-bench-e2e: error: --repo: " << o.repo << "/scripts/run-sim.sh is not an executable script\n";
    return 2;
  }
  if (!fs::is_directory(o.build)) {
    std::cerr << "fact-bench-e2e: error: --build: " << o.build << " is not a folder\n";
    return 2;
  }
  if (o.work_dir.empty()) o.work_dir = o.out_dir + "/e2e-runs";
  for (const auto& [flag, dir] : {std::pair<const char*, std::string>{"--out-dir", o.out_dir}, {"--work-dir", o.work_dir}}) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (!fs::is_directory(dir)) {
      std::cerr << "fact-bench-e2e: error: " << flag << ": cannot make the folder " << dir
                << (ec ? ": " + ec.message() : std::string()) << "\n";
      return 1;
    }
  }

  // e2e_runs.csv is rewritten whole after every run: what finished is kept, an old file is never
  // left half-written.
  std::ostringstream runs_csv;
  runs_csv << runs_header() << '\n';
  int failed_setup = 0;  // run-sim.sh's exit code when it refused to run at all

  try {
    std::map<int, std::vector<Run>> by_size;
    const auto t0 = std::chrono::steady_clock::now();
    const int total = static_cast<int>(o.drones.size()) * o.seeds;
    int done = 0;
    bool interrupted = false;
    for (int n : o.drones) {
      for (int s = o.first_seed; s < o.first_seed + o.seeds && !interrupted; ++s) {
        const Run r = run_one(o, n, s);
        // std::system ignores SIGINT in this process while run-sim.sh runs, so a Ctrl-C reaches only
        // the run, which exits 130 (or dies of it): stop here and summarise the runs that finished.
        if (r.exit_code == 128 + SIGINT) {
          std::printf("[%d/%d] N=%d seed %d: interrupted; summarising the %d finished runs\n", done + 1, total, n, s, done);
          interrupted = true;
          break;
        }
        // 2: bad flags or world, 125: no private network namespace, 126/127: run-sim.sh or a tool it
        // needs cannot run. Every other run would fail the same way: stop, and exit non-zero.
        if (r.exit_code == 2 || r.exit_code >= 125) {
          std::printf("[%d/%d] N=%d seed %d: run-sim.sh could not run (exit %d; its output: %s.out in %s); stopping\n",
                      done + 1, total, n, s, r.exit_code, ("n" + std::to_string(n) + "-s" + std::to_string(s)).c_str(),
                      o.work_dir.c_str());
          failed_setup = r.exit_code;
          interrupted = true;
          break;
        }
        write_run_row(runs_csv, r);
        fact::bench::write_results_file(o.out_dir + "/e2e_runs.csv", runs_csv.str());
        by_size[n].push_back(r);
        ++done;
        const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::printf("[%d/%d] N=%d seed %d: %s, t_cert %.1f s sim, rounds %d, yaw MAE %.4f rad, pos median %.3f m, "
                    "%.0f s wall (elapsed %.0f s)%s%s\n",
                    done, total, n, s, r.correct ? "certified+correct" : r.certified_wrong ? "CERTIFIED-WRONG" : "failed",
                    r.time_to_certified, r.rounds, r.yaw_mae, r.position_median, r.wall_seconds, el,
                    r.correct ? "" : ": ", r.correct ? "" : r.reason.c_str());
        std::fflush(stdout);
      }
    }

    if (done == 0) {
      std::cerr << "fact-bench-e2e: no run finished; " << o.out_dir << " left as it was\n";
      return 1;
    }
    write_summaries(o.out_dir, by_size,
                    std::to_string(o.seeds) + " seeds per size from " + std::to_string(o.first_seed) + ", world " +
                        (o.world.empty() ? "default (obstacles)" : o.world) + ", --fast");
    std::cout << "wrote " << o.out_dir << "/e2e_runs.csv, e2e.csv, e2e_summary.txt\n";
    return failed_setup != 0 ? 1 : 0;
  } catch (const std::exception& e) {  // a results file that cannot be written
    std::cerr << "fact-bench-e2e: error: " << e.what() << "\n";
    return 1;
  }
}
