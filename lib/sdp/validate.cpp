#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>

#include "internal.h"

namespace fact::sdp {

namespace detail {

std::string printed(const char* format, ...) {
  char buffer[512];
  va_list args;
  va_start(args, format);
  const int length = std::vsnprintf(buffer, sizeof buffer, format, args);
  va_end(args);
  return std::string(buffer, static_cast<std::size_t>(std::clamp(length, 0, static_cast<int>(sizeof buffer) - 1)));
}

}  // namespace detail

using detail::printed;

std::string validate(const Eigen::MatrixXd& C, int d) {
  if (d != 1 && d != 2) {
    return printed("d = %d: block size must be 1 or 2", d);
  }
  if (C.rows() != C.cols()) {
    return printed("C is %td×%td: must be square", C.rows(), C.cols());
  }
  if (C.rows() % d != 0) {
    return printed("C is %td×%td: size not divisible by d = %d", C.rows(), C.cols(), d);
  }
  if (C.rows() / d < 2) {
    return printed("N = %td blocks: need at least 2 (one drone has nothing to relate to)", C.rows() / d);
  }
  for (Eigen::Index j = 0; j < C.cols(); ++j)
    for (Eigen::Index i = 0; i < C.rows(); ++i)
      if (!std::isfinite(C(i, j))) return printed("C(%td,%td) = %g: not finite", i, j, C(i, j));
  const double largest = C.cwiseAbs().maxCoeff();
  const double n = static_cast<double>(C.rows());
  Eigen::Index largest_row = 0, largest_col = 0;  // where it is: only for the messages
  if (largest > kLargestObjective / (n * n) || (largest > 0 && largest < kSmallestEntry))
    C.cwiseAbs().maxCoeff(&largest_row, &largest_col);
  if (largest > kLargestObjective / (n * n))
    return printed("C(%td,%td) = %g: too large for n = %td; max|C_ij| must stay below %g/n² = %g, or the objective "
                   "(up to n²·max|C_ij|) may not be a finite double",
                   largest_row, largest_col, C(largest_row, largest_col), C.rows(), kLargestObjective,
                   kLargestObjective / (n * n));
  if (largest > 0 && largest < kSmallestEntry)
    return printed("C(%td,%td) = %g is C's largest entry: below %g the certificate's multipliers, of C's scale, lose "
                   "their digits to subnormal rounding (scale C up; C = 0 itself is accepted)",
                   largest_row, largest_col, C(largest_row, largest_col), kSmallestEntry);
  const double tol = 1e-9 * largest;  // relative to C's own scale, whatever it is
  for (Eigen::Index j = 0; j < C.cols(); ++j)
    for (Eigen::Index i = j + 1; i < C.rows(); ++i)
      if (std::abs(C(i, j) - C(j, i)) > tol)
        return printed("C not symmetric: C(%td,%td) = %.17g but C(%td,%td) = %.17g", i, j, C(i, j), j, i, C(j, i));
  return {};
}

std::string validate(const Options& options) {
  const auto tolerance = [](const char* name, double value) {
    return std::isfinite(value) && value >= 0 ? std::string() : printed("%s = %g: must be finite and ≥ 0", name, value);
  };
  const auto count = [](const char* name, int value) {
    return value >= 0 ? std::string() : printed("%s = %d: must be ≥ 0", name, value);
  };
  for (const std::string& why :
       {tolerance("gap_tol", options.gap_tol), tolerance("psd_tol", options.psd_tol),
        tolerance("null_tol", options.null_tol), count("max_sweeps", options.max_sweeps),
        count("max_ipm_iterations", options.max_ipm_iterations),
        count("max_newton_iterations", options.max_newton_iterations), count("max_rank", options.max_rank)})
    if (!why.empty()) return "options: " + why;
  const int method = static_cast<int>(options.method);
  if (method < static_cast<int>(Method::automatic) || method > static_cast<int>(Method::null_space))
    return printed("options: method = %d: not a Method", method);
  return {};
}

const char* to_string(Status s) {
  switch (s) {
    case Status::certified_unique: return "certified_unique";
    case Status::certified_not_unique: return "certified_not_unique";
    case Status::not_certified: return "not_certified";
    case Status::invalid_input: return "invalid_input";
  }
  return "unknown";
}

const char* to_string(Method m) {
  switch (m) {
    case Method::automatic: return "automatic";
    case Method::low_rank: return "low_rank";
    case Method::interior_point: return "interior_point";
    case Method::complex_low_rank: return "complex_low_rank";
    case Method::null_space: return "null_space";
  }
  return "unknown";
}

}  // namespace fact::sdp
