// Damped Riemannian Newton at fixed rank on the product of Stiefel manifolds St(d, r)^N.
//
// Cost f(Y) = tr(C Y Yᵀ), Y n × r, block Y_i (d × r) with orthonormal rows.
// With Λ(Y) = SymBlockDiag(C Y Yᵀ) and S = C − Λ(Y) (n × n):
//   Riemannian gradient   grad f = 2 S Y
//   Riemannian Hessian    Hess f[V] = Proj_Y(2 S V)
// With few tangent directions per block they are written in an orthonormal basis of each block's
// tangent space,
//   T_i = { Ω Y_i + A N_iᵀ : Ω skew d×d, A d×(r−d) },  N_i r×(r−d) with Y_i N_i = 0,
// which has t = d·r − d(d+1)/2 directions, and the Newton system (H + μI) η = −g is N·t square
// (dense_newton). When t exceeds the d(d+1)/2 normal directions per block the system is solved in
// Schur form instead, N·d(d+1)/2 square whatever r is (schur_newton).
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "internal.h"
#include "step_length.h"

namespace fact::sdp::detail {
namespace {

// Every matrix of one Newton run at fixed rank, allocated once. n = d·N rows, r columns,
// t tangent directions per block.
struct NewtonWorkspace {
  NewtonWorkspace(Eigen::Index n, int d, Eigen::Index r, int blocks, int t)
      : CY(n, r), lambda(n, d), S(n, n), SY(n, r), basis(n, r * t), Bc(n, t), SB(n, blocks * t), g(blocks * t),
        H(blocks * t, blocks * t), llt(blocks * t), eta(blocks * t), next(n, r), next_CY(n, r), Q(r, r) {}
  Eigen::MatrixXd CY;       // C Y for the current Y, n × r
  Eigen::MatrixXd lambda;   // Λ(Y) = SymBlockDiag(C Y Yᵀ), d × d blocks stacked, n × d
  Eigen::MatrixXd S;        // C − blkdiag(Λ), n × n
  Eigen::MatrixXd SY;       // S Y, n × r
  Eigen::MatrixXd basis;    // tangent basis: direction a of block i is basis.block(d·i, r·a, d, r), n × r·t
  Eigen::MatrixXd Bc;       // column c of every basis matrix: Bc(d·i + k, a) = basis(d·i + k, r·a + c), n × t
  Eigen::MatrixXd SB;       // S times the block-diagonal matrix of the Bc blocks, n × N·t
  Eigen::VectorXd g;        // gradient coefficients, N·t
  Eigen::MatrixXd H;        // Hessian in the tangent bases, N·t × N·t
  SpdSolver llt;            // factor of H + μI (its own N·t × N·t copy)
  Eigen::VectorXd eta;      // Newton step coefficients, N·t
  Eigen::MatrixXd next;     // trial factor, n × r
  Eigen::MatrixXd next_CY;  // C · next, n × r
  Eigen::MatrixXd Q;        // r × r: Y_i's rows as columns, then N_i (complement_of_rows)
};

// N_i into the columns d … r − 1 of ws.Q (r × r): an orthonormal basis of the complement of Y_i's
// d orthonormal rows (Y_i = Y.middleRows(row, d), r > d), by Gram–Schmidt of the unit vectors e_k
// against those rows and the columns kept so far, each time the e_k with the largest remainder.
// What is left of the complement has dimension c and the remainders' squared norms sum to c over
// the r − kept candidates, so the one taken has norm ≥ 1/√r; one re-orthogonalisation pass keeps
// it orthogonal to rounding. Eigen's Householder QR with the formed Q did the same 3–6 % slower at
// r = 4 and 5 (plain_noisy N = 5, 8; random_fullrank N = 6, 7; BENCHMARKS.md, session 23).
void complement_of_rows(const Eigen::MatrixXd& Y, Eigen::Index row, int d, NewtonWorkspace& ws) {
  const Eigen::Index r = Y.cols();
  auto Q = ws.Q.leftCols(r);  // columns 0 … d − 1: Y_i's rows; d … r − 1: N_i
  for (int a = 0; a < d; ++a) Q.col(a) = Y.row(row + a).transpose();
  std::vector<bool> used(static_cast<std::size_t>(r), false);
  for (Eigen::Index kept = d; kept < r; ++kept) {
    Eigen::Index best = -1;
    double best_norm = -1;
    for (Eigen::Index k = 0; k < r; ++k) {
      if (used[static_cast<std::size_t>(k)]) continue;
      const double remainder = 1.0 - Q.row(k).head(kept).squaredNorm();  // ‖e_k − Q Qᵀ e_k‖²
      if (remainder > best_norm) best_norm = remainder, best = k;
    }
    if (best < 0)  // every remainder NaN (a non-finite Y): take the first unused, keep the write in bounds
      best = std::find(used.begin(), used.end(), false) - used.begin();
    used[static_cast<std::size_t>(best)] = true;
    auto q = Q.col(kept);
    q = -Q.leftCols(kept) * Q.row(best).head(kept).transpose();
    q[best] += 1.0;
    q -= Q.leftCols(kept) * (Q.leftCols(kept).transpose() * q);
    q.normalize();
  }
}

// N_i for d = 2, r = 3 (the small real staircase's usual top level) into column 2 of ws.Q: the unit
// normal of Y_i's two orthonormal rows, their cross product; the QR it replaces cost a quarter of
// plain_noisy N = 3 and 4 (0.053 → 0.038 and 0.046 → 0.035 ms a solve; BENCHMARKS.md, session 23).
// False for a degenerate block (the product's norm, 1 for orthonormal rows, below 0.5).
bool normal_of_rows(const Eigen::MatrixXd& Y, Eigen::Index row, NewtonWorkspace& ws) {
  const Eigen::Vector3d normal = Y.row(row).transpose().head<3>().cross(Y.row(row + 1).transpose().head<3>());
  const double norm = normal.norm();
  if (!(norm > 0.5)) return false;
  for (int k = 0; k < 3; ++k) ws.Q(k, 2) = normal[k] / norm;
  return true;
}

// Orthonormal basis of the tangent space at block Y_i = Y.middleRows(row, d) into ws.basis:
// for d = 2 first Ω Y_i (Ω skew, unit Frobenius norm), then for r > d the matrices with one
// row equal to a column of N_iᵀ (N_i: r × (r − d), orthonormal, Y_i N_i = 0).
void tangent_basis(const Eigen::MatrixXd& Y, Eigen::Index row, int d, NewtonWorkspace& ws) {
  const Eigen::Index r = Y.cols();
  Eigen::Index a = 0;
  if (d == 2) {  // Ω = [[0, −1/√2], [1/√2, 0]]
    ws.basis.block(row, 0, 1, r) = -M_SQRT1_2 * Y.row(row + 1);
    ws.basis.block(row + 1, 0, 1, r) = M_SQRT1_2 * Y.row(row);
    a = 1;
  }
  if (r == d) return;
  if (!(d == 2 && r == 3 && normal_of_rows(Y, row, ws))) complement_of_rows(Y, row, d, ws);
  for (Eigen::Index k = 0; k < d; ++k)
    for (Eigen::Index b = d; b < r; ++b, ++a) {
      ws.basis.block(row, r * a, d, r).setZero();
      ws.basis.block(row + k, r * a, 1, r) = ws.Q.col(b).transpose();
    }
}

// Λ = SymBlockDiag(C Y Yᵀ) from CY = C Y (n × r) into lambda (n × d), then S = C − blkdiag(Λ)
// (n × n) and S Y = C Y − blkdiag(Λ) Y (n × r). D = d as a compile-time size: the d × d products
// are fixed-size kernels.
template <int D>
void certificate_at(const Eigen::MatrixXd& C, const Eigen::MatrixXd& Y, const Eigen::MatrixXd& CY,
                    Eigen::MatrixXd& lambda, Eigen::MatrixXd& SY, Eigen::MatrixXd& S) {
  for (Eigen::Index i = 0; i < C.rows(); i += D) {
    const auto Yi = Y.middleRows<D>(i);  // D × r
    Eigen::Matrix<double, D, D> block = CY.middleRows<D>(i) * Yi.transpose();
    block = (0.5 * (block + block.transpose())).eval();
    lambda.middleRows<D>(i) = block;
    SY.middleRows<D>(i) = CY.middleRows<D>(i);
    SY.middleRows<D>(i).noalias() -= block * Yi;
  }
  certificate_matrix(C, lambda, D, S);
}

// certificate_at for d = 1 or 2.
void certificate_at(const Eigen::MatrixXd& C, const Eigen::MatrixXd& Y, int d, const Eigen::MatrixXd& CY,
                    Eigen::MatrixXd& lambda, Eigen::MatrixXd& SY, Eigen::MatrixXd& S) {
  if (d == 1)
    certificate_at<1>(C, Y, CY, lambda, SY, S);
  else
    certificate_at<2>(C, Y, CY, lambda, SY, S);
}

// H = 2 Σ_c B_cᵀ S B_c, B_c = blkdiag over blocks of the D × t matrices Bc_i (column c of
// every basis matrix of block i): entry (i a, j b) is 2⟨B_ia, S_ij B_jb⟩. D = d as a
// compile-time size, so the products with inner dimension D are small fixed-size kernels.
template <int D>
void hessian(Eigen::Index r, int blocks, int t, NewtonWorkspace& ws) {
  ws.H.setZero();
  for (Eigen::Index c = 0; c < r; ++c) {
    for (int a = 0; a < t; ++a) ws.Bc.col(a) = ws.basis.col(r * a + c);
    for (int j = 0; j < blocks; ++j)
      ws.SB.middleCols(j * t, t).noalias() = ws.S.middleCols<D>(j * D) * ws.Bc.middleRows<D>(j * D);
    for (int i = 0; i < blocks; ++i)
      ws.H.middleRows(i * t, t).noalias() += ws.Bc.middleRows<D>(i * D).transpose() * ws.SB.middleRows<D>(i * D);
  }
  ws.H *= 2.0;
  symmetrize(ws.H);
}

// Rows row … row + d − 1 of Y replaced by their nearest orthonormal rows (polar factor);
// the d = 2 case in closed form (as polar_rows), the rank-deficient case through polar_rows.
void retract_rows(Eigen::MatrixXd& Y, Eigen::Index row, int d) {
  auto G = Y.middleRows(row, d);
  if (d == 1) {
    const double norm = G.norm();
    if (norm > 0) G /= norm;
    return;
  }
  const double m00 = G.row(0).squaredNorm(), m11 = G.row(1).squaredNorm(), m01 = G.row(0).dot(G.row(1));
  double i00, i01, i11;  // (G Gᵀ)^{-1/2}, or the SVD in polar_rows when the closed form is not trusted
  if (!polar_closed_form(m00, m01, m11, i00, i01, i11)) {
    const Eigen::MatrixXd polar = polar_rows(G);
    if (polar.size() > 0) G = polar;
    return;
  }
  for (Eigen::Index k = 0; k < G.cols(); ++k) {
    const double x = G(0, k), y = G(1, k);
    G(0, k) = i00 * x + i01 * y;
    G(1, k) = i01 * x + i11 * y;
  }
}

// ws.next = retraction of Y + Σ η_ia B_ia, block by block; returns ⟨C, next nextᵀ⟩ (ws.next_CY = C next).
double trial_step(const Eigen::MatrixXd& C, const Eigen::MatrixXd& Y, int d, int blocks, int t, NewtonWorkspace& ws) {
  const Eigen::Index r = Y.cols();
  ws.next = Y;
  for (int i = 0; i < blocks; ++i) {
    for (int a = 0; a < t; ++a) ws.next.middleRows(i * d, d) += ws.eta[i * t + a] * ws.basis.block(i * d, r * a, d, r);
    retract_rows(ws.next, i * d, d);
  }
  ws.next_CY.noalias() = C * ws.next;
  return ws.next.cwiseProduct(ws.next_CY).sum();
}

// Damped Newton with the Hessian formed in the tangent bases (N·t × N·t).
int dense_newton(const Eigen::MatrixXd& C, int d, Eigen::MatrixXd& Y, int max_iterations, double grad_tol,
                 CrawlWatch crawl) {
  const Eigen::Index n = C.rows(), r = Y.cols();
  const int blocks = static_cast<int>(n / d), t = static_cast<int>(d * r - d * (d + 1) / 2);
  NewtonWorkspace ws(n, d, r, blocks, t);
  double mu = 1e-8;  // Levenberg–Marquardt damping on the Newton system
  ws.CY.noalias() = C * Y;
  double f = Y.cwiseProduct(ws.CY).sum();  // ⟨C, Y Yᵀ⟩
  const double noise = 100.0 * static_cast<double>(n) * std::numeric_limits<double>::epsilon() * C.norm();
  int it = 0;
  for (; it < max_iterations; ++it) {
    certificate_at(C, Y, d, ws.CY, ws.lambda, ws.SY, ws.S);
    for (int i = 0; i < blocks; ++i) tangent_basis(Y, i * d, d, ws);
    for (int i = 0; i < blocks; ++i)  // gradient coefficients 2⟨B_ia, (S Y)_i⟩
      for (int a = 0; a < t; ++a)
        ws.g[i * t + a] = 2.0 * ws.basis.block(i * d, r * a, d, r).cwiseProduct(ws.SY.middleRows(i * d, d)).sum();
    if (ws.g.norm() < grad_tol || crawl.crawls(it, f, ws.g.norm())) break;
    if (d == 1)
      hessian<1>(r, blocks, t, ws);
    else
      hessian<2>(r, blocks, t, ws);
    const double f_next = damped_newton_step(ws.H, ws.llt, ws.g, ws.eta, mu, f, noise,
                                             [&](const Eigen::VectorXd&) { return trial_step(C, Y, d, blocks, t, ws); });
    if (std::isnan(f_next)) break;
    Y.swap(ws.next);
    ws.CY.swap(ws.next_CY);
    f = f_next;
  }
  return it;
}

// Every matrix of one Newton run in Schur form, allocated once. n rows, r columns, m = N·d(d+1)/2
// block constraints.
struct SchurWorkspace {
  SchurWorkspace(Eigen::Index n, int d, Eigen::Index r, int m)
      : CY(n, r), lambda(n, d), S(n, n), X(n, n), SY(n, r), W(n, n), WSY(n, r),
        M(m, m), llt(m), rhs(m), nu(m), normal(n, d), pushed(n, r), next(n, r), next_CY(n, r) {}
  Eigen::MatrixXd CY;        // C Y, n × r
  Eigen::MatrixXd lambda;    // Λ(Y) = SymBlockDiag(C Y Yᵀ), d × d blocks stacked, n × d
  Eigen::MatrixXd S;         // C − blkdiag(Λ), n × n
  Eigen::MatrixXd X;         // Y Yᵀ, n × n
  Eigen::MatrixXd SY;        // S Y, n × r
  // Above kSweepInverseMaxSize rows (sized when first used):
  Eigen::MatrixXd shifted;   // S + λI, n × n (its lower triangle is factored)
  Eigen::MatrixXd L, L_inv;  // S + λI = L Lᵀ (lower triangle) and L⁻¹ (zeros above), n × n
  Eigen::MatrixXd W;         // (S + λI)⁻¹, n × n
  Eigen::MatrixXd WSY;       // W S Y, n × r
  Eigen::MatrixXd M;         // Schur complement tr(A_p X A_q W), m × m
  SpdSolver llt;             // its factor
  Eigen::VectorXd rhs, nu;   // Schur right-hand side and the multipliers ν of the step (m)
  Eigen::MatrixXd normal;    // blkdiag(Ν) from ν, d × d blocks stacked, n × d
  Eigen::MatrixXd pushed;    // S Y + blkdiag(Ν) Y, n × r (the step is V = −W · it)
  Eigen::MatrixXd next, next_CY;  // trial factor and C · it, n × r
};

// One damped Newton trial in Schur form at shift λ, into ws.next (rows retracted). The damped
// system Proj(S V) + λV = −S Y (the dense one's (H + μI) η = −g with μ = 2λ) over tangent V is
//     (S + λI) V + blkdiag(Ν) Y = −S Y,   sym(Y_i V_iᵀ) = 0 for every block i,
// Ν_i symmetric d × d, the multipliers of the tangency constraints (ν, one per constraint entry).
// With W = (S + λI)⁻¹ (needs S + λI ≻ 0), V = −W (S Y + blkdiag(Ν) Y), and the constraints give
//     M ν = −A((W S Y) Yᵀ),   M_pq = tr(A_p X A_q W),  X = Y Yᵀ,
// (A(P)_p = ⟨A_p, P⟩ needs only P's block diagonal). Every term is of the order of S Y, the
// gradient, so the step keeps its digits near the optimum, where W grows as 1/λ (the equivalent
// Y + V = W blkdiag(λI − Ν) Y cancels terms of order 1 there and lost 4 of the step's digits at
// λ = 5e-9). M is the interior point's Schur complement for X and W, positive definite when
// S + λI is (X_ii = I); its factorisation fails only by rounding. Cost: one n × n inversion (up to
// kSweepInverseMaxSize rows by inverse_by_sweeps, above by Cholesky, L⁻¹ and L⁻ᵀ L⁻¹; the sweeps
// took random full rank N = 6 / 8 / 12 to 0.96 / 0.99 / 1.00 of the time, BENCHMARKS.md, session
// 51) and product, and an m × m factorisation, whatever r is. False when S + λI or M does not
// factor (no trial formed).
bool schur_trial(const Eigen::MatrixXd& Y, int d, double lambda, const std::vector<Entry>& entries,
                       SchurWorkspace& ws) {
  const Eigen::Index n = Y.rows();
  if (n <= kSweepInverseMaxSize) {
    if (!inverse_by_sweeps(ws.S, lambda, ws.W)) return false;
  } else {
    ws.shifted = ws.S;
    ws.shifted.diagonal().array() += lambda;
    if (n <= kGridStepMaxSize) {
      ws.L.resize(n, n);  // (no allocation after the first trial)
      if (!cholesky_lower(ws.shifted, ws.L)) return false;
    } else {
      ws.L.swap(ws.shifted);
      if (!cholesky_in_place(ws.L)) return false;
    }
    invert_lower_factor(ws.L, ws.L_inv);
    gram_of_lower_factor(ws.L_inv, ws.W);  // L⁻ᵀ L⁻¹
  }
  schur_complement(ws.X, ws.W, entries, ws.M);
  if (!ws.llt.factor(ws.M)) return false;
  ws.WSY.noalias() = ws.W * ws.SY;
  for (std::size_t p = 0; p < entries.size(); ++p) {  // −A((W S Y) Yᵀ)
    const auto [u, v] = entries[p];
    const double entry = u == v ? ws.WSY.row(u).dot(Y.row(u)) : ws.WSY.row(u).dot(Y.row(v)) + ws.WSY.row(v).dot(Y.row(u));
    ws.rhs[static_cast<Eigen::Index>(p)] = -entry;
  }
  ws.llt.solve(ws.rhs, ws.nu);
  lambda_from_y(ws.nu, entries, d, ws.normal);
  ws.pushed = ws.SY;  // S Y + blkdiag(Ν) Y
  for (Eigen::Index i = 0; i < n; i += d) ws.pushed.middleRows(i, d).noalias() += ws.normal.middleRows(i, d) * Y.middleRows(i, d);
  ws.next = Y;
  ws.next.noalias() -= ws.W * ws.pushed;  // Y + V
  for (Eigen::Index i = 0; i < n; i += d) retract_rows(ws.next, i, d);
  return true;
}

// Damped Newton in Schur form (schur_trial), with the dense path's damping rule: λ raised 10×
// while S + λI is not positive definite, M does not factor or the trial raises f by more than
// rounding, lowered 10× after an accepted step.
int schur_newton(const Eigen::MatrixXd& C, int d, Eigen::MatrixXd& Y, int max_iterations, double grad_tol,
                 CrawlWatch crawl) {
  const Eigen::Index n = C.rows(), r = Y.cols();
  const std::vector<Entry> entries = constraint_entries(static_cast<int>(n), d);
  SchurWorkspace ws(n, d, r, static_cast<int>(entries.size()));
  ws.CY.noalias() = C * Y;
  double f = Y.cwiseProduct(ws.CY).sum();  // ⟨C, Y Yᵀ⟩
  const double noise = 100.0 * static_cast<double>(n) * std::numeric_limits<double>::epsilon() * C.norm();
  double lambda = 0.5e-8;  // the dense path's first μ = 1e-8
  int it = 0;
  for (; it < max_iterations; ++it) {
    certificate_at(C, Y, d, ws.CY, ws.lambda, ws.SY, ws.S);
    const double grad_norm = 2.0 * ws.SY.norm();  // ‖grad f‖ = ‖2 S Y‖ (S Y is tangent)
    if (grad_norm < grad_tol || crawl.crawls(it, f, grad_norm)) break;
    ws.X.noalias() = Y * Y.transpose();
    bool accepted = false;
    for (int tries = 0; tries < 12 && !accepted; ++tries, lambda *= 10) {
      if (!schur_trial(Y, d, lambda, entries, ws)) continue;
      ws.next_CY.noalias() = C * ws.next;
      const double f_next = ws.next.cwiseProduct(ws.next_CY).sum();
      if (!(f_next <= f + noise)) continue;
      Y.swap(ws.next);
      ws.CY.swap(ws.next_CY);
      f = f_next;
      lambda = std::max(0.5e-12, lambda / 100);  // 10× below the accepted λ after the loop's ×10
      accepted = true;
    }
    if (!accepted) break;
  }
  return it;
}

}  // namespace

int newton_refine(const Eigen::MatrixXd& C, int d, Eigen::MatrixXd& Y, int max_iterations, double grad_tol,
                  NewtonSystem system, double crawl_decrease) {
  const int t = static_cast<int>(d * Y.cols() - d * (d + 1) / 2);  // tangent directions per block
  if (t <= 0) return 0;
  if (system == NewtonSystem::automatic)
    system = t > d * (d + 1) / 2 ? NewtonSystem::schur : NewtonSystem::tangent_basis;
  const CrawlWatch crawl(crawl_decrease);
  if (system == NewtonSystem::schur) return schur_newton(C, d, Y, max_iterations, grad_tol, crawl);
  return dense_newton(C, d, Y, max_iterations, grad_tol, crawl);
}

}  // namespace fact::sdp::detail
