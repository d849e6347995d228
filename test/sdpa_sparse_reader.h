// Reads back the SDPA-sparse files (.dat-s) that fact::bench::write_sdpa_sparse writes for
//     minimize ⟨C, X⟩  s.t.  X ⪰ 0, X_ii = I_d   (C n×n symmetric, n = d·N, d ∈ {1, 2}).
// Layout: optional "comment" / * comment lines, then
//     m = mDIM,  1 = nBLOCK,  n = bLOCKsTRUCT,  b_1 … b_m,
//     "0 1 i j v"  entries of the objective matrix F0 = −C (1-based, i ≤ j),
//     "k 1 i j v"  one entry per constraint k: the constraints X_ii = I_d in the order
//                  block, a, b ≥ a — entry (d·blk+a+1, d·blk+b+1), value 1 (a = b) or ½, rhs 1 or 0.
// d is inferred from m and n (m = n for d = 1, 2m = 3n for d = 2) and every constraint is
// checked against that pattern. Malformed input throws std::runtime_error("path:line: …").
// Header-only; used by the tests that compare fact::sdp::solve with test/data/sdp/optima.csv.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace fact::test {
namespace sdpa_detail {

[[noreturn]] inline void fail(const std::string& path, int line, const std::string& what) {
  throw std::runtime_error(path + ":" + std::to_string(line) + ": " + what);
}

// Non-blank lines of the file with their 1-based numbers; SDPA punctuation {}(),= → blanks.
struct Lines {
  std::vector<std::string> text;
  std::vector<int> number;
};

inline Lines read_lines(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  Lines out;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    for (char& ch : line)
      if (ch == '{' || ch == '}' || ch == '(' || ch == ')' || ch == ',' || ch == '=') ch = ' ';
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    out.text.push_back(line);
    out.number.push_back(number);
  }
  return out;
}

inline std::vector<std::string> tokens(const std::string& line) {
  std::istringstream ss(line);
  std::vector<std::string> out;
  for (std::string t; ss >> t;) out.push_back(t);
  return out;
}

inline double to_double(const std::string& t, const std::string& path, int line) {
  char* end = nullptr;
  const double v = std::strtod(t.c_str(), &end);
  if (end == t.c_str() || *end != '\0' || !std::isfinite(v)) fail(path, line, "'" + t + "' is not a finite number");
  return v;
}

inline int to_int(const std::string& t, const std::string& path, int line) {
  char* end = nullptr;
  const long v = std::strtol(t.c_str(), &end, 10);
  if (end == t.c_str() || *end != '\0' || v < -1000000000L || v > 1000000000L)
    fail(path, line, "'" + t + "' is not an integer");
  return static_cast<int>(v);
}

inline bool is_comment(const std::string& line) {
  const std::size_t first = line.find_first_not_of(" \t");
  return first != std::string::npos && (line[first] == '"' || line[first] == '*');
}

// The leading positive integer of header line *at (then advances); *line gets its number.
inline int header_int(const Lines& lines, std::size_t* at, const char* what, const std::string& path, int* line) {
  if (*at >= lines.text.size()) throw std::runtime_error(path + ": ends before " + what);
  *line = lines.number[*at];
  const int v = to_int(tokens(lines.text[*at]).front(), path, *line);
  if (v < 1) fail(path, *line, std::string(what) + " = " + std::to_string(v) + ", need >= 1");
  ++*at;
  return v;
}

// One "k b i j v" line (1-based indices as in the file).
struct Entry {
  int k = 0, block = 0, i = 0, j = 0;
  double value = 0;
  int line = 0;
};

inline Entry parse_entry(const std::string& text, const std::string& path, int line, int m, int n) {
  const std::vector<std::string> t = tokens(text);
  if (t.size() != 5) fail(path, line, "expected 'matrix block i j value', got " + std::to_string(t.size()) + " fields");
  Entry e{to_int(t[0], path, line), to_int(t[1], path, line), to_int(t[2], path, line), to_int(t[3], path, line),
          to_double(t[4], path, line), line};
  if (e.k < 0 || e.k > m) fail(path, line, "matrix number " + t[0] + " outside 0.." + std::to_string(m));
  if (e.block != 1) fail(path, line, "block number " + t[1] + ", the file has one block");
  if (e.i < 1 || e.j < e.i || e.j > n)
    fail(path, line, "index (" + t[2] + ", " + t[3] + ") not in the upper triangle of a " + std::to_string(n) + "×" +
                         std::to_string(n) + " block");
  return e;
}

