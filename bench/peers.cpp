#include "peers.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <new>
#include <stdexcept>
#include <string>

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#ifdef FACT_HAVE_SDPA
#include <sdpa_call.h>
#endif
#ifdef FACT_HAVE_CSDP
extern "C" {
#include <csdp/declarations.h>
}
#endif

namespace fact::bench {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Throws std::invalid_argument unless C is a finite symmetric n×n matrix, n a multiple of d.
void check_problem(const Eigen::MatrixXd& c, int d) {
  if (c.rows() != c.cols() || c.rows() == 0)
    throw std::invalid_argument("peers: C is " + std::to_string(c.rows()) + "×" +
                                std::to_string(c.cols()) + ", need square and non-empty");
  if (!c.allFinite()) throw std::invalid_argument("peers: C has a non-finite entry");
  const double asym = (c - c.transpose()).cwiseAbs().maxCoeff();
  if (asym > 1e-12 * std::max(1.0, c.cwiseAbs().maxCoeff()))
    throw std::invalid_argument("peers: C is not symmetric (max |C - Cᵀ| = " + std::to_string(asym) + ")");
  block_constraints(static_cast<int>(c.rows()), d);  // validates d and n
}

// The symmetric part's (i, j) entry: what ⟨C, X⟩ sees for a symmetric X.
double sym(const Eigen::MatrixXd& c, int i, int j) { return 0.5 * (c(i, j) + c(j, i)); }

// Runs its scope in an empty directory of its own (made once per process, removed at exit), and
// returns to the caller's working directory after: CSDP's easy_sdp reads a "param.csdp" from the
// working directory when there is one, so a stray file there (maxiter=3, say) changed the peer's
// answers (review, session 34).
class InEmptyDirectory {
 public:
  InEmptyDirectory() {
    static EmptyDirectory dir{make_empty_directory()};
    if (access(dir.path.c_str(), F_OK) != 0) dir.path = make_empty_directory();  // removed meanwhile (a /tmp cleaner)
    saved_ = open(".", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (saved_ < 0) throw std::runtime_error("peers: cannot open the working directory");
    if (chdir(dir.path.c_str()) != 0) {
      close(saved_);  // (the destructor does not run for a constructor that throws)
      throw std::runtime_error("peers: cannot enter the empty directory " + dir.path + " for CSDP");
    }
  }
  ~InEmptyDirectory() {
    if (fchdir(saved_) != 0) std::perror("peers: cannot return to the working directory");
    close(saved_);
  }
  InEmptyDirectory(const InEmptyDirectory&) = delete;
  InEmptyDirectory& operator=(const InEmptyDirectory&) = delete;

 private:
  struct EmptyDirectory {  // removed when the process exits
    std::string path;
    ~EmptyDirectory() { rmdir(path.c_str()); }
  };
  static std::string make_empty_directory() {
    std::string pattern = (std::filesystem::temp_directory_path() / "fact-csdp-cwd-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("peers: mkdtemp " + pattern + " failed");
    return pattern;
  }
  int saved_ = -1;
};

// Redirects the process's stdout (fd 1) to /dev/null for its lifetime: CSDP's easy_sdp
// prints its iteration log with printf unless a param.csdp says printlevel=0, and SDPA
// prints some warnings ("Strange behavior : primal < dual") even without a display.
class SilenceStdout {
 public:
  SilenceStdout() {
    std::cout.flush();
    std::fflush(stdout);
    saved_ = dup(STDOUT_FILENO);
    const int null_fd = open("/dev/null", O_WRONLY);
    if (saved_ >= 0 && null_fd >= 0) dup2(null_fd, STDOUT_FILENO);
    if (null_fd >= 0) close(null_fd);
  }
  ~SilenceStdout() {
    std::fflush(stdout);
    if (saved_ >= 0) {
      dup2(saved_, STDOUT_FILENO);
      close(saved_);
    }
  }
  SilenceStdout(const SilenceStdout&) = delete;
  SilenceStdout& operator=(const SilenceStdout&) = delete;

 private:
  int saved_ = -1;
};

#ifdef FACT_HAVE_SDPA
void configure_sdpa(SDPA* p, double c_norm) {
  p->setDisplay(nullptr);  // no iteration log
  p->setParameterType(SDPA::PARAMETER_DEFAULT);
  // SDPA's defaults assume data of order one: it stops when an objective leaves
  // [−1e5, 1e5] and starts from X = Y = 100·I. The swarm costs reach ‖C‖_F ~ 1e10, and
  // with the defaults SDPA declares "pFEAS_dINF" after 5 iterations from N = 12 on. So
  // the bounds are switched off and the start is scaled to the data (λ* = max(100, ‖C‖_F)).
  p->setParameterLowerBound(-1e300);
  p->setParameterUpperBound(1e300);
  p->setParameterLambdaStar(std::max(100.0, c_norm));
}

// One n×n SDP block; F0 = −C and F_k = A_k (upper triangles, 1-based), c_k = b_k.
void load_sdpa(SDPA* p, const Eigen::MatrixXd& c, const std::vector<BlockConstraint>& cons) {
  const int n = static_cast<int>(c.rows());
  const int m = static_cast<int>(cons.size());
  p->inputConstraintNumber(m);
  p->inputBlockNumber(1);
  p->inputBlockSize(1, n);
  p->inputBlockType(1, SDPA::SDP);
  p->initializeUpperTriangleSpace();
  for (int k = 0; k < m; ++k) p->inputCVec(k + 1, cons[k].rhs);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i <= j; ++i)
      if (sym(c, i, j) != 0.0) p->inputElement(0, 1, i + 1, j + 1, -sym(c, i, j));
  for (int k = 0; k < m; ++k) p->inputElement(k + 1, 1, cons[k].row + 1, cons[k].col + 1, cons[k].value);
  p->initializeUpperTriangle();
}

PeerResult sdpa_outcome(SDPA* p) {
  PeerResult r;
  r.available = true;
  r.objective = -p->getDualObj();  // ⟨F0, Y⟩ = −⟨C, X⟩ with Y = X
  r.converged = (p->getPhaseValue() == SDPA::pdOPT);
  char phase_text[64] = {};
  p->getPhaseString(phase_text);
  std::string phase(phase_text);
  phase.erase(phase.find_last_not_of(' ') + 1);  // SDPA pads it with blanks
  r.note = "phase " + phase + ", " + std::to_string(p->getIteration()) + " iterations";
  return r;
}
#endif  // FACT_HAVE_SDPA

#ifdef FACT_HAVE_CSDP
// CSDP frees its problem with free(), so everything handed to it comes from malloc.
template <class T>
T* c_alloc(std::size_t count) {
  void* p = std::malloc(count * sizeof(T));
  if (p == nullptr) throw std::bad_alloc();
  return static_cast<T*>(p);
}

// CSDP's objective: one dense n×n block holding C' = −C (column-major, 1-based blocks).
blockmatrix csdp_objective(const Eigen::MatrixXd& c) {
  const int n = static_cast<int>(c.rows());
  blockmatrix out;
  out.nblocks = 1;
  out.blocks = c_alloc<blockrec>(2);  // blocks[1] is the only block
  out.blocks[1].blockcategory = MATRIX;
  out.blocks[1].blocksize = n;
  out.blocks[1].data.mat = c_alloc<double>(static_cast<std::size_t>(n) * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) out.blocks[1].data.mat[ijtok(i + 1, j + 1, n)] = -sym(c, i, j);
  return out;
}

// CSDP's constraints, 1-based: constraints[k].blocks is a one-entry sparse block.
constraintmatrix* csdp_constraints(const std::vector<BlockConstraint>& cons, int n) {
  const std::size_t m = cons.size();
  constraintmatrix* out = c_alloc<constraintmatrix>(m + 1);
  out[0].blocks = nullptr;
  for (std::size_t k = 1; k <= m; ++k) {
    sparseblock* b = c_alloc<sparseblock>(1);
    b->next = nullptr;
    b->nextbyblock = nullptr;
    b->blocknum = 1;
    b->blocksize = n;
    b->constraintnum = static_cast<int>(k);
    b->issparse = 1;
    b->numentries = 1;
    b->entries = c_alloc<double>(2);  // 1-based arrays of one entry
    b->iindices = c_alloc<int>(2);
    b->jindices = c_alloc<int>(2);
    b->entries[1] = cons[k - 1].value;
    b->iindices[1] = cons[k - 1].row + 1;
    b->jindices[1] = cons[k - 1].col + 1;
    out[k].blocks = b;
  }
  return out;
}

const char* csdp_return_text(int code) {
  switch (code) {
    case 0: return "success";
    case 1: return "primal infeasible";
    case 2: return "dual infeasible";
    case 3: return "partial success (full accuracy not reached)";
    case 4: return "maximum iterations reached";
    case 5: return "stuck at edge of primal feasibility";
    case 6: return "stuck at edge of dual feasibility";
    case 7: return "lack of progress";
    case 8: return "X, Z or O singular";
    case 9: return "NaN or Inf detected";
    default: return "unknown return code";
  }
}
#endif  // FACT_HAVE_CSDP

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char ch : s) out += (ch == '\'') ? std::string("'\\''") : std::string(1, ch);
  return out + "'";
}

