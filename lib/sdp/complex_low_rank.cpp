// The tight complex (U(1)) form solved in complex arithmetic: Burer–Monteiro staircase with a
// damped Riemannian Newton step on a product of unit spheres in ℂ^p.
//
// A d = 2 cost C (2N × 2N) whose every 2×2 block is [[a, −b], [b, a]] is the real embedding of
// the Hermitian N × N matrix H with H_ij = a + i·b (C = complex_form(Q) always is). The d = 2
// problem on C then has a K-invariant optimum X = emb(Z), Z ⪰ 0 Hermitian with unit diagonal,
// and ⟨C, emb(Z)⟩ = 2 tr(H Z). With Z = Y Yᴴ, Y N × p complex with unit rows:
//   cost           f(Y) = tr(Yᴴ H Y)
//   multipliers    μ_i = Re (H Y)_i y_iᴴ               (Λ_ii = μ_i I₂ in the d = 2 problem)
//   certificate    S = H − diag(μ), N × N Hermitian      (the d = 2 one is emb(S))
//   gradient       grad f = 2 S Y (row by row tangent to the sphere)
//   Hessian        Hess f[V] = Proj_Y(2 S V)
// Row i's tangent space is {w ∈ ℂ^p : Re w y_iᴴ = 0} (real dimension 2p − 1). At rank 1 it is
// spanned by i·y_i and the Newton system is N × N real (rank_one_newton); above rank 1 the system
// is solved in Schur form through (S + λI)⁻¹ (schur_complex_newton), O(N³) whatever p is.
#include <algorithm>
#include <cmath>
#include <limits>

#include "internal.h"
#include "step_length.h"

