// fact-sdp-reference: writes the fixed reference instances of the block SDP
//     minimize ⟨C, X⟩  s.t.  X ⪰ 0, X_ii = I_d
// to <out-dir>/<name>.dat-s (SDPA-sparse, see fact::bench::write_sdpa_sparse: the file's
// objective matrix is −C) and their optima by three independent routes to
// <out-dir>/optima.csv:
//     name,n,d,sdpa_objective,csdp_objective,csdp_binary_objective
// n is the matrix dimension (C is n×n, n = d·N); objectives are ⟨C, X⟩ in OUR minimisation
// sign, %.12e (the csdp binary prints only 8 significant digits).
// Exits 1 when the three routes disagree by more than 1e-6 relative, or one gives no value, and
// then leaves <out-dir> as it was (the files are staged and replaced only when all agree).
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "instances.h"
#include "peers.h"
#include "results_file.h"

namespace {

using fact::bench::PeerResult;

constexpr double kAgreementTol = 1e-6;  // relative, |a − b| / max(1, |b|)

struct RefInstance {
  std::string name;
  Eigen::MatrixXd C;  // n × n cost, n = d·N
  int d = 2;
};

// The fixed set: d = 2 swarm costs for N = 2 … 6 (noisy instances of the same N share
// their data, so tight and plain forms of one swarm can be compared) and two d = 1 random
// PSD costs. Deterministic by seed.
std::vector<RefInstance> reference_instances() {
  using fact::bench::random_psd;
  using fact::bench::synthetic_cost;
  std::vector<RefInstance> out;
  const auto swarm = [&](const std::string& kind, int drones, double noise, bool tight, std::uint64_t seed) {
    out.push_back({kind + "_N" + std::to_string(drones), synthetic_cost(drones, noise, tight, seed), 2});
  };
  for (int drones : {3, 5}) swarm("tight_noisefree", drones, 0.0, true, 10 + drones);
  for (int drones : {2, 3, 4, 5, 6}) swarm("tight_noisy", drones, 0.05, true, 20 + drones);
  for (int drones : {2, 4, 6}) swarm("plain_noisy", drones, 0.05, false, 20 + drones);
  for (int n : {5, 8}) out.push_back({"random_d1_n" + std::to_string(n), random_psd(n, n, 40 + n), 1});
  return out;
}

struct Optima {
  PeerResult sdpa, csdp, binary;
};

double rel_diff(double a, double b) { return std::abs(a - b) / std::max(1.0, std::abs(b)); }

// Largest pairwise relative difference among the three objectives (NaN if one is missing).
double disagreement(const Optima& o) {
  const double a = o.sdpa.objective, b = o.csdp.objective, c = o.binary.objective;
  if (std::isnan(a) || std::isnan(b) || std::isnan(c)) return std::nan("");
  return std::max({rel_diff(a, b), rel_diff(a, c), rel_diff(b, c)});
}

std::string warnings(const Optima& o) {
  std::string w;
  if (!o.sdpa.converged) w += " [SDPA: " + o.sdpa.note + "]";
  if (!o.csdp.converged) w += " [CSDP: " + o.csdp.note + "]";
  if (!o.binary.converged) w += " [csdp binary: " + o.binary.note + "]";
  return w;
}

Optima solve_all(const RefInstance& inst, const std::string& dat_path, const std::string& workdir) {
  Optima o;
  o.sdpa = fact::bench::solve_sdpa(inst.C, inst.d);
  o.csdp = fact::bench::solve_csdp(inst.C, inst.d);
  o.binary = fact::bench::run_csdp_binary(dat_path, workdir);  // on the very file written
  return o;
}

std::string usage() {
  return "usage: fact-sdp-reference [--out-dir DIR]\n"
         "  writes DIR/<name>.dat-s and DIR/optima.csv (default DIR: test/data/sdp)\n";
}

// The three routes' values as the CSV row, %.12e.
std::string csv_row(const RefInstance& inst, const Optima& o) {
  char row[256];
  std::snprintf(row, sizeof row, "%s,%d,%d,%.12e,%.12e,%.12e\n", inst.name.c_str(), static_cast<int>(inst.C.rows()),
                inst.d, o.sdpa.objective, o.csdp.objective, o.binary.objective);
  return row;
}

std::string read_whole(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) throw std::runtime_error("cannot read back " + path.string());
  return text.str();
}