// The expected constraint k (0-based): 0-based (row, col), value and rhs.
inline void expected_constraint(int k, int d, int* row, int* col, double* value, double* rhs) {
  const int per_block = d * (d + 1) / 2;
  const int block = k / per_block, r = k % per_block;
  const int a = (d == 1 || r < 2) ? 0 : 1;  // d = 2: r = 0 → (0,0), 1 → (0,1), 2 → (1,1)
  const int b = (d == 1) ? 0 : (r == 0 ? 0 : 1);
  *row = d * block + a;
  *col = d * block + b;
  *value = (a == b) ? 1.0 : 0.5;
  *rhs = (a == b) ? 1.0 : 0.0;
}

inline void check_constraint(const std::vector<Entry>& entries, int k, int d, double rhs_in_file, int rhs_line,
                             int header_line, const std::string& path) {
  int row = 0, col = 0;
  double value = 0, rhs = 0;
  expected_constraint(k, d, &row, &col, &value, &rhs);
  const std::string name = "constraint " + std::to_string(k + 1);
  if (entries.size() != 1)
    fail(path, entries.empty() ? header_line : entries[1].line,
         name + " has " + std::to_string(entries.size()) + " entries, expected 1");
  const Entry& e = entries.front();
  if (e.i != row + 1 || e.j != col + 1 || e.value != value)
    fail(path, e.line,
         name + " should be entry (" + std::to_string(row + 1) + ", " + std::to_string(col + 1) + ") = " +
             (value == 1.0 ? "1" : "0.5") + " for d = " + std::to_string(d));
  if (rhs_in_file != rhs) fail(path, rhs_line, name + " right-hand side should be " + (rhs == 1.0 ? "1" : "0"));
}

}  // namespace sdpa_detail

// Returns C (n × n, symmetric) and sets *d (1 or 2). Throws std::runtime_error naming the
// file and line on malformed input or on constraints that are not X_ii = I_d.
inline Eigen::MatrixXd read_sdpa_sparse(const std::string& path, int* d) {
  using namespace sdpa_detail;
  const Lines lines = read_lines(path);
  std::size_t at = 0;
  while (at < lines.text.size() && is_comment(lines.text[at])) ++at;
  int m_line = 0, nblock_line = 0, n_line = 0;
  const int m = header_int(lines, &at, "mDIM", path, &m_line);
  if (header_int(lines, &at, "nBLOCK", path, &nblock_line) != 1) fail(path, nblock_line, "nBLOCK must be 1");
  const int n = header_int(lines, &at, "bLOCKsTRUCT", path, &n_line);
  const int inferred_d = (m == n) ? 1 : (2 * m == 3 * n && n % 2 == 0) ? 2 : 0;
  if (inferred_d == 0)
    fail(path, m_line, "mDIM = " + std::to_string(m) + " with block size " + std::to_string(n) +
                           " fits neither d = 1 (m = n) nor d = 2 (2m = 3n)");

  std::vector<double> rhs;  // b_1 … b_m and the line of each
  std::vector<int> rhs_line;
  for (; at < lines.text.size() && static_cast<int>(rhs.size()) < m; ++at)
    for (const std::string& t : tokens(lines.text[at])) {
      if (static_cast<int>(rhs.size()) == m) fail(path, lines.number[at], "more than mDIM right-hand sides");
      rhs.push_back(to_double(t, path, lines.number[at]));
      rhs_line.push_back(lines.number[at]);
    }
  if (static_cast<int>(rhs.size()) < m) throw std::runtime_error(path + ": ends inside the right-hand sides");

  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixXi seen = Eigen::MatrixXi::Zero(n, n);
  std::vector<std::vector<Entry>> constraints(m);
  for (; at < lines.text.size(); ++at) {
    const Entry e = parse_entry(lines.text[at], path, lines.number[at], m, n);
    if (e.k > 0) {
      constraints[e.k - 1].push_back(e);
      continue;
    }
    if (seen(e.i - 1, e.j - 1)++) fail(path, e.line, "duplicate objective entry");
    c(e.i - 1, e.j - 1) = c(e.j - 1, e.i - 1) = -e.value;  // the file holds F0 = −C
  }
  for (int k = 0; k < m; ++k) check_constraint(constraints[k], k, inferred_d, rhs[k], rhs_line[k], m_line, path);
  if (d != nullptr) *d = inferred_d;
  return c;
}

}  // namespace fact::test
