// Tests of fact::solve_assignment: minimise Σ matched cost(r, c) + no_match_cost · #(unmatched
// rows) over one-to-one partial matchings. The expected optima come from brute force over every
// partial matching (small matrices), from hand-worked cases, and, for larger ones, from planted
// optima and from the transposed problem.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "fact/hungarian.h"

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The cost of an assignment recomputed from its row_to_col, independently of solve_assignment.
double assignment_cost(const Eigen::MatrixXd& cost, double no_match_cost, const std::vector<int>& row_to_col) {
  double total = 0;
  for (std::size_t r = 0; r < row_to_col.size(); ++r)
    total += row_to_col[r] >= 0 ? cost(r, row_to_col[r]) : no_match_cost;
  return total;
}

// Lowest cost over every one-to-one partial matching, by exhaustive search: row r either stays
// unmatched or takes any column not used by rows 0 … r−1. +inf pairs are never taken.
double brute_force(const Eigen::MatrixXd& cost, double no_match_cost, int row, std::vector<char>& used) {
  if (row == cost.rows()) return 0;
  double best = no_match_cost + brute_force(cost, no_match_cost, row + 1, used);
  for (int c = 0; c < cost.cols(); ++c) {
    if (used[c] || cost(row, c) == kInf) continue;
    used[c] = 1;
    best = std::min(best, cost(row, c) + brute_force(cost, no_match_cost, row + 1, used));
    used[c] = 0;
  }
  return best;
}

double brute_force(const Eigen::MatrixXd& cost, double no_match_cost) {
  std::vector<char> used(cost.cols(), 0);
  return brute_force(cost, no_match_cost, 0, used);
}

// Checks that `a` is a consistent one-to-one partial matching of `cost` that never takes a
// +inf pair or a pair dearer than no_match_cost, and that a.cost is its cost.
void expect_valid(const Eigen::MatrixXd& cost, double no_match_cost, const fact::Assignment& a) {
  ASSERT_EQ(a.row_to_col.size(), static_cast<std::size_t>(cost.rows()));
  ASSERT_EQ(a.col_to_row.size(), static_cast<std::size_t>(cost.cols()));
  int matched_rows = 0, matched_cols = 0;
  for (int r = 0; r < cost.rows(); ++r) {
    const int c = a.row_to_col[r];
    if (c < 0) {
      EXPECT_EQ(c, -1) << "row " << r;
      continue;
    }
    ++matched_rows;
    ASSERT_LT(c, cost.cols()) << "row " << r;
    EXPECT_EQ(a.col_to_row[c], r) << "row " << r << " → col " << c << " not mirrored";
    EXPECT_LT(cost(r, c), kInf) << "row " << r << " matched to a forbidden col " << c;
    EXPECT_LE(cost(r, c), no_match_cost) << "row " << r << " col " << c;
  }
  for (int c = 0; c < cost.cols(); ++c) {
    const int r = a.col_to_row[c];
    if (r < 0) {
      EXPECT_EQ(r, -1) << "col " << c;
      continue;
    }
    ++matched_cols;
    ASSERT_LT(r, cost.rows()) << "col " << c;
    EXPECT_EQ(a.row_to_col[r], c) << "col " << c << " → row " << r << " not mirrored";
  }
  EXPECT_EQ(matched_rows, matched_cols);
  EXPECT_NEAR(a.cost, assignment_cost(cost, no_match_cost, a.row_to_col), 1e-12);
}

