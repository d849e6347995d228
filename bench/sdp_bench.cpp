// fact-bench-sdp: times fact::sdp::solve against SDPA and CSDP (in-process) on the
// block-constrained SDP  minimize ⟨C, X⟩ s.t. X ⪰ 0, X_ii = I_d, over growing swarm sizes N.
// Run with --help for the flags. Writes one CSV row per (N, instance).
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "fact/memory.h"
#include "fact/sdp.h"
#include "instances.h"
#include "peers.h"
#include "results_file.h"
#include "stats.h"

namespace {

using fact::bench::PeerResult;
using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

const std::vector<int> kSizes = {2, 3, 4, 5, 6, 7, 8, 12, 16, 32, 64, 100, 200};
const std::vector<std::string> kInstances = {"tight_noisefree", "tight_noisy", "plain_noisy", "random_lowrank",
                                             "random_fullrank"};

// Seconds per solve with MOSEK reported in the paper, for N = 2 … 8; NaN otherwise.
double paper_mosek_seconds(int drones) {
  static const double seconds[] = {0.004, 0.009, 0.021, 0.032, 0.109, 0.163, 0.253};
  return (drones >= 2 && drones <= 8) ? seconds[drones - 2] : kNaN;
}

struct Args {
  int max_n = 200;
  int reps = 3;
  int peer_max_n = 200;  // every size of the table (N = 200 adds about a minute)
  bool peers = true;
  bool quick = false;  // --quick: max_n at most 16, applied after all flags
  bool stages = false;  // --stages: each row's methods (Result::stages) under it
  std::string out = "bench/results/sdp.csv";
};

void print_usage(std::ostream& os) {
  os << "usage: fact-bench-sdp [--max-n N] [--quick] [--reps R] [--out FILE] [--no-peers] [--peer-max-n N]\n"
        "                      [--stages]\n"
        "  --max-n N       largest swarm size N to run (sizes: 2..8, 12, 16, 32, 64, 100, 200)\n"
        "  --quick         only N <= 16\n"
        "  --reps R        repetitions per solver; times are medians (default 3)\n"
        "  --out FILE      CSV output (default bench/results/sdp.csv, folders are created)\n"
        "  --no-peers      time fact::sdp::solve only\n"
        "  --peer-max-n N  run SDPA/CSDP only up to this N (default 200); larger shows '-'\n"
        "  --stages        under each row, the methods our solve ran: iterations, ms (of the\n"
        "                  last repetition) and how each ended\n"
        "For steady peer timings run with OPENBLAS_NUM_THREADS=1.\n";
}

int parse_int(const std::string& flag, const char* text, int min_value) {
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || v < min_value || v > 1000000)
    throw std::invalid_argument(flag + " needs an integer >= " + std::to_string(min_value) + ", got '" + text + "'");
  return static_cast<int>(v);
}

// Returns false when --help was asked. Throws std::invalid_argument on a bad flag.
bool parse_args(int argc, char** argv, Args* args) {
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    const auto value = [&]() -> const char* {
      if (i + 1 >= argc) throw std::invalid_argument(flag + " needs a value");
      return argv[++i];
    };
    if (flag == "--help" || flag == "-h") return false;
    if (flag == "--max-n") args->max_n = parse_int(flag, value(), 2);
    else if (flag == "--quick") args->quick = true;
    else if (flag == "--reps") args->reps = parse_int(flag, value(), 1);
    else if (flag == "--out") args->out = value();
    else if (flag == "--no-peers") args->peers = false;
    else if (flag == "--peer-max-n") args->peer_max_n = parse_int(flag, value(), 0);
    else if (flag == "--stages") args->stages = true;
    else throw std::invalid_argument("unknown flag '" + flag + "'");
  }
  if (args->quick) args->max_n = std::min(args->max_n, 16);  // whatever the flags' order
  return true;
}

struct Instance {
  std::string name;
  std::string form;  // "tight", "plain" or "random" (summary groups)
  Eigen::MatrixXd C; // n × n cost, n = d·N
  int d = 2;
};

