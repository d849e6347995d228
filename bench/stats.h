// Sample statistics for the benchmarks' tables. Each function takes its sample by value (it sorts
// a copy) and returns NaN for an empty one; none drops non-finite values (filter first).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace fact::bench {

// The middle value, or the mean of the two middle values of an even count.
inline double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

// The q-quantile (0 ≤ q ≤ 1), interpolated linearly between the order statistics on either side
// of position q·(n − 1).
inline double quantile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const double position = q * static_cast<double>(v.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(std::floor(position));
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (position - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

// The order statistic nearest to position q·(n − 1) (0 ≤ q ≤ 1; a half rounds up).
inline double nearest_order_statistic(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5))];
}

// The nearest-rank percentile (0 < percent ≤ 100): the smallest value with at least percent % of
// the sample at or below it, the ⌈percent·n/100⌉-th smallest (in integers: no rounding of q·n).
inline double nearest_rank(std::vector<double> v, int percent) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t rank = (v.size() * static_cast<std::size_t>(percent) + 99) / 100;
  return v[std::clamp<std::size_t>(rank, 1, v.size()) - 1];
}

// v without its NaN and infinite values.
inline std::vector<double> finite_values(std::vector<double> v) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  return v;
}

}  // namespace fact::bench