// The message of the std::invalid_argument that solve_assignment throws, or "" when it throws none.
std::string assignment_error(const Eigen::MatrixXd& cost, double no_match_cost) {
  try {
    fact::solve_assignment(cost, no_match_cost);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Hungarian, MatchesBruteForceOnRandomSmallProblems) {
  std::mt19937_64 rng(2024);
  std::uniform_int_distribution<int> size(0, 6);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> small_int(0, 3);
  const double no_match_costs[] = {-0.5, 0.0, 0.25, 0.5, 1.0, 2.5, 1e3};
  int cases = 0, with_unmatched = 0, with_inf = 0;
  for (int trial = 0; trial < 800; ++trial) {
    const int rows = size(rng), cols = size(rng);
    const double no_match = no_match_costs[trial % 7];
    const bool integer_entries = trial % 3 == 0;  // many ties
    const double inf_fraction = (trial % 4) * 0.15;
    Eigen::MatrixXd cost(rows, cols);
    for (int c = 0; c < cols; ++c)
      for (int r = 0; r < rows; ++r) {
        cost(r, c) = integer_entries ? small_int(rng) * 0.5 : 2.0 * unit(rng) - 0.3;
        if (unit(rng) < inf_fraction) cost(r, c) = kInf;
      }
    SCOPED_TRACE("trial " + std::to_string(trial) + ": " + std::to_string(rows) + " × " + std::to_string(cols) +
                 ", no_match_cost " + std::to_string(no_match));
    const fact::Assignment a = fact::solve_assignment(cost, no_match);
    expect_valid(cost, no_match, a);
    EXPECT_NEAR(a.cost, brute_force(cost, no_match), 1e-12);
    ++cases;
    for (int r : a.row_to_col) with_unmatched += r < 0;
    with_inf += (cost.array() == kInf).any();
  }
  EXPECT_EQ(cases, 800);
  EXPECT_GT(with_unmatched, 100);  // the no-match option was really exercised
  EXPECT_GT(with_inf, 100);
}

TEST(Hungarian, WideProblemPicksTheCheapestColumns) {
  // 2 rows × 4 cols. Best: row 0 → col 3 (1), row 1 → col 1 (2); total 3.
  Eigen::MatrixXd cost(2, 4);
  cost << 5, 9, 4, 1,
          6, 2, 3, 1.5;
  const fact::Assignment a = fact::solve_assignment(cost, 100);
  expect_valid(cost, 100, a);
  EXPECT_EQ(a.row_to_col, (std::vector<int>{3, 1}));
  EXPECT_EQ(a.col_to_row, (std::vector<int>{-1, 1, -1, 0}));
  EXPECT_DOUBLE_EQ(a.cost, 3.0);
}

TEST(Hungarian, TallProblemLeavesTheDearestRowUnmatched) {
  // 4 rows × 2 cols: at least two rows stay unmatched at 10 each.
  // Best: row 2 → col 0 (1), row 0 → col 1 (2), rows 1 and 3 unmatched; 1 + 2 + 20 = 23.
  Eigen::MatrixXd cost(4, 2);
  cost << 3, 2,
          4, 4,
          1, 3,
          5, 6;
  const fact::Assignment a = fact::solve_assignment(cost, 10);
  expect_valid(cost, 10, a);
  EXPECT_EQ(a.row_to_col, (std::vector<int>{1, -1, 0, -1}));
  EXPECT_EQ(a.col_to_row, (std::vector<int>{2, 0}));
  EXPECT_DOUBLE_EQ(a.cost, 23.0);
}

TEST(Hungarian, PairsDearerThanNoMatchAreLeftUnmatched) {
  // Row 0's only cheap column is taken more profitably by row 1; row 0's other pair (7) costs
  // more than leaving it unmatched (5). Best: row 1 → col 0 (0), row 0 unmatched (5).
  Eigen::MatrixXd cost(2, 2);
  cost << 1, 7,
          0, kInf;
  fact::Assignment a = fact::solve_assignment(cost, 5);
  expect_valid(cost, 5, a);
  EXPECT_EQ(a.row_to_col, (std::vector<int>{-1, 0}));
  EXPECT_DOUBLE_EQ(a.cost, 5.0);
  // With no_match_cost 8 the 7 pair becomes worth taking: 7 + 0.
  a = fact::solve_assignment(cost, 8);
  expect_valid(cost, 8, a);
  EXPECT_EQ(a.row_to_col, (std::vector<int>{1, 0}));
  EXPECT_DOUBLE_EQ(a.cost, 7.0);
}

TEST(Hungarian, AllForbiddenMeansNothingMatched) {
  const Eigen::MatrixXd cost = Eigen::MatrixXd::Constant(3, 5, kInf);
  const fact::Assignment a = fact::solve_assignment(cost, 2.5);
  expect_valid(cost, 2.5, a);
  EXPECT_EQ(a.row_to_col, (std::vector<int>(3, -1)));
  EXPECT_EQ(a.col_to_row, (std::vector<int>(5, -1)));
  EXPECT_DOUBLE_EQ(a.cost, 7.5);
}

TEST(Hungarian, TiesGiveAnOptimalFullMatching) {
  // Every pair costs 1 against a no-match cost of 2: any perfect matching of the 4 rows is
  // optimal, cost 4; every row must be matched.
  const Eigen::MatrixXd cost = Eigen::MatrixXd::Ones(4, 6);
  const fact::Assignment a = fact::solve_assignment(cost, 2);
  expect_valid(cost, 2, a);
  for (int r = 0; r < 4; ++r) EXPECT_GE(a.row_to_col[r], 0) << "row " << r;
  EXPECT_DOUBLE_EQ(a.cost, 4.0);
  // Pair cost equal to the no-match cost: either choice is optimal, the cost is 4 regardless.
  const fact::Assignment b = fact::solve_assignment(cost, 1);
  expect_valid(cost, 1, b);
  EXPECT_DOUBLE_EQ(b.cost, 4.0);
}

TEST(Hungarian, EmptyInputs) {
  fact::Assignment a = fact::solve_assignment(Eigen::MatrixXd(0, 0), 1.0);
  EXPECT_TRUE(a.row_to_col.empty());
  EXPECT_TRUE(a.col_to_row.empty());
  EXPECT_EQ(a.cost, 0.0);

  a = fact::solve_assignment(Eigen::MatrixXd(0, 4), 1.0);
  EXPECT_TRUE(a.row_to_col.empty());
  EXPECT_EQ(a.col_to_row, (std::vector<int>(4, -1)));
  EXPECT_EQ(a.cost, 0.0);

  a = fact::solve_assignment(Eigen::MatrixXd(3, 0), 1.5);
  EXPECT_EQ(a.row_to_col, (std::vector<int>(3, -1)));
  EXPECT_TRUE(a.col_to_row.empty());
  EXPECT_DOUBLE_EQ(a.cost, 4.5);
}

TEST(Hungarian, FindsAPlantedPermutationInALargeProblem) {
  // 40 × 60: row r's planted column p(r) costs 0, every other pair costs in [1, 2), so the
  // planted matching is the unique optimum.
  const int rows = 40, cols = 60;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<int> planted(cols);
  for (int c = 0; c < cols; ++c) planted[c] = c;
  std::shuffle(planted.begin(), planted.end(), rng);
  Eigen::MatrixXd cost(rows, cols);
  for (int c = 0; c < cols; ++c)
    for (int r = 0; r < rows; ++r) cost(r, c) = 1.0 + unit(rng);
  for (int r = 0; r < rows; ++r) cost(r, planted[r]) = 0.0;
  const fact::Assignment a = fact::solve_assignment(cost, 5.0);
  expect_valid(cost, 5.0, a);
  for (int r = 0; r < rows; ++r) EXPECT_EQ(a.row_to_col[r], planted[r]) << "row " << r;
  EXPECT_EQ(a.cost, 0.0);
}

TEST(Hungarian, TransposeAgreesWhenEveryPossibleRowIsMatched) {
  // With a no-match cost larger than any full matching, the wide problem matches every row and
  // the tall (transposed) one leaves exactly cols − rows rows unmatched, so
  // cost(tall) = cost(wide) + (cols − rows) · no_match_cost. Also reuses the per-thread
  // scratch across sizes.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const auto& [rows, cols] : {std::pair{30, 45}, std::pair{3, 9}, std::pair{25, 26}, std::pair{1, 50}}) {
    Eigen::MatrixXd cost(rows, cols);
    for (int c = 0; c < cols; ++c)
      for (int r = 0; r < rows; ++r) cost(r, c) = unit(rng);
    const double no_match = 1e3;
    const fact::Assignment wide = fact::solve_assignment(cost, no_match);
    const fact::Assignment tall = fact::solve_assignment(cost.transpose(), no_match);
    SCOPED_TRACE(std::to_string(rows) + " × " + std::to_string(cols));
    expect_valid(cost, no_match, wide);
    expect_valid(cost.transpose(), no_match, tall);
    for (int r = 0; r < rows; ++r) EXPECT_GE(wide.row_to_col[r], 0) << "row " << r;
    EXPECT_NEAR(tall.cost, wide.cost + (cols - rows) * no_match, 1e-9);
    // The same pairs, read from either side.
    for (int r = 0; r < rows; ++r) EXPECT_EQ(tall.col_to_row[r], wide.row_to_col[r]) << "row " << r;
  }
}