namespace fact::sdp::detail {
namespace {

using Eigen::MatrixXcd;
using Eigen::MatrixXd;
using Eigen::VectorXd;
constexpr std::complex<double> kI{0.0, 1.0};
constexpr int kMaxNewColumns = 2;  // columns one staircase escape adds at most

// f(Z) = tr(Zᴴ H Z) with ZH = H Z.
double cost_of(const MatrixXcd& Z, const MatrixXcd& ZH) { return (ZH.array() * Z.array().conjugate()).real().sum(); }

// μ at Y (N): complex_multipliers of H Y, by times_thin.
VectorXd multipliers_at(const MatrixXcd& H, const MatrixXcd& Y) {
  MatrixXcd HY;  // H Y, N × p
  times_thin(H, Y, HY);
  VectorXd mu;
  complex_multipliers(HY, Y, mu);
  return mu;
}

// The certificate matrix S = H − diag(μ) into S (N × N).
void certificate_matrix(const MatrixXcd& H, const VectorXd& mu, MatrixXcd& S) {
  S = H;
  S.diagonal() -= mu.cast<std::complex<double>>();
}

// Every matrix of one rank-1 Newton run, allocated once. Y = z ∈ ℂᴺ (N × 1) with |z_i| = 1, and
// row i's one tangent direction is b_i = i·z_i.
struct RankOneWorkspace {
  explicit RankOneWorkspace(Eigen::Index N)
      : HY(N, 1), SY(N, 1), next(N, 1), next_HY(N, 1), mu(N), S(N, N), Hm(N, N), llt(N), g(N), eta(N) {}
  MatrixXcd HY, SY;          // H z and S z = H z − diag(μ) z, N × 1
  MatrixXcd next, next_HY;   // trial z and H · it, N × 1
  VectorXd mu;               // μ_i = Re((H z)_i conj(z_i)), N
  MatrixXcd S;               // H − diag(μ), N × N
  MatrixXd Hm;               // Hessian 2 Re(S_ij conj(b_i) b_j), N × N (the lower triangle is read)
  SpdSolver llt;             // factor of Hm + damping·I
  VectorXd g;                // gradient coefficients 2 Re(conj(b_i) (S z)_i), N
  VectorXd eta;              // Newton step coefficients, N
};

// μ, S, S z, the gradient and the Hessian at z (ws.HY = H z already).
void rank_one_system(const MatrixXcd& H, const MatrixXcd& Y, RankOneWorkspace& ws) {
  const Eigen::Index N = Y.rows();
  complex_multipliers(ws.HY, Y, ws.mu);
  certificate_matrix(H, ws.mu, ws.S);
  ws.SY = ws.HY - ws.mu.asDiagonal() * Y;
  for (Eigen::Index i = 0; i < N; ++i) ws.g[i] = 2.0 * (std::conj(kI * Y(i, 0)) * ws.SY(i, 0)).real();
  for (Eigen::Index j = 0; j < N; ++j) {
    const std::complex<double> bj = 2.0 * kI * Y(j, 0);
    for (Eigen::Index i = j; i < N; ++i) ws.Hm(i, j) = (ws.S(i, j) * std::conj(kI * Y(i, 0)) * bj).real();
  }
}

// ws.next = z with row i moved by η_i b_i and normalised; returns f(next) (ws.next_HY = H next).
double rank_one_trial(const MatrixXcd& H, const MatrixXcd& Y, RankOneWorkspace& ws) {
  for (Eigen::Index i = 0; i < Y.rows(); ++i) {
    const std::complex<double> moved = Y(i, 0) + ws.eta[i] * (kI * Y(i, 0));
    ws.next(i, 0) = moved / std::sqrt(std::norm(moved));
  }
  times_thin(H, ws.next, ws.next_HY);
  return cost_of(ws.next, ws.next_HY);
}

// Above rank 1, a step that lowered f by more than kExtendDecrease of |f| is tried longer
// (extend_schur_step): on the flat, indefinite stretch after a staircase escape the damped step is
// short and a longer one gains (tight_noisy N = 5: 28 → 19 steps with the dense Hessian,
// BENCHMARKS.md, session 13; N = 6 in Schur form: 30 → 22, session 16); near the optimum the
// decrease is below kExtendDecrease and nothing is tried.
constexpr double kExtendDecrease = 1e-3;

}  // namespace

void complex_multipliers(const Eigen::MatrixXcd& HY, const Eigen::MatrixXcd& Y, Eigen::VectorXd& mu) {
  mu = (HY.array() * Y.array().conjugate()).real().rowwise().sum();
}

// Messages by printed (vsnprintf) only on a mismatch: an std::ostringstream built on every call
// cost 1 % of a tight N = 5 solve.
std::pair<Eigen::Index, Eigen::Index> first_non_complex_block(const Eigen::MatrixXd& M) {
  for (Eigen::Index j = 0; j < M.cols(); j += 2)
    for (Eigen::Index i = 0; i < M.rows(); i += 2)
      if (M(i, j) != M(i + 1, j + 1) || M(i, j + 1) != -M(i + 1, j)) return {i, j};
  return {-1, -1};
}

std::string complex_embedding_mismatch(const Eigen::MatrixXd& C) {
  if (C.rows() != C.cols() || C.rows() % 2 != 0)
    return printed("C is %ld×%ld: not 2N × 2N", static_cast<long>(C.rows()), static_cast<long>(C.cols()));
  const auto [i, j] = first_non_complex_block(C);
  if (i < 0) return "";
  const char* what = ": not the real embedding of a Hermitian matrix (every 2×2 block [[a, −b], [b, a]])";
  const long a = static_cast<long>(i), b = static_cast<long>(j);
  if (C(i, j) != C(i + 1, j + 1))
    return printed("C(%ld,%ld) = %g but C(%ld,%ld) = %g%s", a, b, C(i, j), a + 1, b + 1, C(i + 1, j + 1), what);
  return printed("C(%ld,%ld) = %g but C(%ld,%ld) = %g%s", a, b + 1, C(i, j + 1), a + 1, b, C(i + 1, j), what);
}

Eigen::MatrixXcd hermitian_of(const Eigen::MatrixXd& C) {
  const Eigen::Index N = C.rows() / 2;
  MatrixXcd H(N, N);  // H_ij = C(2i, 2j) + i·C(2i+1, 2j), N × N
  for (Eigen::Index j = 0; j < N; ++j)
    for (Eigen::Index i = 0; i < N; ++i) H(i, j) = {C(2 * i, 2 * j), C(2 * i + 1, 2 * j)};
  return H;
}

namespace {

// Damped Newton at rank 1, the N × N real system factored densely (cheaper than the Schur form
// there).
int rank_one_newton(const Eigen::MatrixXcd& H, Eigen::MatrixXcd& Y, int max_iterations, double grad_tol) {
  const Eigen::Index N = H.rows();
  RankOneWorkspace ws(N);
  double damping = 1e-8;  // Levenberg–Marquardt shift of the Newton system
  times_thin(H, Y, ws.HY);
  double f = cost_of(Y, ws.HY);  // tr(Yᴴ H Y)
  const double noise = 100.0 * static_cast<double>(N) * std::numeric_limits<double>::epsilon() * H.norm();
  int it = 0;
  for (; it < max_iterations; ++it) {
    rank_one_system(H, Y, ws);
    const double grad_norm = ws.g.norm();
    if (grad_norm < grad_tol) break;
    // The first damping: the decade at or below ‖grad‖, at most 1, where that is above 1e-8. From
    // the spectral start the Hessian is indefinite and the ladder from 1e-8 failed up to about
    // ‖grad‖ (tight_noisy N = 6 / 12: 8 / 9 factorisations for the first step, accepted at 0.1 / 1
    // with ‖grad‖ = 0.12 / 0.49); the step accepted is the same unless a damping below that decade
    // would have been. Every rank-1 run starts so (the polish of a rank-1 factor and the single
    // step after a gap miss too); near the optimum ‖grad‖ is below 1e-7 and the damping stays 1e-8,
    // and a damping of the order of ‖grad‖ keeps the step's convergence quadratic.
    if (it == 0)
      while (damping < 1.0 && damping * 10 <= grad_norm) damping *= 10;
    const double f_next = damped_newton_step(ws.Hm, ws.llt, ws.g, ws.eta, damping, f, noise,
                                             [&](const VectorXd&) { return rank_one_trial(H, Y, ws); });
    if (std::isnan(f_next)) break;
    Y.swap(ws.next);
    ws.HY.swap(ws.next_HY);
    f = f_next;
  }
  return it;
}

// Every matrix of one Schur-form Newton run, allocated once (N × N complex unless noted).
struct SchurWorkspace {
  SchurWorkspace(Eigen::Index N, Eigen::Index p)
      : HY(N, p), WY(N, p), scaled(N, p), next(N, p), next_HY(N, p), longer(N, p), longer_HY(N, p), S(N, N),
        W(N, N), X(N, N), M(N, N), llt(N), mu(N), r(N), nu(N) {}
  MatrixXcd HY;              // H Y, N × p
  MatrixXcd WY;              // W Y, N × p
  MatrixXcd scaled;          // diag(λ − ν) Y, N × p
  MatrixXcd next, next_HY;   // trial factor and H · it, N × p
  MatrixXcd longer, longer_HY;  // a longer trial along the same step and H · it, N × p
  MatrixXcd S;               // H − diag(μ)
  MatrixXcd L, L_inv;        // S + λI = L Lᴴ (lower triangle) and L⁻¹: sized when first used (above
                             // kSweepInverseMaxSize rows)
  MatrixXcd W;               // (S + λI)⁻¹
  MatrixXcd X;               // Y Yᴴ
  MatrixXd M;                // Schur complement Re(W_ij conj(X_ij)), N × N real
  SpdSolver llt;             // its factor
  VectorXd mu, r, nu;        // multipliers, Schur right-hand side, row multipliers of the step (N)
};

}  // namespace

// (column j is Σ_k conj(y_jk) y_k, by whole-column axpys: N = 6 / 12 / 24 at p = 2 took 38 / 135 /
// 504 ns by sums over the lower triangle, mirrored, against 26 / 59 / 171 ns; BENCHMARKS.md,
// session 49)
void factor_gram(const MatrixXcd& Y, MatrixXcd& X) {
  const Eigen::Index N = Y.rows(), p = Y.cols();
  X.resize(N, N);
  if (p == 0) X.setZero();
  for (Eigen::Index j = 0; j < N; ++j) {
    std::complex<double>* __restrict x = &X(0, j);
    for (Eigen::Index k = 0; k < p; ++k) {
      const std::complex<double> weight = std::conj(Y(j, k));
      const std::complex<double>* __restrict y = &Y(0, k);
      if (k == 0)
        for (Eigen::Index i = 0; i < N; ++i) x[i] = y[i] * weight;
      else
        for (Eigen::Index i = 0; i < N; ++i) x[i] += y[i] * weight;
    }
  }
}

EIGEN_DONT_INLINE void times_thin(const MatrixXcd& A, const MatrixXcd& B, MatrixXcd& C) { C.noalias() = A.lazyProduct(B); }

constexpr int kMaxPowerSteps = 30;             // bottom_vector_by_inverse's steps at most
constexpr Eigen::Index kSquaredPowerMaxSize = 8;  // up to which it iterates on W² instead of W

Eigen::MatrixXcd bottom_vector_by_inverse(const Eigen::MatrixXcd& H) {
  const Eigen::Index N = H.rows();
  MatrixXcd W;  // (H + δI)⁻¹, N × N
  if (!shifted_inverse(H, W)) return MatrixXcd();
  if (N <= kSquaredPowerMaxSize) {  // W² (its product costs less than the steps it saves there)
    MatrixXcd squared;  // N × N
    times_thin(W, W, squared);
    W.swap(squared);
  }
  MatrixXcd v(N, 1), w(N, 1);  // iterates
  for (Eigen::Index i = 0; i < N; ++i) v(i, 0) = generic_start_entry(i, 0);
  v.normalize();
  for (int step = 0; step < kMaxPowerSteps; ++step) {
    times_thin(W, v, w);
    w.normalize();
    const double agreement = std::abs(w.col(0).dot(v.col(0)));
    v.swap(w);
    if (agreement > 1 - 1e-14) break;
  }
  return v;
}

double skipped_shift(double lambda, double carried_failure, double grad_norm, double shift_per_gradient) {
  const bool skip = shift_per_gradient == 0 && lambda <= carried_failure && grad_norm > 10 * carried_failure;
  return skip ? carried_failure : 0.0;
}

namespace {

// One Levenberg–Marquardt-damped Newton system at shift λ in Schur form, without forming the
// N·t × N·t Hessian. The damped system (Hess + 2λ) V = −grad is
//     (S + λI) V + diag(ν) Y = −S Y,   Re⟨y_i, v_i⟩ = 0 for every row i,
// ν ∈ ℝᴺ the multipliers of the tangency constraints. With W = (S + λI)⁻¹ (needs S + λI ≻ 0) and
// W S Y = Y − λ W Y, the constraints give M ν = −r, M_ij = Re(W_ij conj(X_ij)) with X = Y Yᴴ
// (positive definite: the interior point's Schur complement), r_i = 1 − λ Re⟨y_i, (W Y)_i⟩, and
// then Y + V = W diag(λ − ν) Y. ws.next gets its rows normalised (the retraction). Cost: one
// N × N complex inversion (up to kSweepInverseMaxSize rows by inverse_by_sweeps's sweeps,
// above by Cholesky, L⁻¹ and L⁻ᴴ L⁻¹; the sweeps took tight_noisy N = 6 / 12 from 18.0 / 47.5 to
// 16.3 / 41.7 µs, BENCHMARKS.md, session 51) and an N × N real factorisation, whatever p is. M is
// positive definite in exact arithmetic whenever S + λI is (Schur product theorem); its
// factorisation fails only by rounding.
enum class Trial { formed, shift_too_small, schur_not_definite };
Trial schur_newton_trial(const MatrixXcd& Y, double lambda, SchurWorkspace& ws) {
  const Eigen::Index N = Y.rows();
  if (N <= kSweepInverseMaxSize) {
    if (!inverse_by_sweeps(ws.S, lambda, ws.W)) return Trial::shift_too_small;
  } else {
    ws.L = ws.S;
    ws.L.diagonal().array() += lambda;
    if (!cholesky_in_place(ws.L)) return Trial::shift_too_small;
    invert_lower_factor(ws.L, ws.L_inv);
    gram_of_lower_factor(ws.L_inv, ws.W);  // L⁻ᴴ L⁻¹
  }
  ws.M = (ws.W.array() * ws.X.array().conjugate()).real();
  if (!ws.llt.factor(ws.M)) return Trial::schur_not_definite;
  times_thin(ws.W, Y, ws.WY);
  ws.r = VectorXd::Ones(N) - lambda * (Y.array().conjugate() * ws.WY.array()).real().rowwise().sum().matrix();
  ws.llt.solve(ws.r, ws.nu);                // −ν = M⁻¹ r
  ws.nu = lambda + ws.nu.array();            // λ − ν
  ws.scaled.noalias() = ws.nu.asDiagonal() * Y;
  times_thin(ws.W, ws.scaled, ws.next);
  ws.next.rowwise().normalize();
  return Trial::formed;
}

// After an accepted step that lowered f by more than kExtendDecrease of |f| (the flat, indefinite
// stretch after a staircase escape), steps of 2 and 4 times its length along V = next − Y, kept
// while they lower f further; returns the f of the one kept (in ws.next, ws.next_HY).
double extend_schur_step(const MatrixXcd& H, const MatrixXcd& Y, double f, double f_next, SchurWorkspace& ws) {
  if (!(f - f_next > kExtendDecrease * std::abs(f))) return f_next;
  for (double factor = 2.0; factor <= 4.0; factor *= 2.0) {
    ws.longer = Y + factor * (ws.next - Y);
    ws.longer.rowwise().normalize();
    times_thin(H, ws.longer, ws.longer_HY);
    const double f_longer = cost_of(ws.longer, ws.longer_HY);
    if (!(f_longer < f_next)) break;
    f_next = f_longer;
    ws.next.swap(ws.longer);
    ws.next_HY.swap(ws.longer_HY);
  }
  return f_next;
}

// Newton in Schur form (schur_newton_trial) for p ≥ 2, with the dense path's damping rule: λ
// raised 10× while S + λI is not positive definite or the trial raises f, lowered 10× after a
// step. With saddle_exit it returns early once S has an eigenvalue below −λ (a Cholesky failed
// at that shift) while ‖grad‖ < λ: the negative curvature then dominates, the point is near a
// saddle of the SDP at this rank, and converging to it only costs steps (the staircase escapes
// instead; tight_noisy N = 12: 25 of 39 steps were spent there). With shift_per_gradient > 0, from
// the second step on λ is also kept at most shift_per_gradient·‖grad‖ (complex_newton).
int schur_complex_newton(const MatrixXcd& H, MatrixXcd& Y, int max_iterations, double grad_tol, bool saddle_exit,
                         double curvature, double shift_per_gradient) {
  const Eigen::Index N = H.rows();
  SchurWorkspace ws(N, Y.cols());
  times_thin(H, Y, ws.HY);
  double f = cost_of(Y, ws.HY);
  double carried_failure = 0;  // the largest shift whose Cholesky failed (or was skipped) last step
  double lambda = 1e-8;  // the first shift tried: the decade at or below |curvature|/10, at most 1
  while (lambda < 1.0 && lambda * 10 <= 0.1 * std::abs(curvature)) lambda *= 10;  // (NaN: 1e-8)
  const double noise = 100.0 * static_cast<double>(N) * std::numeric_limits<double>::epsilon() * H.norm();
  int it = 0;
  for (; it < max_iterations; ++it) {
    complex_multipliers(ws.HY, Y, ws.mu);
    const double grad_norm = 2.0 * (ws.HY - ws.mu.asDiagonal() * Y).norm();  // ‖2 S Y‖
    if (grad_norm < grad_tol) break;
    if (shift_per_gradient > 0 && it > 0) lambda = std::max(1e-13, std::min(lambda, shift_per_gradient * grad_norm));
    certificate_matrix(H, ws.mu, ws.S);
    factor_gram(Y, ws.X);
    double failed_shift = 0;  // the largest shift whose Cholesky failed this step: λ_min(S) < −failed_shift
    const double skipped = skipped_shift(lambda, carried_failure, grad_norm, shift_per_gradient);
    if (skipped > 0) lambda = 10 * skipped;
    bool accepted = false;
    for (int tries = 0; tries < 14 && !accepted; ++tries, lambda *= 10) {
      const Trial trial = schur_newton_trial(Y, lambda, ws);
      if (trial == Trial::shift_too_small) failed_shift = lambda;
      if (trial != Trial::formed) continue;
      if (saddle_exit && grad_norm < failed_shift) return it;
      times_thin(H, ws.next, ws.next_HY);
      const double f_next = cost_of(ws.next, ws.next_HY);
      if (!(f_next <= f + noise)) continue;
      f = extend_schur_step(H, Y, f, f_next, ws);
      Y.swap(ws.next);
      ws.HY.swap(ws.next_HY);
      lambda = std::max(1e-13, lambda / 100);  // 10× below the accepted λ after the loop's ×10
      accepted = true;
    }
    if (!accepted) break;
    carried_failure = std::max(failed_shift, skipped);
  }
  return it;
}

}  // namespace

int complex_newton(const Eigen::MatrixXcd& H, Eigen::MatrixXcd& Y, int max_iterations, double grad_tol, bool saddle_exit,
                   double curvature, double shift_per_gradient) {
  if (Y.cols() == 1) return rank_one_newton(H, Y, max_iterations, grad_tol);
  return schur_complex_newton(H, Y, max_iterations, grad_tol, saddle_exit, curvature, shift_per_gradient);
}

namespace {

// From kPowerStartMinSize to kPowerStartMaxSize rows the spectral start's eigenvector comes from
// bottom_vector_by_inverse. Below, and where H + δI does not factor, from the tridiagonal
// reduction (bottom_eigenvectors with full_up_to = kPowerStartMaxSize); above, from
// bottom_eigenvectors' subspace inverse iteration.
constexpr Eigen::Index kPowerStartMinSize = 4;
constexpr Eigen::Index kPowerStartMaxSize = 32;

// The spectral start: H's bottom eigenvector (bottom_vector_by_inverse from N = 4 to 32;
// bottom_eigenvectors otherwise, and where H + δI does not factor) with every entry normalised to
// |z_i| = 1 (an entry at zero set to 1), N × 1. Exact on noise-free data, up to the power
// iteration's angle (H from the scaled problem, ‖C‖_F = 1, so that its shift δ is small against
// λ₂; see bottom_vector_by_inverse).
Eigen::MatrixXcd spectral_start(const MatrixXcd& H) {
  const Eigen::Index N = H.rows();
  MatrixXcd Y;  // N × 1
  if (N >= kPowerStartMinSize && N <= kPowerStartMaxSize) Y = bottom_vector_by_inverse(H);
  if (Y.size() == 0) Y = bottom_eigenvectors(H, 1, kPowerStartMaxSize);
  for (Eigen::Index i = 0; i < Y.rows(); ++i) Y(i, 0) = std::abs(Y(i, 0)) > 0 ? Y(i, 0) / std::abs(Y(i, 0)) : 1.0;
  return Y;
}

// [Y, α√N V] with rows normalised (V: unit eigenvectors, N × k), for the α in 1, ½, … 2⁻⁹
// of least cost. Row i of the candidate is s_i [y_i, α√N v_i] with s_i = 1/√(|y_i|² + α²N|v_i|²),
// so its cost is sᵀ (A + α²N B) s with A = Re(H ∘ conj(Y Yᴴ)) and B = Re(H ∘ conj(V Vᴴ)) (N × N
// real, formed once): O(N²) a candidate instead of a product with H and a new factor each (6 % of
// tight_noisy N = 5; BENCHMARKS.md, session 40).
Eigen::MatrixXcd escape(const MatrixXcd& H, const MatrixXcd& Y, const MatrixXcd& v) {
  const Eigen::Index N = Y.rows();
  const double n = static_cast<double>(N);
  MatrixXcd gram;  // Y Yᴴ, then V Vᴴ (N × N)
  factor_gram(Y, gram);
  const MatrixXd A = (H.array() * gram.array().conjugate()).real();  // N × N
  factor_gram(v, gram);
  const MatrixXd B = (H.array() * gram.array().conjugate()).real();  // N × N
  const VectorXd y_norms = Y.rowwise().squaredNorm(), v_norms = v.rowwise().squaredNorm();  // N
  double best_alpha = 1.0, best_f = std::numeric_limits<double>::infinity();
  VectorXd scale(N);  // s_i
  for (double alpha = 1.0; alpha > 1e-3; alpha *= 0.5) {
    const double weight = alpha * alpha * n;
    scale = (y_norms + weight * v_norms).cwiseSqrt().cwiseInverse();
    const double f = scale.dot(A * scale) + weight * scale.dot(B * scale);
    if (f < best_f) {
      best_f = f;
      best_alpha = alpha;
    }
  }
  MatrixXcd next(N, Y.cols() + v.cols());
  next << Y, best_alpha * std::sqrt(n) * v;
  next.rowwise().normalize();
  return next;
}

}  // namespace

ComplexOutcome complex_outcome(const Eigen::MatrixXcd& H, Eigen::MatrixXcd Y, Eigen::VectorXd mu, int iterations,
                               bool want_vectors, double vectors_below) {
  ComplexOutcome out;
  out.Y = std::move(Y);
  out.iterations = iterations;
  out.mu = std::move(mu);
  MatrixXcd S;  // H − diag(μ), N × N
  certificate_matrix(H, out.mu, S);
  if (want_vectors) {
    lowest_eigenpairs(S, static_cast<int>(std::min<Eigen::Index>(kMaxNewColumns, S.rows())), out.eigenvalues,
                      out.eigenvectors, vectors_below);
  } else {
    out.eigenvalues = eigenvalues_of(S);
  }
  return out;
}

ComplexOutcome complex_outcome(const Eigen::MatrixXcd& H, Eigen::MatrixXcd Y, int iterations, bool want_vectors) {
  VectorXd mu = multipliers_at(H, Y);
  return complex_outcome(H, std::move(Y), std::move(mu), iterations, want_vectors);
}

bool shifted_positive_definite(const Eigen::MatrixXcd& H, const Eigen::VectorXd& mu, double shift) {
  MatrixXcd S;  // H − diag(μ), N × N
  certificate_matrix(H, mu, S);
  return positive_definite_when_shifted(std::move(S), shift);
}

ComplexOutcome solve_complex_low_rank(const Eigen::MatrixXcd& H, const Options& options, int max_unknowns,
                                      bool spectrum_if_not_psd) {
  const Eigen::Index N = H.rows();
  MatrixXcd Y = spectral_start(H);
  int iterations = 0;
  double curvature = 0;  // λ_min(S) at the level below, whose eigenvector the escape followed
  for (;;) {
    iterations += complex_newton(H, Y, options.max_newton_iterations, 1e-12, true, curvature);
    const Eigen::Index p = Y.cols();
    const bool can_climb = complex_newton_unknowns(N, p + 1) <= max_unknowns && p < N;
    VectorXd mu = multipliers_at(H, Y);  // N
    if (!can_climb && !spectrum_if_not_psd && !shifted_positive_definite(H, mu, 2.0 * options.psd_tol)) {
      // λ_min(S) < −2·psd_tol (up to rounding): not certified, and no spectrum is computed.
      ComplexOutcome out;
      out.Y = std::move(Y);
      out.mu = std::move(mu);
      out.iterations = iterations;
      return out;
    }
    // Eigenvectors only for an escape: a level whose S + psd_tol·I passes a Cholesky test will
    // certify (up to rounding at the boundary, where they are computed after all), and its
    // eigenvalues alone cost a third of the full decomposition (N = 8: 1.8 against 5 µs).
    const bool will_certify = can_climb && shifted_positive_definite(H, mu, options.psd_tol);
    // (Vectors only for the eigenvalues below −psd_tol, the ones an escape follows: at N = 6 the
    // second lowest is usually Y's own, at zero.)
    ComplexOutcome out = complex_outcome(H, std::move(Y), std::move(mu), iterations, can_climb && !will_certify,
                                         -options.psd_tol);
    out.certified = out.eigenvalues[0] >= -options.psd_tol;
    if (out.certified || !can_climb) return out;
    if (out.eigenvectors.size() == 0)
      out = complex_outcome(H, std::move(out.Y), std::move(out.mu), iterations, true, -options.psd_tol);
    // Up to kMaxNewColumns columns at once, one per negative eigenvalue (BENCHMARKS.md,
    // session 11: two save a level at N = 32 and 64 without slowing the next one).
    // (lowest_eigenpairs found a vector for each of these: it counts on the same eigenvalues.)
    int columns = std::min<int>(kMaxNewColumns, (out.eigenvalues.array() < -options.psd_tol).count());
    while (columns > 1 && complex_newton_unknowns(N, p + columns) > max_unknowns) --columns;
    Y = escape(H, out.Y, out.eigenvectors.leftCols(columns));
    curvature = out.eigenvalues[0];
  }
}

Eigen::MatrixXcd complex_factor_of(const Eigen::MatrixXd& X) {
  const Eigen::Index N = X.rows() / 2;
  MatrixXcd Z(N, N);  // K-average of X as a Hermitian matrix, N × N
  for (Eigen::Index j = 0; j < N; ++j)
    for (Eigen::Index i = 0; i < N; ++i)
      Z(i, j) = {0.5 * (X(2 * i, 2 * j) + X(2 * i + 1, 2 * j + 1)), 0.5 * (X(2 * i + 1, 2 * j) - X(2 * i, 2 * j + 1))};
  return complex_factor(Z, 1e-6);
}

Eigen::MatrixXcd complex_factor(const Eigen::MatrixXcd& Z, double cutoff) {
  MatrixXcd Y = pivoted_cholesky(Z, cutoff);
  for (Eigen::Index i = 0; i < Y.rows(); ++i) {
    const double norm = Y.row(i).norm();
    if (norm > 0) Y.row(i) /= norm; else Y(i, 0) = 1.0;
  }
  return Y;
}

Certificate complex_certificate(const ComplexOutcome& outcome) {
  const Eigen::Index N = outcome.mu.size();
  Certificate cert;
  cert.lambda = Eigen::MatrixXd::Zero(2 * N, 2);  // Λ_ii = μ_i I₂ stacked, 2N × 2
  for (Eigen::Index i = 0; i < N; ++i) cert.lambda(2 * i, 0) = cert.lambda(2 * i + 1, 1) = outcome.mu[i];
  cert.trace_lambda = 2.0 * outcome.mu.sum();
  if (outcome.eigenvalues.size() == 0) {  // no spectrum (S failed its Cholesky test): no bound
    cert.min_eig = cert.dual_bound = -std::numeric_limits<double>::infinity();
    return cert;
  }
  cert.eigenvalues.resize(2 * N);
  for (Eigen::Index i = 0; i < N; ++i) cert.eigenvalues[2 * i] = cert.eigenvalues[2 * i + 1] = outcome.eigenvalues[i];
  bound_from_spectrum(cert);
  return cert;
}

}  // namespace fact::sdp::detail