// Runs `command` through the shell, returning its combined output and exit status.
std::string run_command(const std::string& command, int* exit_status) {
  std::FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) throw std::runtime_error("peers: cannot run " + command);
  std::string output;
  char buffer[4096];
  std::size_t got = 0;
  while ((got = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) output.append(buffer, got);
  const int status = pclose(pipe);
  *exit_status = (status != -1 && WIFEXITED(status)) ? WEXITSTATUS(status) : -1;
  return output;
}

// The value after `label` on the first line containing it; NaN when absent.
double parse_labelled_value(const std::string& output, const std::string& label) {
  const std::size_t at = output.find(label);
  if (at == std::string::npos) return std::nan("");
  return std::strtod(output.c_str() + at + label.size(), nullptr);
}

// The first line of the csdp binary's verdict ("Success: …", "Partial Success: …", "Failure: …").
std::string csdp_verdict(const std::string& output) {
  for (const char* key : {"Success:", "Partial Success:", "Failure:"}) {
    const std::size_t at = output.find(key);
    if (at != std::string::npos) return output.substr(at, output.find('\n', at) - at);
  }
  return "no verdict in csdp output";
}

}  // namespace

std::vector<BlockConstraint> block_constraints(int n, int d) {
  if (d != 1 && d != 2) throw std::invalid_argument("peers: d = " + std::to_string(d) + ", need 1 or 2");
  if (n <= 0 || n % d != 0)
    throw std::invalid_argument("peers: n = " + std::to_string(n) + " is not a positive multiple of d = " +
                                std::to_string(d));
  std::vector<BlockConstraint> out;
  for (int block = 0; block < n / d; ++block)
    for (int a = 0; a < d; ++a)
      for (int b = a; b < d; ++b) {
        BlockConstraint k;
        k.row = d * block + a;
        k.col = d * block + b;
        k.value = (a == b) ? 1.0 : 0.5;  // ⟨A_k, X⟩ = X[row][col]
        k.rhs = (a == b) ? 1.0 : 0.0;
        out.push_back(k);
      }
  return out;
}