// Removes the staging folder however run() ends (a throw left it in /tmp).
struct RemovedAtEnd {
  std::filesystem::path path;
  ~RemovedAtEnd() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

// "" when every file run() writes can be replaced in out_dir (a folder, made if missing, whose
// targets are not folders), else why not: checked before the solves, so that a failure cannot
// come after some .dat-s files were replaced and leave them beside the old optima.csv.
std::string output_problem(const std::filesystem::path& out_dir, const std::vector<std::string>& names) {
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (!std::filesystem::is_directory(out_dir)) return "--out-dir: " + out_dir.string() + " is not a folder";
  if (access(out_dir.c_str(), W_OK) != 0) return "--out-dir: " + out_dir.string() + " is not writable";
  for (const std::string& name : names)
    if (std::filesystem::is_directory(out_dir / name)) return "--out-dir: " + (out_dir / name).string() + " is a folder";
  return "";
}

// Solves every instance with its .dat-s written to a staging directory, and only when all of them
// agree copies the .dat-s files and optima.csv into out_dir, each replaced atomically: a run that
// disagrees leaves out_dir as it was (it used to rewrite the files first and exit 1 after, leaving
// the disagreeing values for test_sdp to read; review, session 34). Returns 0 when all instances
// agree, 1 otherwise.
int run(const std::string& out_dir) {
  const std::vector<RefInstance> instances = reference_instances();
  std::vector<std::string> outputs{"optima.csv"};
  for (const RefInstance& inst : instances) outputs.push_back(inst.name + ".dat-s");
  if (const std::string e = output_problem(out_dir, outputs); !e.empty()) throw std::runtime_error(e);
  const RemovedAtEnd workdir{std::filesystem::temp_directory_path() /
                             ("fact-sdp-reference-" + std::to_string(getpid()))};
  const std::filesystem::path stage = workdir.path / "stage";
  std::filesystem::create_directories(stage);
  std::string csv = "name,n,d,sdpa_objective,csdp_objective,csdp_binary_objective\n";
  std::printf("%-22s %4s %2s %20s %20s %20s %9s\n", "name", "n", "d", "sdpa", "csdp", "csdp binary", "max diff");
  int failures = 0;
  for (const RefInstance& inst : instances) {
    const std::string dat = (stage / (inst.name + ".dat-s")).string();
    fact::bench::write_sdpa_sparse(dat, inst.C, inst.d);
    const Optima o = solve_all(inst, dat, workdir.path.string());
    const double diff = disagreement(o);
    const bool ok = diff <= kAgreementTol;  // false for NaN
    failures += ok ? 0 : 1;
    csv += csv_row(inst, o);
    std::printf("%-22s %4d %2d %20.12e %20.12e %20.12e %9.1e%s%s\n", inst.name.c_str(),
                static_cast<int>(inst.C.rows()), inst.d, o.sdpa.objective, o.csdp.objective, o.binary.objective, diff,
                ok ? "" : "  DISAGREE", warnings(o).c_str());
  }
  const std::filesystem::path csv_path = std::filesystem::path(out_dir) / "optima.csv";
  if (failures) {
    std::printf("%d instance(s) disagree by more than %.0e: %s and its .dat-s files left as they were\n", failures,
                kAgreementTol, csv_path.c_str());
    return 1;
  }
  for (const RefInstance& inst : instances) {
    const std::string name = inst.name + ".dat-s";
    fact::bench::write_results_file((std::filesystem::path(out_dir) / name).string(), read_whole(stage / name));
  }
  fact::bench::write_results_file(csv_path.string(), csv);  // last: beside the .dat-s it describes
  std::printf("wrote %s and the .dat-s files beside it\n", csv_path.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string out_dir = "test/data/sdp";
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--out-dir") && i + 1 < argc) {
      out_dir = argv[++i];
    } else if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
      std::cout << usage();
      return 0;
    } else {
      std::cerr << "fact-sdp-reference: unknown or incomplete flag '" << argv[i] << "'\n" << usage();
      return 2;
    }
  }
  if (!fact::bench::sdpa_compiled_in() || !fact::bench::csdp_compiled_in() || fact::bench::csdp_binary_path().empty()) {
    std::cerr << "fact-sdp-reference: needs SDPA, the CSDP library and the csdp executable (SDPA "
              << (fact::bench::sdpa_compiled_in() ? "ok" : "not available") << ", CSDP "
              << (fact::bench::csdp_compiled_in() ? "ok" : "not available") << ", csdp binary "
              << (fact::bench::csdp_binary_path().empty() ? "not available" : "ok") << ")\n";
    return 1;
  }
  try {
    return run(out_dir);
  } catch (const std::exception& e) {
    std::cerr << "fact-sdp-reference: " << e.what() << "\n";
    return 1;
  }
}
