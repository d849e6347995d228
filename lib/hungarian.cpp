// Rectangular assignment with a per-row no-match cost, by shortest augmenting paths with
// potentials (Kuhn–Munkres in the Jonker–Volgenant / Dijkstra form), O(rows² · (cols + rows)).
//
// Conceptually row i gets a private dummy column of cost no_match_cost, so the working matrix is
// rows × (cols + rows):
//     a(i, j)        = cost(i, j)       for j < cols       (real columns),
//     a(i, cols + i) = no_match_cost                        (row i's own "unmatched" column),
//     a(i, cols + k) = +infinity        for k ≠ i           (never used).
// Every row then has a finite option, so each augmentation succeeds, and a row assigned to its
// dummy is an unmatched row. Rows are added one at a time; each addition is a Dijkstra search
// on reduced costs a(i, j) − u(i) − v(j) ≥ 0 from the new row to a free column.
//
// The dummy columns are not stored. Only row i can reach dummy i, so a row that has gone to its
// dummy is never expanded again, dummy columns are never inside a search tree, and their
// potentials stay 0: the slack of dummy i is no_match_cost − u(i). Each search therefore scans
// the real columns plus the dummies of the rows it has expanded.
#include "fact/hungarian.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace fact {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Largest |entry| and |no_match_cost|: sums and differences of potentials and slacks stay finite
// (entries of ±1e308 overflowed the slacks to +inf and the search wrote outside its arrays).
constexpr double kLargestCost = 1e100;

// Per-thread working arrays, reused between calls so that a solve does not allocate once the
// sizes have been seen. Rows are 1-based (1..rows); columns are 1-based (1..cols) with column 0 a
// virtual column that holds the row being added.
struct Scratch {
  std::vector<double> row_potential;  // u, rows + 1
  std::vector<double> col_potential;  // v, cols + 1
  std::vector<double> min_slack;      // smallest reduced cost into each column found so far, cols + 1
  std::vector<int> col_owner;         // row assigned to each column, 0 = free, cols + 1
  std::vector<int> came_from;         // previous column on the shortest path to each column, cols + 1
  std::vector<char> visited;          // column already in the shortest-path tree, cols + 1
  // Dummies of the rows expanded in the current search (at most rows of them):
  std::vector<double> dummy_slack;    // smallest reduced cost into the dummy
  std::vector<int> dummy_via;         // the column whose owner the dummy belongs to (0: the new row)
  int dummies = 0;                    // entries in use

  void reset(int rows, int cols) {
    row_potential.assign(rows + 1, 0.0);
    col_potential.assign(cols + 1, 0.0);
    min_slack.resize(cols + 1);
    col_owner.assign(cols + 1, 0);
    came_from.resize(cols + 1);
    visited.resize(cols + 1);
    dummy_slack.resize(rows + 1);
    dummy_via.resize(rows + 1);
  }
};

