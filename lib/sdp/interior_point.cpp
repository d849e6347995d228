// Primal–dual interior point for  min ⟨C,X⟩  s.t.  X_ii = I_d,  X ⪰ 0.
//
// Feasible start (X = I, Λ = −2I so Z = C − Λ ≻ 0 because ‖C‖_F = 1), HKM search
// direction, Mehrotra predictor–corrector. Because both residuals stay zero, ΔZ = −Aᵀ(Δy)
// is block diagonal, which keeps every product with ΔZ at O(n² d).
//
// Constraints p = (block i, a ≤ b) pick entries (u, v) = (d·i+a, d·i+b):
//   diagonal (u = v):   A_p = e_u e_uᵀ,              b_p = 1
//   off-diagonal:       A_p = e_u e_vᵀ + e_v e_uᵀ,   b_p = 0
// so Aᵀ(y) = blkdiag(Λ) with Λ entries equal to the y_p, and A(W)_p = W_uv (+ W_vu).
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

#include "internal.h"

namespace fact::sdp::detail {
namespace {

struct Entry {
  int u, v;  // the (row, column) of X this constraint fixes, u ≤ v
};

std::vector<Entry> constraint_entries(int n, int d) {
  std::vector<Entry> entries;
  for (int i = 0; i < n; i += d)
    for (int a = 0; a < d; ++a)
      for (int b = a; b < d; ++b) entries.push_back({i + a, i + b});
  return entries;
}

// A(W) for symmetric or general W: m-vector.
Eigen::VectorXd apply_A(const Eigen::MatrixXd& W, const std::vector<Entry>& entries) {
  Eigen::VectorXd out(entries.size());
  for (std::size_t p = 0; p < entries.size(); ++p) {
    const auto [u, v] = entries[p];
    out[p] = u == v ? W(u, u) : W(u, v) + W(v, u);
  }
  return out;
}

// Λ (n × d, blocks stacked) from y.
Eigen::MatrixXd lambda_from_y(const Eigen::VectorXd& y, const std::vector<Entry>& entries, int n, int d) {
  Eigen::MatrixXd lambda = Eigen::MatrixXd::Zero(n, d);
  for (std::size_t p = 0; p < entries.size(); ++p) {
    const auto [u, v] = entries[p];
    lambda(u, v % d) = y[p];
    lambda(v, u % d) = y[p];
  }
  return lambda;
}

// Schur complement M_pq = tr(A_p X A_q W), m × m, with W = Z⁻¹.
// For A_p = Σ e_α e_βᵀ over its entry pairs: tr(e_α e_βᵀ X e_γ e_δᵀ W) = X_βγ W_δα.
Eigen::MatrixXd schur_complement(const Eigen::MatrixXd& X, const Eigen::MatrixXd& W,
                                 const std::vector<Entry>& entries) {
  const int m = static_cast<int>(entries.size());
  Eigen::MatrixXd M(m, m);
  for (int p = 0; p < m; ++p) {
    const auto [u, v] = entries[p];
    for (int q = p; q < m; ++q) {
      const auto [s, t] = entries[q];
      double value;
      if (u == v && s == t) {
        value = X(u, s) * W(s, u);
      } else if (u == v) {  // A_q has (s,t) and (t,s)
        value = X(u, s) * W(t, u) + X(u, t) * W(s, u);
      } else if (s == t) {  // A_p has (u,v) and (v,u)
        value = X(v, s) * W(s, u) + X(u, s) * W(s, v);
      } else {
        value = X(v, s) * W(t, u) + X(v, t) * W(s, u) + X(u, s) * W(t, v) + X(u, t) * W(s, v);
      }
      M(p, q) = M(q, p) = value;
    }
  }
  return M;
}

// (P · blkdiag(D)) for P n × n and D stacked n × d: O(n² d).
Eigen::MatrixXd times_block_diagonal(const Eigen::MatrixXd& P, const Eigen::MatrixXd& D, int d) {
  Eigen::MatrixXd out(P.rows(), P.cols());
  for (Eigen::Index i = 0; i < P.cols(); i += d)
    out.middleCols(i, d).noalias() = P.middleCols(i, d) * D.middleRows(i, d);
  return out;
}

// Smallest eigenvalue estimate of L⁻¹ Δ L⁻ᵀ by Lanczos (k steps, full reorthogonalisation).
// Ritz values lie inside the spectrum, so the caller verifies the step with a Cholesky test.
double lanczos_min_eig(const Eigen::LLT<Eigen::MatrixXd>& chol, const Eigen::MatrixXd& delta, int k) {
  const Eigen::Index n = delta.rows();
  k = static_cast<int>(std::min<Eigen::Index>(k, n));
  Eigen::MatrixXd V(n, k);  // Lanczos basis, n × k
  Eigen::VectorXd alpha(k), beta(k);
  Eigen::VectorXd v = Eigen::VectorXd::Ones(n) / std::sqrt(static_cast<double>(n));
  for (Eigen::Index i = 0; i < n; ++i) v[i] += 1e-3 * std::sin(1.0 + 7.0 * i);  // avoid symmetric starts
  v.normalize();
  int steps = 0;
  for (int j = 0; j < k; ++j) {
    V.col(j) = v;
    Eigen::VectorXd w = chol.matrixU().solve(v);  // L⁻ᵀ v
    w = delta * w;
    chol.matrixL().solveInPlace(w);               // L⁻¹ Δ L⁻ᵀ v
    alpha[j] = v.dot(w);
    w -= V.leftCols(j + 1) * (V.leftCols(j + 1).transpose() * w);
    w -= V.leftCols(j + 1) * (V.leftCols(j + 1).transpose() * w);
    beta[j] = w.norm();
    steps = j + 1;
    if (beta[j] < 1e-12) break;
    v = w / beta[j];
  }
  Eigen::MatrixXd T = Eigen::MatrixXd::Zero(steps, steps);  // tridiagonal Lanczos matrix
  for (int j = 0; j < steps; ++j) {
    T(j, j) = alpha[j];
    if (j + 1 < steps) T(j, j + 1) = T(j + 1, j) = beta[j];
  }
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(T, Eigen::EigenvaluesOnly).eigenvalues()(0);
}

// Number of eigenvalues below x of the symmetric tridiagonal (diag a, off-diagonal b): Sturm count.
int eigenvalues_below(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double x) {
  int count = 0;
  double q = a[0] - x;
  if (q < 0) ++count;
  for (Eigen::Index i = 1; i < a.size(); ++i) {
    if (q == 0) q = 1e-300;
    q = a[i] - x - b[i - 1] * b[i - 1] / q;
    if (q < 0) ++count;
  }
  return count;
}

// Smallest eigenvalue of L⁻¹ Δ L⁻ᵀ (small n): Householder tridiagonalisation, then bisection
// on the Sturm count to a relative accuracy of 1e-6 of the spectral radius bound.
double exact_min_eig(const Eigen::LLT<Eigen::MatrixXd>& chol, const Eigen::MatrixXd& delta) {
  const Eigen::MatrixXd LinvD = chol.matrixL().solve(delta);                           // L⁻¹ Δ
  const Eigen::MatrixXd B = chol.matrixL().solve(Eigen::MatrixXd(LinvD.transpose()));  // L⁻¹ Δ L⁻ᵀ
  const Eigen::Tridiagonalization<Eigen::MatrixXd> tri(0.5 * (B + B.transpose()));
  const Eigen::VectorXd a = tri.diagonal(), b = tri.subDiagonal();
  double radius = 0;  // Gershgorin bound on |λ|
  for (Eigen::Index i = 0; i < a.size(); ++i)
    radius = std::max(radius, std::abs(a[i]) + (i > 0 ? std::abs(b[i - 1]) : 0.0) +
                                  (i + 1 < a.size() ? std::abs(b[i]) : 0.0));
  double lo = -radius, hi = radius;
  while (hi - lo > 1e-6 * radius) {
    const double mid = 0.5 * (lo + hi);
    (eigenvalues_below(a, b, mid) > 0 ? hi : lo) = mid;
  }
  return lo;
}

// Largest α ≤ 1 with P + α Δ ≻ 0 (times the fraction τ), given the Cholesky factor of P.
double step_length(const Eigen::MatrixXd& P, const Eigen::LLT<Eigen::MatrixXd>& chol, const Eigen::MatrixXd& delta,
                   double tau) {
  const bool small = P.rows() <= 48;
  const double lmin = small ? exact_min_eig(chol, delta) : lanczos_min_eig(chol, delta, 24);
  double alpha = lmin < 0 ? std::min(1.0, -tau / lmin) : 1.0;
  if (tau >= 1.0) return alpha;  // predictor: only used to estimate μ, may touch the boundary
  for (int tries = 0; tries < 30; ++tries, alpha *= 0.7) {
    Eigen::LLT<Eigen::MatrixXd> test(P + alpha * delta);
    if (test.info() == Eigen::Success) return alpha;
  }
  return 0.0;
}

}  // namespace

InteriorPointOutcome solve_interior_point(const Eigen::MatrixXd& C, int d, const Options& options) {
  const int n = static_cast<int>(C.rows());
  const auto entries = constraint_entries(n, d);
  const int m = static_cast<int>(entries.size());
  Eigen::VectorXd b(m);  // right-hand side of A(X) = b
  for (int p = 0; p < m; ++p) b[p] = entries[p].u == entries[p].v ? 1.0 : 0.0;

  InteriorPointOutcome out;
  Eigen::MatrixXd X = Eigen::MatrixXd::Identity(n, n);  // primal, n × n
  Eigen::VectorXd y = -2.0 * b;                          // dual, m
  Eigen::MatrixXd lambda = lambda_from_y(y, entries, n, d);
  Eigen::MatrixXd Z = certificate_matrix(C, lambda, d);  // dual slack, n × n
  const double tau = 0.95;

  double best_gap = std::numeric_limits<double>::infinity();
  int stalled = 0;  // iterations since the gap last halved
  for (int it = 0; it < options.max_ipm_iterations; ++it) {
    out.iterations = it + 1;
    const double primal = (C.cwiseProduct(X)).sum(), dual = b.dot(y);
    const double gap = X.cwiseProduct(Z).sum();
    const double rel_gap = gap / std::max({1e-4, std::abs(primal), std::abs(dual)});
    if (rel_gap < 0.1 * options.gap_tol) {
      out.converged = true;
      break;
    }
    if (gap < 0.5 * best_gap) {
      best_gap = gap;
      stalled = 0;
    } else if (++stalled >= 4) {  // rounding now limits the last digits
      std::ostringstream why;
      why << "interior point stalled at relative gap " << rel_gap << " after " << it + 1 << " iterations";
      out.reason = why.str();
      break;
    }
    const double mu = gap / n;
    const Eigen::LLT<Eigen::MatrixXd> chol_z(Z), chol_x(X);
    if (chol_z.info() != Eigen::Success || chol_x.info() != Eigen::Success) {
      out.reason = "interior point lost positive definiteness at iteration " + std::to_string(it);
      break;
    }
    const Eigen::MatrixXd W = chol_z.solve(Eigen::MatrixXd::Identity(n, n));  // Z⁻¹
    const Eigen::LLT<Eigen::MatrixXd> chol_m(schur_complement(X, W, entries));
    if (chol_m.info() != Eigen::Success) {
      out.reason = "Schur complement not positive definite at iteration " + std::to_string(it);
      break;
    }
    // Predictor (σ = 0): T = −X, rhs = A(X) = b.
    const Eigen::VectorXd dy_aff = chol_m.solve(b);
    const Eigen::MatrixXd dz_aff = -lambda_from_y(dy_aff, entries, n, d);  // ΔZ = −Aᵀ(Δy), stacked blocks
    const Eigen::MatrixXd x_dz_aff = times_block_diagonal(X, dz_aff, d);    // X ΔZ, n × n
    Eigen::MatrixXd dx_aff = -X - x_dz_aff * W;
    dx_aff = 0.5 * (dx_aff + dx_aff.transpose()).eval();
    const Eigen::MatrixXd dz_aff_full = certificate_matrix(Eigen::MatrixXd::Zero(n, n), -dz_aff, d);
    const double ap_aff = step_length(X, chol_x, dx_aff, 1.0), ad_aff = step_length(Z, chol_z, dz_aff_full, 1.0);
    const double mu_aff = (X + ap_aff * dx_aff).cwiseProduct(Z + ad_aff * dz_aff_full).sum() / n;
    const double sigma = std::clamp(std::pow(mu_aff / mu, 3.0), 0.0, 1.0);
    // Corrector: T = σμW − X − ΔX_a ΔZ_a W; M Δy = −A(T).
    const Eigen::MatrixXd dxa_dza = times_block_diagonal(dx_aff, dz_aff, d);  // ΔX_a ΔZ_a
    const Eigen::MatrixXd corr = dxa_dza * W;
    const Eigen::MatrixXd T = sigma * mu * W - X - corr;
    const Eigen::VectorXd dy = chol_m.solve(-apply_A(T, entries));
    const Eigen::MatrixXd dz = -lambda_from_y(dy, entries, n, d);
    Eigen::MatrixXd dx = T - times_block_diagonal(X, dz, d) * W;
    dx = 0.5 * (dx + dx.transpose()).eval();
    const Eigen::MatrixXd dz_full = certificate_matrix(Eigen::MatrixXd::Zero(n, n), -dz, d);
    const double ap = step_length(X, chol_x, dx, tau), ad = step_length(Z, chol_z, dz_full, tau);
    if (ap == 0.0 && ad == 0.0) {
      out.reason = "interior point stalled at iteration " + std::to_string(it);
      break;
    }
    X += ap * dx;
    y += ad * dy;
    lambda = lambda_from_y(y, entries, n, d);
    Z = certificate_matrix(C, lambda, d);
  }
  // Undo rounding drift: X ← D^{-1/2} X D^{-1/2}, D = blkdiag(X_ii), so every block is I again.
  for (int i = 0; i < n; i += d) {
    const Eigen::MatrixXd root = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(X.block(i, i, d, d)).operatorInverseSqrt();
    X.middleRows(i, d) = root * X.middleRows(i, d);
    X.middleCols(i, d) = X.middleCols(i, d) * root;
  }
  if (!out.converged && out.reason.empty())
    out.reason = "interior point reached " + std::to_string(options.max_ipm_iterations) + " iterations";
  out.X = X;
  out.lambda = lambda;
  return out;
}

Eigen::MatrixXd factor_psd(const Eigen::MatrixXd& X, double tol) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(X);
  const Eigen::VectorXd& w = eig.eigenvalues();  // ascending
  const double cutoff = tol * std::max(w.maxCoeff(), 0.0);
  int r = 0;
  while (r < w.size() && w[w.size() - 1 - r] > cutoff) ++r;
  Eigen::MatrixXd Y(X.rows(), r);
  for (int k = 0; k < r; ++k) Y.col(k) = eig.eigenvectors().col(w.size() - 1 - k) * std::sqrt(w[w.size() - 1 - k]);
  return Y;
}

}  // namespace fact::sdp::detail
