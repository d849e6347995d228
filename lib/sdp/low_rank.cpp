// Burer–Monteiro Riemannian staircase with block-coordinate minimisation.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "internal.h"

namespace fact::sdp::detail {

int pataki_rank(int blocks, int d) {
  const double m = blocks * d * (d + 1) / 2.0;  // number of equality constraints
  return static_cast<int>(std::floor((std::sqrt(8.0 * m + 1.0) - 1.0) / 2.0)) + 1;
}

Eigen::MatrixXd polar_rows(const Eigen::MatrixXd& G) {
  if (G.rows() == 1) {
    const double norm = G.norm();
    return norm > 0 ? Eigen::MatrixXd(G / norm) : Eigen::MatrixXd();
  }
  // d = 2: P = (G Gᵀ)^{-1/2} G by polar_closed_form, or the SVD when that form is not trusted
  // (an independent review found a rank-1 G, det = 8.9e-18·tr², given rows far from orthonormal).
  const double m00 = G.row(0).squaredNorm(), m11 = G.row(1).squaredNorm(), m01 = G.row(0).dot(G.row(1));
  double i00, i01, i11;
  if (polar_closed_form(m00, m01, m11, i00, i01, i11)) {
    Eigen::MatrixXd P(2, G.cols());
    P.row(0) = i00 * G.row(0) + i01 * G.row(1);
    P.row(1) = i01 * G.row(0) + i11 * G.row(1);
    return P;
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(G, Eigen::ComputeThinU | Eigen::ComputeThinV);
  if (!(svd.singularValues()(0) > 0)) return Eigen::MatrixXd();
  return svd.matrixU() * svd.matrixV().transpose();
}

bool polar_closed_form(double m00, double m01, double m11, double& i00, double& i01, double& i11) {
  const double det = m00 * m11 - m01 * m01, tr = m00 + m11;
  if (!(det > kPolarClosedFormDet * tr * tr)) return false;
  const double s = std::sqrt(det), t = std::sqrt(tr + 2.0 * s);
  const double r00 = (m00 + s) / t, r11 = (m11 + s) / t, r01 = m01 / t, det_root = r00 * r11 - r01 * r01;
  i00 = r11 / det_root, i11 = r00 / det_root, i01 = -r01 / det_root;
  if (det >= kPolarCheckDet * tr * tr) return true;
  // det is rounding-sized against tr²: check P Pᵀ = R⁻¹ M R⁻¹ = I (R⁻¹ = [[i00, i01], [i01, i11]]).
  const double a00 = i00 * m00 + i01 * m01, a01 = i00 * m01 + i01 * m11;
  const double a10 = i01 * m00 + i11 * m01, a11 = i01 * m01 + i11 * m11;
  const double q00 = a00 * i00 + a01 * i01, q01 = a00 * i01 + a01 * i11, q11 = a10 * i01 + a11 * i11;
  return std::max({std::abs(q00 - 1.0), std::abs(q01), std::abs(q11 - 1.0)}) <= kOrthonormalTol;
}

bool project_blocks(Eigen::MatrixXd& Y, int d) {
  for (Eigen::Index i = 0; i < Y.rows(); i += d) {
    const Eigen::MatrixXd block = polar_rows(Y.middleRows(i, d));
    if (block.size() == 0) return false;
    Y.middleRows(i, d) = block;
  }
  return true;
}

// One block update at fixed size D (1 or 2): hot path, fixed-size types.
template <int D>
static int sweeps_fixed(const Eigen::MatrixXd& C, Eigen::MatrixXd& Y, int max_sweeps, double tol) {
  const Eigen::Index n = C.rows(), r = Y.cols();
  Eigen::Matrix<double, D, Eigen::Dynamic> G(D, r);  // (C Y)_i − C_ii Y_i, D × r
  int sweep = 0;
  for (; sweep < max_sweeps; ++sweep) {
    double max_change = 0;
    for (Eigen::Index i = 0; i < n; i += D) {
      G.noalias() = C.middleCols<D>(i).transpose() * Y;
      G.noalias() -= C.block<D, D>(i, i) * Y.middleRows<D>(i);
      const Eigen::MatrixXd next = polar_rows(-G);
      if (next.size() == 0) continue;  // no information about this block: keep it
      max_change = std::max(max_change, (next - Y.middleRows<D>(i)).cwiseAbs().maxCoeff());
      Y.middleRows<D>(i) = next;
    }
    if (max_change < tol) return sweep + 1;
  }
  return sweep;
}

int block_coordinate_sweeps(const Eigen::MatrixXd& C, int d, Eigen::MatrixXd& Y, int max_sweeps, double tol) {
  return d == 1 ? sweeps_fixed<1>(C, Y, max_sweeps, tol) : sweeps_fixed<2>(C, Y, max_sweeps, tol);
}

// Random start with orthonormal-row blocks, deterministic by seed.
static Eigen::MatrixXd random_factor(Eigen::Index n, int d, int r, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  Eigen::MatrixXd Y(n, r);
  for (Eigen::Index i = 0; i < n; i += d) {
    Eigen::MatrixXd block(d, r);
    for (int a = 0; a < d; ++a)
      for (int b = 0; b < r; ++b) block(a, b) = gauss(rng);
    Y.middleRows(i, d) = polar_rows(block);
  }
  return Y;
}

// Adds one column to Y and steps along the descent direction v (the eigenvector of a
// negative eigenvalue of S), retracting every block back to orthonormal rows.
static Eigen::MatrixXd escape_saddle(const Eigen::MatrixXd& Y, const Eigen::VectorXd& v, int d, double step) {
  Eigen::MatrixXd next(Y.rows(), Y.cols() + 1);
  next.leftCols(Y.cols()) = Y;
  next.col(Y.cols()) = step * v;
  project_blocks(next, d);  // every block keeps its orthonormal Y_i part, so none is zero
  return next;
}

// From kInverseStartMinSize to kInverseStartMaxSize rows the spectral start's vectors come from
// bottom_vectors_by_inverse; below (and where C + δI does not factor) from the tridiagonal
// reduction, above from bottom_eigenvectors' inverse iteration by triangular solves.
constexpr Eigen::Index kInverseStartMinSize = 16;
constexpr Eigen::Index kInverseStartMaxSize = 64;
// C's bottom k eigenvectors (n × k, orthonormal) by subspace iteration on W = (C + δI)⁻¹ (δ:
// inverse_iteration_shift) with two guard vectors: W formed once by the interior point's kernels
// (Cholesky, L⁻¹, L⁻ᵀ L⁻¹), then kInverseStartSteps products W·V (n × (k + 2)), each followed by
// Gram–Schmidt twice, and a Rayleigh–Ritz step on C. The products replace bottom_eigenvectors'
// pairs of triangular solves, which Eigen runs slowly at these sizes, and the tridiagonal
// reduction's QL sweeps and back-transformation: random C of full rank at n = 16 / 24 / 32 / 48 /
// 64 took 5.6 / 10.0 / 16.0 / 34.0 / 59.9 µs by the reduction (8.4 / 12.3 / 16.2 / 25.8 / 36.2 µs
// by triangular solves), 4.9 / 6.6 / 8.9 / 15.0 / 25.9 µs this way with 12 steps, the same subspace
// to 4e-12 … 7e-8 (6 steps since session 51: kInverseStartSteps); at n = 100 the triangular solves were faster (73 against 93 µs; BENCHMARKS.md, session 50).
// Empty when C + δI fails its Cholesky test.
Eigen::MatrixXd bottom_vectors_by_inverse(const Eigen::MatrixXd& C, int k) {
  const Eigen::Index n = C.rows();
  Eigen::MatrixXd W;  // (C + δI)⁻¹, n × n
  if (!shifted_inverse(C, W)) return Eigen::MatrixXd();
  const int m = k + 2;
  Eigen::MatrixXd V(n, m), next(n, m);  // orthonormal iterates, n × m
  for (Eigen::Index i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) V(i, j) = generic_start_entry(i, j);
  for (int step = 0; step < kInverseStartSteps; ++step) {
    next.noalias() = W * V;
    orthonormalize_columns(next);
    V.swap(next);
  }
  return bottom_ritz_vectors(C, V, k);
}

// Spectral start: the bottom-d eigenvectors of C, each block projected to orthonormal rows.
// Exact when the data are noise-free and the optimum unique.
static Eigen::MatrixXd spectral_factor(const Eigen::MatrixXd& C, int d, unsigned seed) {
  const Eigen::Index n = C.rows();
  Eigen::MatrixXd Y;  // n × d
  if (n >= kInverseStartMinSize && n <= kInverseStartMaxSize) Y = bottom_vectors_by_inverse(C, d);
  if (Y.size() == 0) Y = bottom_eigenvectors(C, d, kInverseStartMaxSize);
  Eigen::MatrixXd fallback;  // n × d, drawn only when a block has no direction (seeding costs 2 % at N = 3)
  for (Eigen::Index i = 0; i < Y.rows(); i += d) {
    const Eigen::MatrixXd block = polar_rows(Y.middleRows(i, d));
    if (block.size() == 0 && fallback.size() == 0) fallback = random_factor(C.rows(), d, d, seed);
    Y.middleRows(i, d) = block.size() ? block : fallback.middleRows(i, d);
  }
  return Y;
}

namespace {

// True when λ_min(S) < −ε is proved by S Y alone (S = C − Λ(Y), n × n, for a feasible Y, n × r,
// with Λ(Y) from Y itself: S Y is half the Riemannian gradient). Then ⟨S, Y Yᵀ⟩ = 0 and
// tr Y Yᵀ = n, so S + εI ⪰ 0 would give ‖(S + εI) Y‖²_F ≤ ‖S + εI‖₂·⟨S + εI, Y Yᵀ⟩ ≤
// (‖S‖_F + ε)·ε n, that is ‖S Y‖_F ≤ √((‖S‖_F + ε) ε n) + ε √n; a gradient above twice that (the
// factor covers rounding in ⟨S, Y Yᵀ⟩ and in Y's feasibility) rules the certificate out. O(n² r),
// and free of cost where it does not decide: a converged factor's S Y is at rounding level.
bool provably_indefinite(const Eigen::MatrixXd& S, const Eigen::MatrixXd& Y, double eps) {
  if (!(eps > 0)) return false;  // at ε = 0 the limit is 0, and rounding in S Y alone would pass it
  const double n = static_cast<double>(S.rows());
  const double limit = std::sqrt((S.norm() + eps) * eps * n) + eps * std::sqrt(n);
  return (S * Y).norm() > 2.0 * limit;
}

// The certificate of a factor that cannot certify (provably_indefinite): Λ and tr Λ, no
// spectrum, and NaN for λ_min, the bound and its error.
Certificate without_spectrum(const Eigen::MatrixXd& lambda, int d) {
  Certificate cert;
  cert.lambda = lambda;
  cert.trace_lambda = block_trace(lambda, d);
  cert.min_eig = cert.dual_bound = cert.bound_error = std::numeric_limits<double>::quiet_NaN();
  return cert;
}

}  // namespace

LowRankOutcome solve_low_rank(const Eigen::MatrixXd& C, int d, const Options& options, double crawl_decrease,
                              bool spectrum_only_if_certifiable, double climb_eig) {
  const Eigen::Index n = C.rows();
  const int blocks = static_cast<int>(n / d);
  const int max_rank = options.max_rank > 0 ? options.max_rank : std::min<int>(pataki_rank(blocks, d), n);
  LowRankOutcome out;
  out.Y = spectral_factor(C, d, options.seed);
  for (;;) {
    if (out.Y.cols() > d) out.iterations += block_coordinate_sweeps(C, d, out.Y, options.max_sweeps, 1e-3);
    out.iterations +=
        newton_refine(C, d, out.Y, options.max_newton_iterations, 1e-12, NewtonSystem::automatic, crawl_decrease);
    const Eigen::MatrixXd lambda = lambda_from_factor(C, out.Y, d);
    Eigen::MatrixXd S;  // C − Λ (n × n), formed only for the tests below
    bool last_level = out.Y.cols() >= max_rank;
    bool steep = false;  // λ_min(S) < −climb_eig: a critical point with steep negative curvature
    if (climb_eig > 0 && out.Y.cols() == d && !last_level) {
      S = certificate_matrix(C, lambda, d);
      steep = (S * out.Y).norm() < climb_eig && !positive_definite_when_shifted(S, climb_eig);
      last_level = !steep;
    }
    // A last level that cannot certify skips the spectrum: its gradient proves λ_min(S) < −psd_tol
    // (O(n² r)), or S + psd_tol·I fails a Cholesky test (n³/3, against the spectrum's 4n³/3
    // reduction and QL: a converged saddle of random C of full rank, N = 7 … 24, 0.97–0.98 of the
    // solve; where the level certifies the test is extra, 1.01–1.02; BENCHMARKS.md, session 50).
    if (spectrum_only_if_certifiable && last_level) {
      if (S.size() == 0) S = certificate_matrix(C, lambda, d);
      if (provably_indefinite(S, out.Y, options.psd_tol) || !positive_definite_when_shifted(S, options.psd_tol)) {
        out.certificate = without_spectrum(lambda, d);
        return out;
      }
    }
    // A level below the last whose S + psd_tol·I fails a Cholesky test (or the steep-climb test)
    // escapes: its spectrum comes with the eigenvector the escape follows, once, instead of after a
    // spectrum alone. Sweep (N = 3 … 6, 4 seeds): random C of full rank, rank N + 1 and rank 3 and
    // the plain form under noise 0.95–0.98 of the time; where a level certifies at once (the paper's
    // cost noise-free or at 0.01) the test is extra, 1.02–1.05 (BENCHMARKS.md, session 50).
    bool escapes = steep;
    if (!last_level && !steep) {
      if (S.size() == 0) S = certificate_matrix(C, lambda, d);
      escapes = !positive_definite_when_shifted(S, options.psd_tol);
    }
    out.certificate = certify(C, lambda, d, escapes);
    out.certified = out.certificate.min_eig >= -options.psd_tol;
    if (out.certified || last_level) return out;
    if (!escapes) out.certificate = certify(C, lambda, d, true);  // the escape direction needs the eigenvector
    out.Y = escape_saddle(out.Y, out.certificate.min_vector, d, 0.1);
  }
}

}  // namespace fact::sdp::detail