bool sdpa_compiled_in() {
#ifdef FACT_HAVE_SDPA
  return true;
#else
  return false;
#endif
}

bool csdp_compiled_in() {
#ifdef FACT_HAVE_CSDP
  return true;
#else
  return false;
#endif
}

std::string csdp_binary_path() {
#ifdef FACT_CSDP_BINARY
  return std::filesystem::exists(FACT_CSDP_BINARY) ? std::string(FACT_CSDP_BINARY) : std::string();
#else
  return {};
#endif
}

PeerResult solve_sdpa(const Eigen::MatrixXd& C, int d) {
  PeerResult r;
#ifndef FACT_HAVE_SDPA
  (void)C;
  (void)d;
  r.note = "not available";
  return r;
#else
  check_problem(C, d);
  const std::vector<BlockConstraint> cons = block_constraints(static_cast<int>(C.rows()), d);
  const Clock::time_point start = Clock::now();
  SDPA p;
  configure_sdpa(&p, C.norm());
  load_sdpa(&p, C, cons);
  {
    SilenceStdout quiet;
    p.initializeSolve();
    p.solve();
  }
  r = sdpa_outcome(&p);
  p.terminate();
  r.ms = ms_since(start);
  return r;
#endif
}

PeerResult solve_csdp(const Eigen::MatrixXd& C, int d) {
  PeerResult r;
#ifndef FACT_HAVE_CSDP
  (void)C;
  (void)d;
  r.note = "not available";
  return r;
#else
  check_problem(C, d);
  r.available = true;
  const int n = static_cast<int>(C.rows());
  const std::vector<BlockConstraint> cons = block_constraints(n, d);
  const int m = static_cast<int>(cons.size());
  InEmptyDirectory no_param_file;  // outside the timed part
  const Clock::time_point start = Clock::now();
  blockmatrix objective = csdp_objective(C);
  double* rhs = c_alloc<double>(m + 1);  // a_k, 1-based
  for (int k = 1; k <= m; ++k) rhs[k] = cons[k - 1].rhs;
  constraintmatrix* constraints = csdp_constraints(cons, n);
  blockmatrix x, z;
  double* y = nullptr;
  double primal = 0, dual = 0;
  int code = 0;
  {
    SilenceStdout quiet;
    initsoln(n, m, objective, rhs, constraints, &x, &y, &z);  // easy_sdp starts from (X, y, Z)
    code = easy_sdp(n, m, objective, rhs, constraints, 0.0, &x, &y, &z, &primal, &dual);
  }
  free_prob(n, m, objective, rhs, constraints, x, y, z);  // frees everything above
  r.ms = ms_since(start);
  r.objective = -primal;  // CSDP's primal value is tr(−C X)
  r.converged = (code == 0);
  r.note = std::string("return ") + std::to_string(code) + ": " + csdp_return_text(code);
  return r;
#endif
}