std::string entry_text(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "+inf" : "-inf";
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

void validate(const Eigen::MatrixXd& cost, double no_match_cost) {
  if (!(std::abs(no_match_cost) <= kLargestCost))
    throw std::invalid_argument("solve_assignment: no_match_cost = " + entry_text(no_match_cost) +
                                " must be finite, at most 1e100 in magnitude");
  for (Eigen::Index c = 0; c < cost.cols(); ++c)
    for (Eigen::Index r = 0; r < cost.rows(); ++r) {
      const double x = cost(r, c);
      if (x != kInf && !(std::abs(x) <= kLargestCost))
        throw std::invalid_argument("solve_assignment: cost(row " + std::to_string(r) + ", col " +
                                    std::to_string(c) + ") = " + entry_text(x) +
                                    "; entries must be +inf or finite, at most 1e100 in magnitude");
    }
}

// The column nearest to the tree once the owner of column `col` is expanded.
struct Nearest {
  double delta;  // its slack (finite: the new row's own dummy is always a candidate)
  int next;      // the real column reached, or −1 when a dummy is nearer
  int dummy;     // index into Scratch::dummy_slack when a dummy is nearer, else −1
};

// Expands the owner of column `col`: records that row's dummy, updates the slacks of the real
// columns through it, and returns the nearest column outside the tree.
Nearest expand(const Eigen::MatrixXd& cost, double no_match_cost, int col, Scratch& s) {
  const int cols = static_cast<int>(cost.cols());
  const int from = s.col_owner[col];  // 1-based row being expanded
  const double u_from = s.row_potential[from];
  s.dummy_slack[s.dummies] = no_match_cost - u_from;
  s.dummy_via[s.dummies] = col;
  ++s.dummies;
  Nearest best{kInf, -1, -1};
  double* min_slack = s.min_slack.data();
  const char* visited = s.visited.data();
  const double* v = s.col_potential.data();
  for (int j = 1; j <= cols; ++j) {
    if (visited[j]) continue;
    const double slack = cost(from - 1, j - 1) - u_from - v[j];  // +inf stays +inf
    if (slack < min_slack[j]) {
      min_slack[j] = slack;
      s.came_from[j] = col;
    }
    if (min_slack[j] < best.delta) best = {min_slack[j], j, -1};
  }
  for (int k = 0; k < s.dummies; ++k)
    if (s.dummy_slack[k] < best.delta) best = {s.dummy_slack[k], -1, k};
  return best;
}

// Dijkstra step: raises the potentials of the rows in the tree by delta and lowers those of
// their columns, keeping every reduced cost ≥ 0; the slacks of the other columns drop by delta.
void shift_potentials(double delta, Scratch& s) {
  const int cols = static_cast<int>(s.col_owner.size()) - 1;
  for (int j = 0; j <= cols; ++j) {
    if (s.visited[j]) {
      s.row_potential[s.col_owner[j]] += delta;
      s.col_potential[j] -= delta;
    } else {
      s.min_slack[j] -= delta;
    }
  }
  for (int k = 0; k < s.dummies; ++k) s.dummy_slack[k] -= delta;
}

// Adds row `row` (1-based) to the matching: grows a shortest-path tree over columns from it
// until a free real column or the dummy of an expanded row is reached, then flips the path.
// A row whose dummy is reached becomes unmatched.
void add_row(const Eigen::MatrixXd& cost, double no_match_cost, int row, Scratch& s) {
  std::fill(s.min_slack.begin(), s.min_slack.end(), kInf);
  std::fill(s.visited.begin(), s.visited.end(), 0);
  s.dummies = 0;
  s.col_owner[0] = row;
  int col = 0;  // column whose owner is expanded next (0: the new row itself)
  for (;;) {
    s.visited[col] = 1;
    const Nearest nearest = expand(cost, no_match_cost, col, s);
    shift_potentials(nearest.delta, s);
    if (nearest.dummy >= 0) {  // the owner of column dummy_via moves to its dummy; the path ends there
      col = s.dummy_via[nearest.dummy];
      break;
    }
    col = nearest.next;
    if (s.col_owner[col] == 0) break;  // a free real column
  }
  // Flip the augmenting path back to the virtual column 0: each column on it passes to the row
  // that reached it.
  while (col != 0) {
    const int prev = s.came_from[col];
    s.col_owner[col] = s.col_owner[prev];
    col = prev;
  }
}

}  // namespace

Assignment solve_assignment(const Eigen::MatrixXd& cost, double no_match_cost) {
  validate(cost, no_match_cost);
  const int rows = static_cast<int>(cost.rows());
  const int cols = static_cast<int>(cost.cols());
  Assignment out;
  out.row_to_col.assign(rows, -1);
  out.col_to_row.assign(cols, -1);

  thread_local Scratch scratch;
  scratch.reset(rows, cols);
  for (int row = 1; row <= rows; ++row) add_row(cost, no_match_cost, row, scratch);

  for (int j = 1; j <= cols; ++j) {
    const int row = scratch.col_owner[j] - 1;
    if (row < 0) continue;
    // A matched pair dearer than leaving its row unmatched cannot be optimal; rounding in the
    // potentials must not let one through.
    if (cost(row, j - 1) > no_match_cost) continue;
    out.row_to_col[row] = j - 1;
    out.col_to_row[j - 1] = row;
  }
  for (int r = 0; r < rows; ++r)
    out.cost += out.row_to_col[r] >= 0 ? cost(r, out.row_to_col[r]) : no_match_cost;
  return out;
}

}  // namespace fact