TEST(Hungarian, RejectsNanAndMinusInfinityNamingTheEntry) {
  Eigen::MatrixXd cost = Eigen::MatrixXd::Zero(3, 4);
  cost(1, 2) = std::nan("");
  std::string message = assignment_error(cost, 1.0);
  EXPECT_NE(message.find("row 1"), std::string::npos) << message;
  EXPECT_NE(message.find("col 2"), std::string::npos) << message;
  EXPECT_NE(message.find("nan"), std::string::npos) << message;

  cost(1, 2) = 0.0;
  cost(2, 0) = -kInf;
  message = assignment_error(cost, 1.0);
  EXPECT_NE(message.find("row 2"), std::string::npos) << message;
  EXPECT_NE(message.find("col 0"), std::string::npos) << message;
  EXPECT_NE(message.find("-inf"), std::string::npos) << message;

  cost(2, 0) = kInf;  // +inf is allowed: "never match"
  EXPECT_EQ(assignment_error(cost, 1.0), "");
}

TEST(Hungarian, RejectsNonFiniteNoMatchCost) {
  const Eigen::MatrixXd cost = Eigen::MatrixXd::Zero(2, 2);
  for (double bad : {kInf, -kInf, std::nan("")}) {
    const std::string message = assignment_error(cost, bad);
    EXPECT_NE(message.find("no_match_cost"), std::string::npos) << message;
  }
}

// Entries and no_match_cost beyond ±1e100 are refused, naming them: at ±1e308 the slacks
// overflowed to +inf and the search wrote outside its arrays (heap corruption, 3 × 1 of −1e308).
TEST(Hungarian, RejectsHugeEntriesAndNoMatchCost) {
  Eigen::MatrixXd cost = Eigen::MatrixXd::Constant(3, 1, -1e308);
  std::string message = assignment_error(cost, 1e308);
  EXPECT_NE(message.find("no_match_cost"), std::string::npos) << message;
  message = assignment_error(cost, 1.0);
  EXPECT_NE(message.find("row 0"), std::string::npos) << message;
  EXPECT_NE(message.find("1e+308"), std::string::npos) << message;
  // At the limit the answer is still right: the cheapest row takes the column.
  cost << 1e100, -1e100, 0;
  const fact::Assignment a = fact::solve_assignment(cost, 1e100);
  EXPECT_EQ(a.col_to_row[0], 1);
  EXPECT_EQ(a.cost, 1e100 + -1e100 + 1e100);
}

}  // namespace