// The five instances of a swarm size N, all d = 2 (n = 2N), deterministic by seed.
Instance make_instance(const std::string& name, int drones) {
  using fact::bench::random_psd;
  using fact::bench::synthetic_cost;
  const std::uint64_t n = static_cast<std::uint64_t>(drones);
  if (name == "tight_noisefree") return {name, "tight", synthetic_cost(drones, 0.0, true, 1000 + n), 2};
  if (name == "tight_noisy") return {name, "tight", synthetic_cost(drones, 0.05, true, 2000 + n), 2};
  if (name == "plain_noisy") return {name, "plain", synthetic_cost(drones, 0.05, false, 2000 + n), 2};
  if (name == "random_lowrank") return {name, "random", random_psd(2 * drones, 3, 3000 + n), 2};
  if (name == "random_fullrank") return {name, "random", random_psd(2 * drones, 2 * drones, 4000 + n), 2};
  throw std::invalid_argument("unknown instance " + name);
}

using fact::bench::median;

struct OurTiming {
  fact::sdp::Result result;  // of the last repetition (all are identical: fixed seed)
  double median_ms = kNaN;
};

// Every solver, ours and the peers, gets one untimed solve of the instance first: in one
// process the solver that runs after another otherwise pays for the caches and heap the other
// left (ours at N = 100 measured 35 % slower with the peers run in between than without;
// BENCHMARKS.md, session 16).
OurTiming time_ours(const Instance& inst, int reps) {
  OurTiming t;
  std::vector<double> ms;
  fact::sdp::solve(inst.C, inst.d);  // warm-up, untimed
  for (int r = 0; r < reps; ++r) {
    const Clock::time_point start = Clock::now();
    t.result = fact::sdp::solve(inst.C, inst.d);  // default Options: Method::automatic
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  }
  t.median_ms = median(ms);
  return t;
}

struct PeerTiming {
  bool ran = false;        // available and not skipped
  bool converged = false;  // every repetition converged
  double objective = kNaN; // ⟨C, X⟩ of the last repetition
  double median_ms = kNaN;
  std::string note;
};

PeerTiming time_peer(const std::function<PeerResult()>& solve, int reps) {
  PeerTiming t;
  std::vector<double> ms;
  t.converged = true;
  if (!solve().available) reps = 1;  // warm-up, untimed; an unavailable peer says so below
  for (int r = 0; r < reps; ++r) {
    const PeerResult p = solve();
    t.note = p.note;
    if (!p.available) return PeerTiming{false, false, kNaN, kNaN, p.note};
    t.converged = t.converged && p.converged;
    t.objective = p.objective;
    ms.push_back(p.ms);
  }
  t.ran = true;
  t.median_ms = median(ms);
  return t;
}

struct Row {
  int drones = 0;
  std::string instance, form;
  OurTiming ours;
  PeerTiming sdpa, csdp;
};

// |ours − peer| / max(1, |peer|); NaN when the peer did not run.
double rel_diff(const Row& row, const PeerTiming& peer) {
  if (!peer.ran) return kNaN;
  return std::abs(row.ours.result.objective - peer.objective) / std::max(1.0, std::abs(peer.objective));
}

