// Certification: the dual certificate Λ, S = C − Λ and its spectrum.
#include <algorithm>
#include <limits>
#include <sstream>

#include "internal.h"

namespace fact::sdp::detail {

Eigen::MatrixXd lambda_from_factor(const Eigen::MatrixXd& C, const Eigen::MatrixXd& Y, int d) {
  const Eigen::Index n = C.rows();
  const Eigen::MatrixXd CY = C * Y;  // n × r
  Eigen::MatrixXd lambda(n, d);      // Λ_ii stacked, n × d
  for (Eigen::Index i = 0; i < n; i += d) {
    const Eigen::MatrixXd block = CY.middleRows(i, d) * Y.middleRows(i, d).transpose();  // d × d
    lambda.middleRows(i, d) = 0.5 * (block + block.transpose());
  }
  return lambda;
}

void certificate_matrix(const Eigen::MatrixXd& C, const Eigen::MatrixXd& lambda, int d, Eigen::MatrixXd& S) {
  S = C;
  for (Eigen::Index i = 0; i < C.rows(); i += d) S.block(i, i, d, d) -= lambda.middleRows(i, d);
}

Eigen::MatrixXd certificate_matrix(const Eigen::MatrixXd& C, const Eigen::MatrixXd& lambda, int d) {
  Eigen::MatrixXd S;
  certificate_matrix(C, lambda, d, S);
  return S;
}

double block_trace(const Eigen::MatrixXd& lambda, int d) {
  double trace = 0;
  for (Eigen::Index i = 0; i < lambda.rows(); i += d) trace += lambda.middleRows(i, d).trace();
  return trace;
}

double eigensolver_error(Eigen::Index n, double scale) {
  return 4.0 * static_cast<double>(n) * std::numeric_limits<double>::epsilon() *
         std::max(scale, std::numeric_limits<double>::min());
}

void bound_from_spectrum(Certificate& cert) {
  cert.min_eig = cert.eigenvalues(0);
  // ⟨C, X⟩ = tr Λ + ⟨S, X⟩ ≥ tr Λ + λ_min(S)·tr X for every feasible X, and tr X = n. (A NaN
  // λ_min gives a NaN bound: std::min(0.0, NaN) would give 0 and a finite bound.)
  const Eigen::Index n = cert.eigenvalues.size();
  const double negative_part = cert.min_eig >= 0 ? 0.0 : cert.min_eig;
  cert.dual_bound = cert.trace_lambda + static_cast<double>(n) * negative_part;
  // What rounding can have moved it by: n·e, e the eigensolver's backward error on λ_min; the
  // sum tr Λ (n terms, (n + 2)ε relative to Σ|Λ_jj| with n·|λ_min| added); and C's scaling, ε
  // per entry of the scaled C (|X_jk| ≤ 1 on the feasible set, Σ|C_jk| ≤ n‖C‖_F = n).
  const double eps = std::numeric_limits<double>::epsilon(), dn = static_cast<double>(n);
  double abs_trace = 0;  // Σ_j |Λ_jj|
  for (Eigen::Index i = 0; i < cert.lambda.rows(); i += cert.lambda.cols())
    abs_trace += cert.lambda.middleRows(i, cert.lambda.cols()).diagonal().cwiseAbs().sum();
  cert.bound_error = dn * eigensolver_error(n, cert.eigenvalues.cwiseAbs().maxCoeff()) +
                     (dn + 2) * eps * (abs_trace + dn * std::abs(std::min(0.0, cert.min_eig))) + dn * eps;
}

Certificate certify(const Eigen::MatrixXd& C, const Eigen::MatrixXd& lambda, int d, bool want_vector) {
  Certificate cert;
  cert.lambda = lambda;
  const Eigen::MatrixXd S = certificate_matrix(C, lambda, d);
  if (want_vector) {
    Eigen::MatrixXd vector;  // n × 1
    lowest_eigenpairs(S, 1, cert.eigenvalues, vector);
    cert.min_vector = vector.col(0);
  } else {
    cert.eigenvalues = eigenvalues_of(S);
  }
  cert.trace_lambda = block_trace(lambda, d);
  bound_from_spectrum(cert);
  return cert;
}

GapRule::Verdict GapRule::next(double gap, double rel_gap, bool& improved) {
  const bool grew = gap >= best_gap_;
  improved = !grew;
  if (improved) {
    best_gap_ = gap;
    best_rel_gap_ = rel_gap;
  }
  if (rel_gap < stop_gap_) return last_ = Verdict::converged;
  if (rel_gap < handoff_gap_ && improved) return last_ = Verdict::handed_off;
  if (gap < 0.5 * halved_gap_) {
    halved_gap_ = gap;
    stalled_ = 0;
  } else {
    ++stalled_;
  }
  // Rounding now limits the last digits: the gap grew near the end, or has not halved in 4 iterations.
  if ((grew && best_rel_gap_ < 1e-6) || stalled_ >= 4) return last_ = Verdict::stalled;
  return last_ = Verdict::go_on;
}

std::string GapRule::reason(const char* solver, int iterations) const {
  std::ostringstream why;
  if (last_ == Verdict::handed_off)
    why << "handed off at relative gap " << best_rel_gap_;
  else
    why << solver << " stalled at relative gap " << best_rel_gap_ << " after " << iterations << " iterations";
  return why.str();
}

}  // namespace fact::sdp::detail
