// The SDP solve: validate, scale, primal solve (low rank, then interior point if needed),
// certify, and classify. Each step is a named piece in internal.h.
#include <chrono>
#include <cmath>
#include <sstream>

#include "internal.h"

namespace fact::sdp {
namespace {

using detail::Certificate;

// Largest Newton system the polish may factor (its cost is size³/3): beyond it the
// interior point's own result stands.
constexpr int kMaxPolishSize = 2000;

struct Candidate {
  Eigen::MatrixXd Y;      // n × r factor of X
  Certificate cert;       // certificate for it (scaled problem)
  double primal = 0;      // ⟨C, Y Yᵀ⟩ (scaled), from primal_objective, set with cert
  int iterations = 0;
  Method method = Method::low_rank;
  std::string note;       // why the method stopped, when it did not converge
};

// Gap relative to the objective, on the scaled problem (‖C‖_F = 1); the floor 1e-4 keeps
// zero-optimum (noise-free) problems from dividing by nothing.
double relative_gap(double primal, double dual) {
  return (primal - dual) / std::max({1e-4, std::abs(primal), std::abs(dual)});
}

// ⟨C, Y Yᵀ⟩ for a feasible Y (every block of Y Yᵀ is I), computed as tr Λ + ⟨S, Y Yᵀ⟩.
// The two are equal in exact arithmetic; the second has no cancellation, because S and
// Y Yᵀ are both PSD, so the gap ⟨S, Y Yᵀ⟩ stays accurate when the optimum is small.
double primal_objective(const Eigen::MatrixXd& C, const Eigen::MatrixXd& Y, const Certificate& cert, int d) {
  const Eigen::MatrixXd SY = detail::certificate_matrix(C, cert.lambda, d) * Y;  // n × r
  return cert.trace_lambda + Y.cwiseProduct(SY).sum();
}

bool is_certified(const Candidate& c, const Options& o) {
  return c.cert.min_eig >= -o.psd_tol && relative_gap(c.primal, c.cert.dual_bound) <= o.gap_tol;
}

// In automatic mode the low-rank path only tries rank d (the tight case, where Newton has
// converged within 10 steps on every benchmark instance) for at most 25 steps; a problem
// that does not certify there goes to the interior point, which measures faster than
// climbing the staircase on high-rank optima.
Candidate from_low_rank(const Eigen::MatrixXd& C, int d, Options o) {
  if (o.method == Method::automatic) {
    o.max_rank = d;
    o.max_newton_iterations = std::min(o.max_newton_iterations, 25);
  }
  detail::LowRankOutcome lr = detail::solve_low_rank(C, d, o);
  Candidate c{std::move(lr.Y), std::move(lr.certificate), 0, lr.iterations, Method::low_rank, {}};
  c.primal = primal_objective(C, c.Y, c.cert, d);
  return c;
}

Candidate from_interior_point(const Eigen::MatrixXd& C, int d, const Options& o) {
  detail::InteriorPointOutcome ip = detail::solve_interior_point(C, d, o);
  Candidate c;
  c.Y = detail::factor_psd(ip.X, 0.0);
  c.cert = detail::certify(C, ip.lambda, d, false);
  c.primal = primal_objective(C, c.Y, c.cert, d);
  c.iterations = ip.iterations;
  c.method = Method::interior_point;
  c.note = ip.reason;
  return c;
}

// Riemannian Newton from the interior point's X, at the rank it found (at most the Pataki
// bound), when the Newton system is small enough. The interior point finds the optimal face
// reliably, but when the optimum is small against ‖C‖ its last digits are limited by the
// conditioning of Z⁻¹; Newton converges quadratically from there.
Candidate polish(const Eigen::MatrixXd& C, int d, const Candidate& ip) {
  // ip.Y's columns are X's eigenvectors scaled by √eigenvalue, largest first: keep those
  // with eigenvalue above 1e-6 of the largest, at most the Pataki bound.
  const Eigen::VectorXd eigenvalues = ip.Y.colwise().squaredNorm().transpose();
  const int blocks = static_cast<int>(C.rows() / d);
  const int max_rank = detail::pataki_rank(blocks, d);
  int rank = 0;
  while (rank < eigenvalues.size() && rank < max_rank && eigenvalues[rank] > 1e-6 * eigenvalues.maxCoeff()) ++rank;
  const int newton_size = blocks * (d * rank - d * (d + 1) / 2);  // unknowns of the Newton system
  if (rank < d || newton_size > kMaxPolishSize) return ip;
  Eigen::MatrixXd Y = ip.Y.leftCols(rank);
  if (!detail::project_blocks(Y, d)) return ip;
  Candidate c = ip;
  c.iterations += detail::newton_refine(C, d, Y, 60, 1e-12);
  c.Y = std::move(Y);
  c.cert = detail::certify(C, detail::lambda_from_factor(C, c.Y, d), d, false);
  c.primal = primal_objective(C, c.Y, c.cert, d);
  return c;
}

int numerical_rank(const Eigen::MatrixXd& Y) {
  if (Y.cols() == 0) return 0;
  const Eigen::VectorXd s = Eigen::JacobiSVD<Eigen::MatrixXd>(Y).singularValues();
  int r = 0;
  while (r < s.size() && s[r] > 1e-4 * s[0]) ++r;
  return r;
}

void classify(Result& r, const Candidate& c, const Options& o) {
  const Eigen::VectorXd& ev = c.cert.eigenvalues;
  r.nullity = static_cast<int>((ev.array() < o.null_tol).count());
  r.eig_gap = ev.size() > r.d ? ev[r.d] : 0.0;
  std::ostringstream why;
  if (r.min_eig_S < -o.psd_tol) {
    why << "S = C − Λ has λ_min = " << r.min_eig_S << " < −" << o.psd_tol << " after " << r.iterations << " "
        << to_string(c.method) << " iterations";
    if (!c.note.empty()) why << " (" << c.note << ")";
    r.status = Status::not_certified;
  } else if (r.rel_gap > o.gap_tol) {
    why << "relative duality gap " << r.rel_gap << " > " << o.gap_tol;
    if (!c.note.empty()) why << " (" << c.note << ")";
    r.status = Status::not_certified;
  } else if (r.nullity != r.d) {
    why << "optimal, but S has nullity " << r.nullity << " > d = " << r.d << " (λ_" << r.d + 1 << "(S) = " << r.eig_gap
        << " < " << o.null_tol << "): the optimum is not unique; X has rank " << r.rank;
    r.status = Status::certified_not_unique;
  } else {
    why << "optimal and unique: λ_min(S) = " << r.min_eig_S << ", nullity " << r.nullity << ", λ_" << r.d + 1
        << "(S) = " << r.eig_gap;
    r.status = Status::certified_unique;
  }
  r.reason = why.str();
}

}  // namespace

Result solve(const Eigen::MatrixXd& C, int d, const Options& options) {
  const auto start = std::chrono::steady_clock::now();
  Result r;
  r.d = d;
  r.reason = validate(C, d);
  if (!r.reason.empty()) return r;
  r.blocks = static_cast<int>(C.rows() / d);
  r.scale = C.norm() > 0 ? C.norm() : 1.0;
  const Eigen::MatrixXd Cs = C / r.scale;  // scaled problem, ‖Cs‖_F = 1 (or C = 0)

  Candidate best;
  const bool try_low_rank = options.method != Method::interior_point;
  if (try_low_rank) best = from_low_rank(Cs, d, options);
  if (options.method == Method::interior_point ||
      (options.method == Method::automatic && !is_certified(best, options))) {
    Candidate ip = from_interior_point(Cs, d, options);
    ip.iterations += best.iterations;
    if (options.method == Method::automatic && !is_certified(ip, options)) {
      Candidate polished = polish(Cs, d, ip);
      if (is_certified(polished, options)) ip = std::move(polished);
    }
    if (!try_low_rank || is_certified(ip, options) || ip.cert.dual_bound > best.cert.dual_bound) best = ip;
  }

  const double primal = best.primal;
  r.method_used = best.method;
  r.Y = best.Y;
  r.Lambda = best.cert.lambda * r.scale;
  r.objective = primal * r.scale;
  r.dual_bound = best.cert.dual_bound * r.scale;
  r.rel_gap = relative_gap(primal, best.cert.dual_bound);
  r.min_eig_S = best.cert.min_eig;
  r.rank = numerical_rank(best.Y);
  r.iterations = best.iterations;
  classify(r, best, options);
  r.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace fact::sdp