std::string fmt(double v, const char* format, const char* missing) {
  if (std::isnan(v)) return missing;
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

// A peer's time for the table: '-' when skipped, '*' appended when it did not converge.
std::string fmt_peer_ms(const PeerTiming& p) {
  if (!p.ran) return "-";
  return fmt(p.median_ms, "%.3f", "-") + (p.converged ? "" : "*");
}

void print_table_header() {
  std::printf("%4s %-16s %10s %6s %9s %10s %-21s %9s %11s %11s %9s %9s\n", "N", "instance", "ours_ms", "iters",
              "rel_gap", "min_eig_S", "status", "mosek_ms", "sdpa_ms", "csdp_ms", "d_sdpa", "d_csdp");
  std::fflush(stdout);  // (and the lines above it) before the first progress line on stderr
}

void print_row(const Row& r) {
  const fact::sdp::Result& res = r.ours.result;
  std::printf("%4d %-16s %10.3f %6d %9.1e %10.2e %-21s %9s %11s %11s %9s %9s\n", r.drones, r.instance.c_str(),
              r.ours.median_ms, res.iterations, res.rel_gap, res.min_eig_S, fact::sdp::to_string(res.status),
              fmt(1000 * paper_mosek_seconds(r.drones), "%.0f", "").c_str(), fmt_peer_ms(r.sdpa).c_str(),
              fmt_peer_ms(r.csdp).c_str(), fmt(rel_diff(r, r.sdpa), "%.1e", "-").c_str(),
              fmt(rel_diff(r, r.csdp), "%.1e", "-").c_str());
  std::fflush(stdout);
}

// The methods of a row's solve (Result::stages), one line: "stages: low_rank 7 it 0.23 ms (not
// certified) > dual_scaling …".
void print_stages(const Row& r) {
  std::string line = "     stages:";
  for (const fact::sdp::Stage& stage : r.ours.result.stages) {
    if (line.back() != ':') line += " >";
    line += " " + stage.method + " " + std::to_string(stage.iterations) + " it " + fmt(stage.time_ms, "%.3f", "nan") +
            " ms (" + stage.outcome + ")";
  }
  std::printf("%s\n", line.c_str());
  std::fflush(stdout);  // under its row, before the next progress line on stderr (2>&1 into a pipe)
}

const char* kCsvHeader = "n,instance,ours_ms,sdpa_ms,csdp_ms,rel_obj_diff_sdpa,rel_obj_diff_csdp,gap,min_eig_S,status";

// One CSV line; n is the swarm size N (the matrix is 2N × 2N). Skipped peers are "nan".
std::string csv_line(const Row& r) {
  const fact::sdp::Result& res = r.ours.result;
  return std::to_string(r.drones) + "," + r.instance + "," + fmt(r.ours.median_ms, "%.4f", "nan") + "," +
         fmt(r.sdpa.median_ms, "%.4f", "nan") + "," + fmt(r.csdp.median_ms, "%.4f", "nan") + "," +
         fmt(rel_diff(r, r.sdpa), "%.3e", "nan") + "," + fmt(rel_diff(r, r.csdp), "%.3e", "nan") + "," +
         fmt(res.rel_gap, "%.3e", "nan") + "," + fmt(res.min_eig_S, "%.3e", "nan") + "," +
         fact::sdp::to_string(res.status);
}

// Progress on stderr: rewritten in place on a terminal, one line each otherwise.
void progress(int done, int total, int drones, const std::string& instance) {
  static const bool tty = isatty(STDERR_FILENO);
  std::fprintf(stderr, "%s[%d/%d] N=%d %s ...%s", tty ? "\r\033[K" : "", done, total, drones, instance.c_str(),
               tty ? "" : "\n");
  std::fflush(stderr);
}

void clear_progress() {
  if (isatty(STDERR_FILENO)) std::fprintf(stderr, "\r\033[K");
}

// First solves in a process pay for page faults and BLAS thread start-up; do them untimed.
void warm_up(bool peers) {
  const Instance inst = make_instance("tight_noisy", 6);
  for (int i = 0; i < 3; ++i) {
    fact::sdp::solve(inst.C, inst.d);
    if (!peers) continue;
    fact::bench::solve_sdpa(inst.C, inst.d);
    fact::bench::solve_csdp(inst.C, inst.d);
  }
}

Row run_one(int drones, const std::string& name, const Args& args) {
  const Instance inst = make_instance(name, drones);
  Row row{drones, inst.name, inst.form, time_ours(inst, args.reps), {}, {}};
  if (args.peers && drones <= args.peer_max_n) {
    row.sdpa = time_peer([&] { return fact::bench::solve_sdpa(inst.C, inst.d); }, args.reps);
    row.csdp = time_peer([&] { return fact::bench::solve_csdp(inst.C, inst.d); }, args.reps);
  }
  return row;
}

// Per form: the smallest speed-up over the faster peer, and the largest objective
// difference to a peer that converged.
void print_summary(const std::vector<Row>& rows) {
  std::printf("\nsummary (speed-up = faster peer's median time / ours; * = peer did not converge)\n");
  for (const std::string form : {"tight", "plain", "random"}) {
    double min_speedup = kNaN, max_diff = kNaN;
    std::string where_speedup = "-", where_diff = "-";
    int certified = 0, total = 0;
    for (const Row& r : rows) {
      if (r.form != form) continue;
      ++total;
      certified += r.ours.result.certified() ? 1 : 0;
      const double faster = std::fmin(r.sdpa.median_ms, r.csdp.median_ms);  // fmin ignores NaN
      const double speedup = faster / r.ours.median_ms;
      if (!std::isnan(speedup) && !(speedup >= min_speedup)) {
        min_speedup = speedup;
        where_speedup = "N=" + std::to_string(r.drones) + " " + r.instance;
      }
      for (const PeerTiming* p : {&r.sdpa, &r.csdp}) {
        const double diff = rel_diff(r, *p);
        if (p->converged && !std::isnan(diff) && !(diff <= max_diff)) {
          max_diff = diff;
          where_diff = "N=" + std::to_string(r.drones) + " " + r.instance;
        }
      }
    }
    if (total == 0) continue;
    std::printf("  %-6s certified %d/%d   min speed-up %s (%s)   max rel_obj_diff %s (%s)\n", form.c_str(), certified,
                total, fmt(min_speedup, "%.2fx", "-").c_str(), where_speedup.c_str(),
                fmt(max_diff, "%.1e", "-").c_str(), where_diff.c_str());
  }
}

void print_environment(const Args& args) {
  const char* blas_threads = std::getenv("OPENBLAS_NUM_THREADS");
  std::printf("fact-bench-sdp: reps %d, peers %s (SDPA %s, CSDP %s), peers up to N = %d, OPENBLAS_NUM_THREADS=%s\n",
              args.reps, args.peers ? "on" : "off",
              fact::bench::sdpa_compiled_in() ? "available" : "not available",
              fact::bench::csdp_compiled_in() ? "available" : "not available", args.peer_max_n,
              blas_threads ? blas_threads : "(unset)");
  std::printf("times in ms (median, wall clock, set-up and certification included); "
              "mosek_ms = the paper's MOSEK time per solve\n\n");
}

int run(const Args& args) {
  std::vector<int> sizes;
  for (int n : kSizes)
    if (n <= args.max_n) sizes.push_back(n);
  std::string csv = std::string(kCsvHeader) + "\n";  // written whole at the end (results_file.h)
  print_environment(args);
  warm_up(args.peers);
  print_table_header();
  std::vector<Row> rows;
  const int total = static_cast<int>(sizes.size() * kInstances.size());
  for (int drones : sizes)
    for (const std::string& name : kInstances) {
      progress(static_cast<int>(rows.size()) + 1, total, drones, name);
      rows.push_back(run_one(drones, name, args));
      clear_progress();
      print_row(rows.back());
      if (args.stages) print_stages(rows.back());
      csv += csv_line(rows.back()) + "\n";
    }
  print_summary(rows);
  fact::bench::write_results_file(args.out, csv);
  std::printf("\nwrote %s\n", args.out.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  try {
    if (!parse_args(argc, argv, &args)) {
      print_usage(std::cout);
      return 0;
    }
  } catch (const std::invalid_argument& e) {
    std::cerr << "fact-bench-sdp: " << e.what() << "\n";
    print_usage(std::cerr);
    return 2;
  }
  // Freed memory stays in the process for every solver timed here, ours and the peers alike, so
  // no repetition pays for page faults (fact/memory.h).
  fact::keep_freed_memory();
  try {
    return run(args);
  } catch (const std::exception& e) {
    std::cerr << "fact-bench-sdp: " << e.what() << "\n";
    return 1;
  }
}
