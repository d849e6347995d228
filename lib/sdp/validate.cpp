#include <cmath>
#include <sstream>

#include "internal.h"

namespace fact::sdp {

std::string validate(const Eigen::MatrixXd& C, int d) {
  std::ostringstream why;
  if (d != 1 && d != 2) {
    why << "d = " << d << ": block size must be 1 or 2";
    return why.str();
  }
  if (C.rows() != C.cols()) {
    why << "C is " << C.rows() << "×" << C.cols() << ": must be square";
    return why.str();
  }
  if (C.rows() % d != 0) {
    why << "C is " << C.rows() << "×" << C.cols() << ": size not divisible by d = " << d;
    return why.str();
  }
  if (C.rows() / d < 2) {
    why << "N = " << C.rows() / d << " blocks: need at least 2 (one drone has nothing to relate to)";
    return why.str();
  }
  for (Eigen::Index j = 0; j < C.cols(); ++j)
    for (Eigen::Index i = 0; i < C.rows(); ++i)
      if (!std::isfinite(C(i, j))) {
        why << "C(" << i << "," << j << ") = " << C(i, j) << ": not finite";
        return why.str();
      }
  const double tol = 1e-9 * std::max(1.0, C.cwiseAbs().maxCoeff());
  for (Eigen::Index j = 0; j < C.cols(); ++j)
    for (Eigen::Index i = j + 1; i < C.rows(); ++i)
      if (std::abs(C(i, j) - C(j, i)) > tol) {
        why.precision(17);
        why << "C not symmetric: C(" << i << "," << j << ") = " << C(i, j) << " but C(" << j << "," << i
            << ") = " << C(j, i);
        return why.str();
      }
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
