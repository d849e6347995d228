// bench/stats.h: the statistics every benchmark's tables print.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "stats.h"

namespace {

using fact::bench::finite_values;
using fact::bench::median;
using fact::bench::nearest_order_statistic;
using fact::bench::nearest_rank;
using fact::bench::quantile;

TEST(BenchStats, MedianIsTheMiddleOrTheMeanOfTheTwoMiddleValues) {
  EXPECT_EQ(median({3, 1, 2}), 2);
  EXPECT_EQ(median({4, 1, 3, 2}), 2.5);
  EXPECT_EQ(median({7}), 7);
  EXPECT_TRUE(std::isnan(median({})));
}

TEST(BenchStats, QuantileInterpolatesBetweenOrderStatistics) {
  const std::vector<double> v = {40, 10, 30, 20, 50};  // sorted 10 … 50, positions 0 … 4
  EXPECT_EQ(quantile(v, 0.0), 10);
  EXPECT_EQ(quantile(v, 1.0), 50);
  EXPECT_EQ(quantile(v, 0.5), 30);
  EXPECT_DOUBLE_EQ(quantile(v, 0.95), 48);  // position 3.8
  EXPECT_DOUBLE_EQ(quantile({1, 2}, 0.5), 1.5);
  EXPECT_TRUE(std::isnan(quantile({}, 0.5)));
}

TEST(BenchStats, NearestOrderStatisticRoundsThePosition) {
  const std::vector<double> v = {5, 1, 4, 2, 3};  // positions 0 … 4
  EXPECT_EQ(nearest_order_statistic(v, 0.9), 5);   // 3.6 → 4
  EXPECT_EQ(nearest_order_statistic(v, 0.6), 3);   // 2.4 → 2
  EXPECT_EQ(nearest_order_statistic(v, 0.625), 4);  // 2.5 → 3
  EXPECT_TRUE(std::isnan(nearest_order_statistic({}, 0.9)));
}

// ⌈p·n/100⌉-th smallest: the p90 of 10 values is the 9th, of 11 the 10th, of 1 the only one.
TEST(BenchStats, NearestRankIsTheSmallestValueWithEnoughOfTheSampleAtOrBelowIt) {
  std::vector<double> ten;
  for (int i = 10; i >= 1; --i) ten.push_back(i);
  EXPECT_EQ(nearest_rank(ten, 90), 9);
  EXPECT_EQ(nearest_rank(ten, 100), 10);
  EXPECT_EQ(nearest_rank(ten, 1), 1);
  std::vector<double> eleven = ten;
  eleven.push_back(11);
  EXPECT_EQ(nearest_rank(eleven, 90), 10);  // ⌈9.9⌉
  std::vector<double> twenty;
  for (int i = 1; i <= 20; ++i) twenty.push_back(i);
  EXPECT_EQ(nearest_rank(twenty, 90), 18);  // exactly 18, not 19 (0.9·20 in floating point)
  EXPECT_EQ(nearest_rank({4}, 90), 4);
  EXPECT_TRUE(std::isnan(nearest_rank({}, 90)));
}

TEST(BenchStats, FiniteValuesDropsNaNAndInfinities) {
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(finite_values({1, NAN, inf, -inf, 2}), (std::vector<double>{1, 2}));
  EXPECT_EQ(median(finite_values({NAN, 3, 1})), 2);
}

}  // namespace