void write_sdpa_sparse(const std::string& path, const Eigen::MatrixXd& C, int d) {
  check_problem(C, d);
  const int n = static_cast<int>(C.rows());
  const std::vector<BlockConstraint> cons = block_constraints(n, d);
  std::ofstream out(path);
  if (!out) throw std::runtime_error("write_sdpa_sparse: cannot open " + path);
  out.precision(17);
  out << "\"fact block SDP: minimize <C,X>, X >= 0, X_ii = I_d; N=" << n / d << " d=" << d
      << "; matrix 0 is -C (file is a maximisation)\"\n";
  out << cons.size() << " = mDIM\n1 = nBLOCK\n" << n << " = bLOCKsTRUCT\n";
  for (std::size_t k = 0; k < cons.size(); ++k) out << (k ? " " : "") << cons[k].rhs;
  out << "\n";
  for (int i = 0; i < n; ++i)
    for (int j = i; j < n; ++j)
      if (sym(C, i, j) != 0.0) out << "0 1 " << i + 1 << ' ' << j + 1 << ' ' << -sym(C, i, j) << "\n";
  for (std::size_t k = 0; k < cons.size(); ++k)
    out << k + 1 << " 1 " << cons[k].row + 1 << ' ' << cons[k].col + 1 << ' ' << cons[k].value << "\n";
  out.flush();
  if (!out) throw std::runtime_error("write_sdpa_sparse: error while writing " + path);
}

PeerResult run_csdp_binary(const std::string& dat_path, const std::string& workdir) {
  PeerResult r;
  const std::string exe = csdp_binary_path();
  if (exe.empty()) {
    r.note = "not available";
    return r;
  }
  r.available = true;
  const std::string command = "cd " + shell_quote(workdir) + " && " + shell_quote(exe) + " " +
                              shell_quote(std::filesystem::absolute(dat_path).string()) + " 2>&1";
  const Clock::time_point start = Clock::now();
  int exit_status = -1;
  const std::string output = run_command(command, &exit_status);
  r.ms = ms_since(start);
  r.objective = -parse_labelled_value(output, "Primal objective value:");  // file holds −C
  r.converged = (exit_status == 0 && std::isfinite(r.objective));
  r.note = "exit " + std::to_string(exit_status) + ": " + csdp_verdict(output);
  return r;
}

PeerResult solve_csdp_binary(const Eigen::MatrixXd& C, int d, const std::string& workdir) {
  if (csdp_binary_path().empty()) return run_csdp_binary("", workdir);  // "not available"
  static int counter = 0;
  std::filesystem::create_directories(workdir);
  const std::string path = (std::filesystem::path(workdir) / ("fact-csdp-" + std::to_string(getpid()) + "-" +
                                                              std::to_string(counter++) + ".dat-s"))
                               .string();
  const Clock::time_point start = Clock::now();
  write_sdpa_sparse(path, C, d);
  PeerResult r = run_csdp_binary(path, workdir);
  std::filesystem::remove(path);
  r.ms = ms_since(start);
  return r;
}

}  // namespace fact::bench
