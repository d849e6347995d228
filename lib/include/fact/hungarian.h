// Rectangular assignment (Hungarian / Kuhn–Munkres, O(n³) shortest augmenting paths), written
// here. Used to match anonymous detections.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace fact {

struct Assignment {
  std::vector<int> row_to_col;  // size rows; column matched to each row, −1 = no match
  std::vector<int> col_to_row;  // size cols; row matched to each column, −1 = no match
  double cost = 0;              // Σ matched costs + no_match_cost · (unmatched rows)
};

// Minimises Σ_{matched (r,c)} cost(r,c) + no_match_cost · #(unmatched rows) over one-to-one
// partial matchings of rows to columns. Unmatched columns cost nothing. So a pair whose cost
// exceeds no_match_cost is never matched. cost is rows × cols (either may be 0 or larger than the
// other); entries must be finite and at most 1e100 in magnitude, except +infinity, which means
// "never match". Throws std::invalid_argument naming the entry (row, col, value) if an entry is
// NaN, −inf or beyond ±1e100, or if no_match_cost is not finite or beyond ±1e100. Among equally cheap matchings any one may be returned.
// Cost O(rows² · (cols + rows)); an 8 × 16 problem takes about 1.5 µs. Thread-safe: the working
// arrays are per thread and reused, so only the result allocates once sizes have been seen.
Assignment solve_assignment(const Eigen::MatrixXd& cost, double no_match_cost);

}  // namespace fact
