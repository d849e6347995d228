#include <cmath>
#include <iomanip>
#include <sstream>

#include "internal.h"

namespace fact::sdp {

namespace {

// The arguments streamed into one string: built only for a message, because an
// std::ostringstream's construction alone (its locale) costs ~0.3 µs on every solve.
template <class... Parts>
std::string message(const Parts&... parts) {
  std::ostringstream why;
  (why << ... << parts);
  return why.str();
}

}  // namespace

std::string validate(const Eigen::MatrixXd& C, int d) {
  if (d != 1 && d != 2) {
    return message("d = ", d, ": block size must be 1 or 2");
  }
  if (C.rows() != C.cols()) {
    return message("C is ", C.rows(), "×", C.cols(), ": must be square");
  }
  if (C.rows() % d != 0) {
    return message("C is ", C.rows(), "×", C.cols(), ": size not divisible by d = ", d);
  }
  if (C.rows() / d < 2) {
    return message("N = ", C.rows() / d, " blocks: need at least 2 (one drone has nothing to relate to)");
  }
  for (Eigen::Index j = 0; j < C.cols(); ++j)
    for (Eigen::Index i = 0; i < C.rows(); ++i)
      if (!std::isfinite(C(i, j))) return message("C(", i, ",", j, ") = ", C(i, j), ": not finite");
  const double tol = 1e-9 * std::max(1.0, C.cwiseAbs().maxCoeff());
  for (Eigen::Index j = 0; j < C.cols(); ++j)
    for (Eigen::Index i = j + 1; i < C.rows(); ++i)
      if (std::abs(C(i, j) - C(j, i)) > tol)
        return message(std::setprecision(17), "C not symmetric: C(", i, ",", j, ") = ", C(i, j), " but C(", j, ",", i,
                       ") = ", C(j, i));
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
  }
  return "unknown";
}

}  // namespace fact::sdp
