// Step lengths of the interior point (see step_length.h), the factor kernels they and the interior
// points use, and the lowest eigenvalue of a tridiagonal matrix (the Lanczos estimates'). The
// kernels work on raw column-major storage or on zero-padded copies whose size is fixed at compile
// time: at the small sizes (the grid's tests, n ≤ 48) Eigen's blocked Cholesky and triangular
// solves spend most of their time on overhead, and loops over a column's varying tail on their
// remainders.
#include "step_length.h"

#include "complex_product.h"
#include "internal.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

namespace fact::sdp::detail {
namespace {

// Number of eigenvalues below x of the symmetric tridiagonal (diagonal a, subdiagonal b):
// the Sturm count, i.e. the negative pivots of the LDLᵀ factorisation of T − xI.
int eigenvalues_below(const Eigen::Ref<const Eigen::VectorXd>& a, const Eigen::Ref<const Eigen::VectorXd>& b, double x) {
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

// The LDLᵀ pivots q_i of T − xI for the tridiagonal T (diagonal a, subdiagonal b) and, along them,
// s1 = Σ_j 1/(λ_j − x) and s2 = Σ_j 1/(λ_j − x)², minus the first two derivatives of
// log det(T − xI) = Σ log q_i, from the recurrence q_i = a_i − x − b_{i−1}²/q_{i−1} and its first
// two derivatives in x. False when a pivot is not positive: then x is not below λ_min (Sturm).
bool inverse_power_sums(const Eigen::Ref<const Eigen::VectorXd>& a, const Eigen::Ref<const Eigen::VectorXd>& b,
                        double x, double& s1, double& s2) {
  double q = a[0] - x, dq = -1.0, ddq = 0.0;  // q_i and its derivatives q_i', q_i''
  if (!(q > 0)) return false;
  double r = 1.0 / q, d1 = dq * r, d2 = -d1 * d1;  // 1/q_i; Σ q_i'/q_i; Σ (q_i''/q_i − (q_i'/q_i)²)
  for (Eigen::Index i = 1; i < a.size(); ++i) {
    const double e = b[i - 1] * b[i - 1], t = dq * r;  // b_{i−1}², q_{i−1}'/q_{i−1}
    q = a[i] - x - e * r;
    ddq = e * r * (ddq * r - 2.0 * t * t);
    dq = -1.0 + e * t * r;
    if (!(q > 0)) return false;
    r = 1.0 / q;
    const double u = dq * r;
    d1 += u;
    d2 += ddq * r - u * u;
  }
  s1 = -d1;
  s2 = -d2;
  return true;
}

// Laguerre steps lowest_from_below takes before it bisects its bracket instead. On a simple λ_min
// it converges in 3–6 (after a phase that halves the distance when it starts far below a small
// λ_min); on a repeated or tightly clustered one only linearly (a fixed fraction of the error left
// a step: 0.65–0.75 at multiplicity n/2, review, session 28). Random tridiagonal matrices (k = 4 …
// 48, 3000 each, indefinite and positive definite with a small λ_min): no call reaches 12; a
// 24 × 24 matrix whose λ_min is 12-fold takes 12 steps and 37 Sturm counts to rounding, where the
// iteration alone stopped 1.4e-10 short after 50. Stopping at the third step that did not halve
// the last one instead sent positive definite matrices with a small λ_min to a 50-count bisection.
constexpr int kLaguerreSteps = 12;

// The lower end of [lo, hi] narrowed by bisection on Sturm counts until hi − lo ≤ max(absolute,
// relative·|lo|); lo must lie below λ_min of the tridiagonal (a, b) and hi at or above it.
double bisect_from_below(const Eigen::Ref<const Eigen::VectorXd>& a, const Eigen::Ref<const Eigen::VectorXd>& b,
                         double lo, double hi, double relative, double absolute) {
  while (hi - lo > std::max(absolute, relative * std::abs(lo))) {
    const double mid = 0.5 * (lo + hi);
    if (!(mid > lo && mid < hi)) break;  // the bracket is down to adjacent doubles
    (eigenvalues_below(a, b, mid) > 0 ? hi : lo) = mid;
  }
  return lo;
}

// A lower bound lo on λ_min of the tridiagonal (a, b) with λ_min − lo ≤ max(absolute, relative·|lo|),
// by Laguerre's iteration from x, which must lie below λ_min (NaN otherwise). For a matrix, whose
// characteristic polynomial has only real roots, Laguerre's iterates from below rise monotonically
// to λ_min, cubically when it is simple. At each iterate s1 = Σ 1/(λ_j − x) brackets λ_min between
// x + 1/s1 and x + n/s1: the lower end is the bound, the width (n − 1)/s1 its error. After
// kLaguerreSteps (a repeated or clustered λ_min) the bracket is bisected on Sturm counts; an
// iterate that rounding carries to or past λ_min (a pivot ≤ 0) is an upper end, and one count just
// below it usually finishes. Against the geometric bisection it replaces: n = 14 / 32 / 48
// 0.42 / 1.56 / 2.89 µs → 0.31 / 0.87 / 1.34 µs a step length, and the bound is tighter.
double lowest_from_below(const Eigen::Ref<const Eigen::VectorXd>& a, const Eigen::Ref<const Eigen::VectorXd>& b,
                         double x, double relative, double absolute) {
  const double n = static_cast<double>(a.size());
  const auto tolerance = [&](double at) { return std::max(absolute, relative * std::abs(at)); };
  double s1, s2;
  if (!inverse_power_sums(a, b, x, s1, s2)) return std::numeric_limits<double>::quiet_NaN();
  for (int step = 0; step < kLaguerreSteps; ++step) {
    const double lo = x + 1.0 / s1, hi = x + n / s1;  // λ_min ∈ [lo, hi]
    if (hi - lo <= tolerance(lo)) return lo;
    const double next = x + n / (s1 + std::sqrt(std::max(0.0, (n - 1.0) * (n * s2 - s1 * s1))));
    if (!(next > x)) return bisect_from_below(a, b, lo, hi, relative, absolute);  // no progress left
    if (!inverse_power_sums(a, b, next, s1, s2)) {  // λ_min ≤ next
      const double below = next - 0.5 * tolerance(next);
      if (below <= lo) return lo;  // lo is within the tolerance of next
      if (eigenvalues_below(a, b, below) == 0) return below;
      return bisect_from_below(a, b, lo, below, relative, absolute);
    }
    x = next;
  }
  return bisect_from_below(a, b, x + 1.0 / s1, x + n / s1, relative, absolute);  // converging linearly
}

// Lanczos steps of the corrector's estimate (n > kGridStepMaxSize). 12 against 24: the same
// statuses, random full-rank C N = 25 / 32 / 48 / 64 0.81 / 0.84 / 0.90 / 0.91 of the time and the
// paper's cost with 2N rounds 0.79–0.88 (N = 100 / 150: 0.86–0.93 and 0.53–0.93); 8 was as fast
// on average but had a 1.27× outlier (BENCHMARKS.md, session 25). The complex interior point takes 8.
constexpr int kCorrectorLanczosSteps = 12;
// Lanczos steps of the predictor's estimate (it only sets σ): 4 up to n = 64, 8 above. With 4
// instead of 8 at N = 12 / 16 / 24 / 32 (n = 24 … 64): random full rank 0.85 / 0.91 / 0.94 / 0.97
// of the time, the paper's cost with 2N rounds 0.88 / 0.90 / 0.94 / 1.00, plain N = 12 0.80, no
// status changes; but 21 of 200 instances took an iteration more, and from N = 100 that costs
// more than the steps save (full rank N = 100 25.9 → 27.4 ms; BENCHMARKS.md, session 25).
constexpr int kShortPredictorMaxSize = 64;
int predictor_lanczos_steps(Eigen::Index n) { return n <= kShortPredictorMaxSize ? 4 : 8; }

// The smallest eigenvalue of L⁻¹ Δ L⁻ᵀ estimated by Lanczos (full reorthogonalisation):
// predictor_lanczos_steps for the predictor (τ = 1), kCorrectorLanczosSteps for the corrector.
// apply_delta(u, w) writes w = Δ u. Ritz values lie inside the spectrum, so the corrector's step
// is confirmed by a Cholesky test.
// Up to kInverseLanczosMaxSize rows the products go through the explicit L⁻¹ (`inverse`), above
// through triangular solves with L.
template <class ApplyDelta>
double lanczos_min_eig(const Eigen::MatrixXd& L, const Eigen::MatrixXd& inverse, double tau, ApplyDelta apply_delta) {
  const Eigen::Index n = L.rows();
  Eigen::VectorXd u(n), t(n);
  const int steps = tau >= 1.0 ? predictor_lanczos_steps(n) : kCorrectorLanczosSteps;
  if (n <= kInverseLanczosMaxSize)
    return lanczos_lowest<Eigen::VectorXd>(n, steps, [&](const Eigen::VectorXd& v, Eigen::VectorXd& w) {
      u.noalias() = inverse.transpose() * v;  // L⁻ᵀ v
      apply_delta(u, t);
      w.noalias() = inverse * t;              // L⁻¹ Δ L⁻ᵀ v
    });
  const auto lower = L.triangularView<Eigen::Lower>();
  return lanczos_lowest<Eigen::VectorXd>(n, steps, [&](const Eigen::VectorXd& v, Eigen::VectorXd& w) {
    u = lower.transpose().solve(v);  // L⁻ᵀ v
    apply_delta(u, w);
    lower.solveInPlace(w);           // L⁻¹ Δ L⁻ᵀ v
  });
}

// out = P · blkdiag(D) for P n × n and D the d × d diagonal blocks stacked (n × d): O(n² d).
template <int Dim>
void times_block_diagonal_fixed(const Eigen::MatrixXd& P, const Eigen::MatrixXd& D, Eigen::MatrixXd& out) {
  for (Eigen::Index i = 0; i < P.cols(); i += Dim)
    out.middleCols<Dim>(i).noalias() = P.middleCols<Dim>(i) * D.middleRows<Dim>(i).template leftCols<Dim>();
}

}  // namespace

GershgorinBounds gershgorin_bounds(const Eigen::Ref<const Eigen::VectorXd>& a, const Eigen::Ref<const Eigen::VectorXd>& b) {
  const Eigen::Index n = a.size();
  GershgorinBounds bounds{a[0], a[0]};
  for (Eigen::Index i = 0; i < n; ++i) {
    const double r = (i > 0 ? std::abs(b[i - 1]) : 0.0) + (i + 1 < n ? std::abs(b[i]) : 0.0);
    bounds.lo = std::min(bounds.lo, a[i] - r);
    bounds.hi = std::max(bounds.hi, a[i] + r);
  }
  return bounds;
}

double lowest_tridiagonal_eigenvalue(const Eigen::Ref<const Eigen::VectorXd>& a, const Eigen::Ref<const Eigen::VectorXd>& b) {
  if (!a.allFinite() || !b.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  const double largest = std::max(a.cwiseAbs().maxCoeff(), b.size() > 0 ? b.cwiseAbs().maxCoeff() : 0.0);
  if (largest == 0) return 0.0;  // T = 0
  if (largest < 1e-100 || largest > 1e100) {  // the pivots' recurrence squares b and divides by q
    const Eigen::VectorXd an = a / largest, bn = b / largest;
    return largest * lowest_tridiagonal_eigenvalue(an, bn);
  }
  const GershgorinBounds discs = gershgorin_bounds(a, b);  // λ_min ∈ [discs.lo, discs.hi]
  const double width = 4.0 * std::numeric_limits<double>::epsilon() * discs.radius();
  // (discs.lo may be λ_min itself, a diagonal T: the iteration starts below it)
  return lowest_from_below(a, b, discs.lo - 0.01 * (discs.hi - discs.lo) - width, 0.0, width);
}

void symmetrize(Eigen::MatrixXd& A) {
  for_each_entry_below_diagonal(A.rows(), [&A](Eigen::Index i, Eigen::Index j) {
    A(i, j) = A(j, i) = 0.5 * (A(i, j) + A(j, i));
  });
}

void times_block_diagonal(const Eigen::MatrixXd& P, const Eigen::MatrixXd& D, int d, Eigen::MatrixXd& out) {
  if (d == 1)
    times_block_diagonal_fixed<1>(P, D, out);
  else
    times_block_diagonal_fixed<2>(P, D, out);
}

namespace {

// Left-looking: column j of L is A's below the diagonal less L(j:n, 0:j)·L(j, 0:j)ᵀ, one
// matrix–vector product (Eigen's kernel) a column.
bool cholesky_lower_by_columns(const Eigen::MatrixXd& A, Eigen::MatrixXd& L) {
  const Eigen::Index n = A.rows();
  for (Eigen::Index j = 0; j < n; ++j) {
    const Eigen::Index rest = n - j;
    auto column = L.col(j).tail(rest);
    column = A.col(j).tail(rest);
    if (j > 0) column.noalias() -= L.block(j, 0, rest, j) * L.row(j).head(j).transpose();
    const double pivot = column[0];
    if (!(pivot > 0)) return false;
    const double root = std::sqrt(pivot);
    column[0] = root;
    column.tail(rest - 1) /= root;
  }
  return true;
}

}  // namespace

namespace {
bool padded_cholesky(const Eigen::MatrixXd& A, Eigen::MatrixXd& L);  // (below)
}  // namespace

bool cholesky_lower(const Eigen::MatrixXd& A, Eigen::MatrixXd& L) {
  if (A.rows() <= kPaddedCholeskyMaxSize) return padded_cholesky(A, L);
  return cholesky_lower_by_columns(A, L);
}

bool complex_cholesky_by_loops(Eigen::Ref<Eigen::MatrixXcd, 0, Eigen::OuterStride<>> A) {
  using Complex = std::complex<double>;
  const Eigen::Index n = A.rows();
  for (Eigen::Index k = 0; k < n; ++k) {  // L D Lᴴ: column k keeps D_kk·L(:, k) until the scaling below
    const double pivot = A(k, k).real();
    if (!(pivot > 0)) return false;
    const double reciprocal = 1.0 / pivot;
    const Complex* __restrict lk = &A(0, k);
    for (Eigen::Index j = k + 1; j < n; ++j) {
      Complex* __restrict lj = &A(0, j);
      const Complex factor = std::conj(lk[j]) * reciprocal;
      for (Eigen::Index i = j; i < n; ++i) lj[i] -= lk[i] * factor;
    }
  }
  for (Eigen::Index k = 0; k < n; ++k) {  // L D^½: column k over √D_kk
    const double root = std::sqrt(A(k, k).real()), scale = 1.0 / root;
    Complex* __restrict lk = &A(0, k);
    lk[k] = root;
    for (Eigen::Index i = k + 1; i < n; ++i) lk[i] *= scale;
  }
  return true;
}

namespace {

// padded_cholesky_in_place for n ≤ P rows (P a multiple of 8) on a P × P column-major copy on the
// stack: column j holds A's lower part from row j, zeros from the start of its 8-row block to row j
// and from row n on, so that every update runs over whole 8-row blocks, from the block that holds
// the first row it needs to row P, with no remainder loop (the rows above that first row take
// finite values nothing reads; the rows from n on stay 0). Columns k and k + 1 are finished
// together and taken off each later column in one pass. The copy takes at most 128 KiB of stack
// (P = 128).
template <int P>
bool cholesky_padded(Eigen::MatrixXd& A) {
  alignas(64) double a[P * P];
  const int n = static_cast<int>(A.rows());
  for (int j = 0; j < n; ++j) {
    double* aj = a + j * P;
    for (int i = j & ~7; i < j; ++i) aj[i] = 0.0;
    for (int i = j; i < n; ++i) aj[i] = A(i, j);
    for (int i = n; i < P; ++i) aj[i] = 0.0;
  }
  int k = 0;
  for (; k + 1 < n; k += 2) {
    double* __restrict lk = a + k * P;
    double* __restrict next = a + (k + 1) * P;
    if (!(lk[k] > 0)) return false;
    const double root = std::sqrt(lk[k]), scale = 1.0 / root;
    const double below = lk[k + 1] * scale;  // L(k + 1, k)
    const double pivot = next[k + 1] - below * below;
    if (!(pivot > 0)) return false;
    const double next_root = std::sqrt(pivot), next_scale = 1.0 / next_root;
    for (int b = k & ~7; b < P; b += 8)
      for (int t = b; t < b + 8; ++t) {
        lk[t] *= scale;
        next[t] = (next[t] - lk[t] * below) * next_scale;
      }
    lk[k] = root;
    next[k + 1] = next_root;
    for (int j = k + 2; j < n; ++j) {
      double* __restrict aj = a + j * P;
      const double factor = lk[j], next_factor = next[j];
      for (int b = j & ~7; b < P; b += 8)
        for (int t = b; t < b + 8; ++t) aj[t] -= lk[t] * factor + next[t] * next_factor;
    }
  }
  if (k < n) {  // the last column of an odd n: its pivot only
    double* lk = a + k * P;
    if (!(lk[k] > 0)) return false;
    lk[k] = std::sqrt(lk[k]);
  }
  for (int j = 0; j < n; ++j)
    for (int i = j; i < n; ++i) A(i, j) = a[j * P + i];
  return true;
}

}  // namespace

bool padded_cholesky_in_place(Eigen::MatrixXd& A) {
  static_assert(kPaddedCholeskyMinSize > 48 && kBlockedCholeskyMinSize <= 128, "the padded sizes below");
  eigen_assert(A.rows() >= kPaddedCholeskyMinSize && A.rows() < kBlockedCholeskyMinSize);
  switch ((A.rows() + 7) / 8) {
    case 7: return cholesky_padded<56>(A);
    case 8: return cholesky_padded<64>(A);
    case 9: return cholesky_padded<72>(A);
    case 10: return cholesky_padded<80>(A);
    case 11: return cholesky_padded<88>(A);
    case 12: return cholesky_padded<96>(A);
    case 13: return cholesky_padded<104>(A);
    case 14: return cholesky_padded<112>(A);
    case 15: return cholesky_padded<120>(A);
    default: return cholesky_padded<128>(A);  // 121 … 127 rows
  }
}

bool complex_cholesky_by_panels(Eigen::MatrixXcd& A) {
  const Eigen::Index n = A.rows();
  for (Eigen::Index k = 0; k < n; k += kComplexCholeskyPanel) {
    const Eigen::Index width = std::min(kComplexCholeskyPanel, n - k), below = n - k - width;
    if (!complex_cholesky_by_loops(A.block(k, k, width, width))) return false;
    if (below == 0) break;
    auto panel = A.block(k + width, k, below, width);  // A21 → L21 = A21 L11⁻ᴴ
    A.block(k, k, width, width).triangularView<Eigen::Lower>().adjoint().solveInPlace<Eigen::OnTheRight>(panel);
    A.block(k + width, k + width, below, below).selfadjointView<Eigen::Lower>().rankUpdate(panel, -1.0);
  }
  return true;
}

namespace {

// Below this size a real diagonal block of L is inverted directly (invert_lower_padded); above it
// the recursion's matrix products, which Eigen vectorises far better than its triangular solves
// (complex, N = 100, AVX-512: 0.06 ms against 0.73 ms for L.solve(I), BENCHMARKS.md, session 15;
// 24 measured best with substitution, session 25; the padded kernel measured faster than the
// recursion up to 32 rows too, but not at 48, session 28). A complex L⁻¹ of up to
// kSplitInverseMaxSize rows goes by invert_complex_lower_padded, without recursion.
constexpr Eigen::Index kInverseBlock = 24;
constexpr Eigen::Index kSplitInverseMaxSize = 32;
// Above kSplitInverseMaxSize a complex L⁻¹ goes by panels (invert_lower_by_panels) of
// kInversePanel columns instead of the recursion: with 8 columns (16 from 80 rows) and the
// diagonal blocks by substitution, n = 32 / 48 / 64 / 100 / 128 / 200 took 2.5 / 5.7 / 11.0 /
// 29.8 / 54.5 / 177 µs against 3.4 / 7.1 / 14.6 / 45 / 74 / 224 µs (BENCHMARKS.md, session 47).
// With the diagonal blocks by invert_complex_lower_padded, panels of 24 columns measured best
// from 33 to 200 rows (8 / 16 / 24 / 32: n = 48 5.4 / 4.6 / 4.5 / 4.8 µs, n = 100 31.7 / 27.9 /
// 26.3 / 26.9 µs, n = 200 204 / 177 / 169 / 165 µs; session 48). A real L⁻¹ by panels lost at
// every size from 24 to 200 (0.59 / 14.4 / 64.8 µs at n = 24 / 100 / 200 by the recursion, 0.96 /
// 16.3 / 69.5 by panels; session 47).
constexpr Eigen::Index kInversePanel = 24;

// Real L⁻¹ for n ≤ P rows on P × P copies fixed at compile time. Row k of L⁻¹ is final once
// divided by L_kk; its multiples are then taken off the rows below in every column at once, whole
// P-vectors that do not wait on each other, where a substitution column by column waits on each
// x_k in turn: n = 10 / 16 / 24 0.29 / 0.80 / 1.94 µs → 0.19 / 0.27 / 0.64 µs
// (BENCHMARKS.md, session 28).
template <int P>
void invert_lower_padded(const Eigen::Ref<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>& L,
                         Eigen::Ref<Eigen::MatrixXd, 0, Eigen::OuterStride<>> inverse) {
  const int n = static_cast<int>(L.rows());
  Eigen::Matrix<double, P, P> below;     // L's strictly lower triangle, zero elsewhere
  Eigen::Matrix<double, P, 1> reciprocal;  // 1 / L_kk
  below.setZero();
  reciprocal.setZero();
  for (int j = 0; j < n; ++j) {
    for (int i = j + 1; i < n; ++i) below(i, j) = L(i, j);
    reciprocal[j] = 1.0 / L(j, j);
  }
  Eigen::Matrix<double, P, P> X = Eigen::Matrix<double, P, P>::Identity();  // becomes L⁻¹
  for (int k = 0; k < n; ++k) {
    for (int c = 0; c <= k; ++c) X(k, c) *= reciprocal[k];
    for (int c = 0; c <= k; ++c) X.col(c) -= below.col(k) * X(k, c);
  }
  inverse = X.topLeftCorner(n, n);
}

// invert_lower_padded at the smallest padded size that holds L (n ≤ 24). Not inlined: the padded
// copies (up to 9 KB) then stay out of invert_lower's recursive frames.
EIGEN_DONT_INLINE void invert_lower_small(const Eigen::Ref<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>& L,
                                          Eigen::Ref<Eigen::MatrixXd, 0, Eigen::OuterStride<>> inverse) {
  const Eigen::Index n = L.rows();
  if (n <= 8) return invert_lower_padded<8>(L, inverse);
  if (n <= 12) return invert_lower_padded<12>(L, inverse);
  if (n <= 16) return invert_lower_padded<16>(L, inverse);
  if (n <= 20) return invert_lower_padded<20>(L, inverse);
  return invert_lower_padded<24>(L, inverse);
}

// Complex L⁻¹ for n ≤ P rows, as invert_lower_padded on split copies: L = A + iB and L⁻¹ = X + iY
// each P × P real, fixed at compile time (A, B: L's strictly lower triangle, zero elsewhere; L's
// diagonal is real and positive, a Cholesky factor's). Row k of L⁻¹ is final once scaled by
// 1 / L_kk; its multiples then come off the rows below in every column, whole P-vectors of real
// multiply-adds. Against the substitution by columns in std::complex (its divisions and loads
// waiting on each x_k in turn) and, above 8 rows, the recursion on it: n = 5 / 8 / 12 / 16 / 24 /
// 32 0.08 / 0.23 / 0.64 / 0.72 / 1.79 / 2.62 µs → 0.07 / 0.12 / 0.25 / 0.39 / 1.00 / 1.96 µs
// (n = 32 against the panels; BENCHMARKS.md, session 48).
template <int P>
void invert_complex_lower_padded(const Eigen::Ref<const Eigen::MatrixXcd, 0, Eigen::OuterStride<>>& L,
                                 Eigen::Ref<Eigen::MatrixXcd, 0, Eigen::OuterStride<>> inverse) {
  using Padded = Eigen::Matrix<double, P, P>;
  const int n = static_cast<int>(L.rows());
  Padded below_re = Padded::Zero(), below_im = Padded::Zero();  // A and B (P × P)
  Eigen::Matrix<double, P, 1> reciprocal = Eigen::Matrix<double, P, 1>::Zero();  // 1 / L_kk
  for (int j = 0; j < n; ++j) {
    for (int i = j + 1; i < n; ++i) {
      below_re(i, j) = L(i, j).real();
      below_im(i, j) = L(i, j).imag();
    }
    reciprocal[j] = 1.0 / L(j, j).real();
  }
  Padded X = Padded::Identity(), Y = Padded::Zero();  // become Re and Im of L⁻¹
  for (int k = 0; k < n; ++k) {
    for (int c = 0; c <= k; ++c) {
      X(k, c) *= reciprocal[k];
      Y(k, c) *= reciprocal[k];
    }
    for (int c = 0; c <= k; ++c) {  // column c minus (A + iB) column k times (x + iy)
      const double x = X(k, c), y = Y(k, c);
      X.col(c) -= below_re.col(k) * x - below_im.col(k) * y;
      Y.col(c) -= below_re.col(k) * y + below_im.col(k) * x;
    }
  }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) inverse(i, j) = {X(i, j), Y(i, j)};
}

// inverse_by_sweeps on P × P padded copies (n ≤ P): re (and for a complex A im) hold A + shift·I
// and zeros beyond n. Pivot k takes a_ik a_kj / a_kk off every other entry (a_kj = conj(a_jk)),
// then column k becomes a_ik / a_kk, row k a_kj / a_kk and the pivot −1 / a_kk; after the n sweeps
// the copies hold −A⁻¹, whose lower triangle is written out, negated and mirrored.
template <int P, class Matrix>
bool inverse_by_padded_sweeps(const Matrix& A, double shift, Matrix& W) {
  constexpr bool kComplex = Eigen::NumTraits<typename Matrix::Scalar>::IsComplex;
  const int n = static_cast<int>(A.rows());
  alignas(64) double re[P * P];
  alignas(64) double im[kComplex ? P * P : 1];
  for (int j = 0; j < P; ++j)
    for (int i = 0; i < P; ++i) {
      const bool inside = i < n && j < n;
      re[j * P + i] = inside ? std::real(A(i, j)) + (i == j ? shift : 0.0) : 0.0;
      if constexpr (kComplex) im[j * P + i] = inside ? std::imag(A(i, j)) : 0.0;
    }
  alignas(64) double column_re[P];                    // column k, its pivot entry zeroed
  alignas(64) double column_im[kComplex ? P : 1];
  for (int k = 0; k < n; ++k) {
    const double pivot = re[k * P + k];
    if (!usable_pivot(pivot)) return false;
    const double reciprocal = 1.0 / pivot;
    for (int i = 0; i < P; ++i) column_re[i] = re[k * P + i];
    column_re[k] = 0.0;
    if constexpr (kComplex) {
      for (int i = 0; i < P; ++i) column_im[i] = im[k * P + i];
      column_im[k] = 0.0;
    }
    for (int j = 0; j < n; ++j) {
      if (j == k) continue;
      const double factor_re = column_re[j] * reciprocal;  // a_kj / a_kk
      double* __restrict wr = re + j * P;
      if constexpr (kComplex) {
        const double factor_im = -column_im[j] * reciprocal;
        double* __restrict wi = im + j * P;
        for (int i = 0; i < P; ++i) {
          wr[i] -= column_re[i] * factor_re - column_im[i] * factor_im;
          wi[i] -= column_re[i] * factor_im + column_im[i] * factor_re;
        }
        wi[k] = factor_im;
      } else {
        for (int i = 0; i < P; ++i) wr[i] -= column_re[i] * factor_re;
      }
      wr[k] = factor_re;
    }
    for (int i = 0; i < P; ++i) re[k * P + i] = column_re[i] * reciprocal;
    re[k * P + k] = -reciprocal;
    if constexpr (kComplex) {
      for (int i = 0; i < P; ++i) im[k * P + i] = column_im[i] * reciprocal;
      im[k * P + k] = 0.0;
    }
  }
  W.resize(n, n);
  for (int j = 0; j < n; ++j) {
    W(j, j) = -re[j * P + j];
    for (int i = j + 1; i < n; ++i) {
      if constexpr (kComplex) {
        W(i, j) = {-re[j * P + i], -im[j * P + i]};
        W(j, i) = std::conj(W(i, j));
      } else {
        W(i, j) = W(j, i) = -re[j * P + i];
      }
    }
  }
  return true;
}

// invert_complex_lower_padded at the smallest padded size (a multiple of 4) that holds L. Not
// inlined, as invert_lower_small.
EIGEN_DONT_INLINE void invert_complex_lower_small(const Eigen::Ref<const Eigen::MatrixXcd, 0, Eigen::OuterStride<>>& L,
                                                  Eigen::Ref<Eigen::MatrixXcd, 0, Eigen::OuterStride<>> inverse) {
  static_assert(kSplitInverseMaxSize <= 32 && kInversePanel <= kSplitInverseMaxSize, "a block larger than P = 32");
  eigen_assert(L.rows() <= kSplitInverseMaxSize);
  switch ((L.rows() + 3) / 4) {
    case 0:
    case 1: return invert_complex_lower_padded<4>(L, inverse);
    case 2: return invert_complex_lower_padded<8>(L, inverse);
    case 3: return invert_complex_lower_padded<12>(L, inverse);
    case 4: return invert_complex_lower_padded<16>(L, inverse);
    case 5: return invert_complex_lower_padded<20>(L, inverse);
    case 6: return invert_complex_lower_padded<24>(L, inverse);
    case 7: return invert_complex_lower_padded<28>(L, inverse);
    default: return invert_complex_lower_padded<32>(L, inverse);  // 29 … 32 rows
  }
}

// Real L⁻¹ of the lower triangle of L into the lower triangle of `inverse` (same size, upper part
// zeroed): [A 0; B C]⁻¹ = [A⁻¹ 0; −C⁻¹ B A⁻¹  C⁻¹], the off-diagonal block by two products with a
// triangular factor (multiply: Eigen's triangular product).
void invert_lower(Eigen::Ref<const Eigen::MatrixXd, 0, Eigen::OuterStride<>> L,
                  Eigen::Ref<Eigen::MatrixXd, 0, Eigen::OuterStride<>> inverse) {
  const Eigen::Index n = L.rows();
  if (n <= kInverseBlock) return invert_lower_small(L, inverse);
  const Eigen::Index k = n / 2, m = n - k;
  invert_lower(L.topLeftCorner(k, k), inverse.topLeftCorner(k, k));
  invert_lower(L.bottomRightCorner(m, m), inverse.bottomRightCorner(m, m));
  inverse.topRightCorner(k, m).setZero();
  Eigen::MatrixXd BA(m, k);  // B A⁻¹ (A⁻¹, C⁻¹ lower triangular, zeros above)
  multiply<Shape::dense, Shape::lower>(L.bottomLeftCorner(m, k), inverse.topLeftCorner(k, k), BA, 1.0, false);
  multiply<Shape::lower>(inverse.bottomRightCorner(m, m), BA, inverse.bottomLeftCorner(m, k), -1.0, false);
}

// Below this size a real W = Gᴴ G is one dense product (G lower triangular); above it the
// recursion.
constexpr Eigen::Index kGramBlock = 32;

// A complex W = Gᴴ G of more than kGramLoopsMaxSize rows and fewer than kGramPanelMinSize is
// Eigen's Hermitian rank-k update (herk: the lower triangle of W += Gᴴ G, on the complex
// matrix-product kernel). It does not skip G's zero triangle (n³/2 multiply-adds against the
// loops' n³/6) and still runs faster than gram_of_lower_by_loops or the recursion's three real
// products (AVX-512, n = 16 / 24: 0.5 / 1.1 µs against 0.6 / 1.6; BENCHMARKS.md, session 46).
// From kGramPanelMinSize rows W is the sum of the Grams of G's row panels of kGramPanel rows, each
// a rank-kGramPanel update of the leading block left of the panel's last column (n³/6
// multiply-adds in all): n = 32 / 48 / 64 / 100 / 128 / 200 took 1.7 / 4.4 / 9.2 / 26 / 77 /
// 158 µs against 2.1 / 6.1 / 12.8 / 47 / 90 / 271 µs by one update up to 64 rows and the
// recursion onto it above (BENCHMARKS.md, session 47; panels of 8, 24 and 32 rows within 15 %).
// A real W this way lost (n ≤ 32 1.0–1.75×, n = 48 … 128 1.2–1.3× the time of the dense product
// and the recursion; session 46).
constexpr Eigen::Index kGramLoopsMaxSize = 12;
constexpr Eigen::Index kGramPanelMinSize = 32;
constexpr Eigen::Index kGramPanel = 16;

// W = Gᴴ G for a complex lower-triangular G (n × n, zeros above the diagonal) by dot products of
// its columns, from row max(i, j) on where both are nonzero; up to kGramLoopsMaxSize rows since
// session 46 (up to 32 before: tight_noisy N = 12 / 32 / 64 had taken 0.92 / 0.94 / 0.97 of the
// time against Eigen's complex product, three real ones from 16 rows on; a real W this way
// 0.98–1.0; BENCHMARKS.md, session 39). Only W's lower triangle is written, its diagonal real
// (gram_of_lower_factor mirrors it).
void gram_of_lower_by_loops(Eigen::Ref<const Eigen::MatrixXcd, 0, Eigen::OuterStride<>> G,
                            Eigen::Ref<Eigen::MatrixXcd, 0, Eigen::OuterStride<>> W) {
  using Complex = std::complex<double>;
  const Eigen::Index n = G.rows();
  for (Eigen::Index j = 0; j < n; ++j) {
    const Complex* gj = G.data() + j * G.outerStride();  // column j
    W(j, j) = Complex(G.col(j).tail(n - j).squaredNorm(), 0.0);
    for (Eigen::Index i = j + 1; i < n; ++i) {
      const Complex* gi = G.data() + i * G.outerStride();  // column i
      Complex sum = 0;
      for (Eigen::Index k = i; k < n; ++k) sum += std::conj(gi[k]) * gj[k];
      W(i, j) = sum;
    }
  }
}

// W = Gᴴ G for a lower-triangular G (n × n, zeros above the diagonal), written into the n × n W
// (real: both triangles; complex: the lower triangle, by the loops, one rank-k update or row
// panels, for gram_of_lower_factor to mirror). Real, with G = [A 0; B C] (A k × k and C m × m
// lower triangular, B m × k):
//   W = [Aᴴ A + Bᴴ B   (Cᴴ B)ᴴ;  Cᴴ B   Cᴴ C],
// the diagonal blocks by recursion, the rest by products: about n³/3 multiply-adds against n³ for
// the product of the dense matrices, n³/4 once Cᴴ B goes through the triangular product (blocks
// of kTriangularShapeMinSize rows and more).
template <class Scalar>
void gram_of_lower(Eigen::Ref<const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>, 0, Eigen::OuterStride<>> G,
                   Eigen::Ref<Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>, 0, Eigen::OuterStride<>> W) {
  const Eigen::Index n = G.rows();
  if constexpr (!std::is_same_v<Scalar, double>) {
    if (n <= kGramLoopsMaxSize) return gram_of_lower_by_loops(G, W);
    W.template triangularView<Eigen::Lower>().setZero();
    if (n < kGramPanelMinSize) {
      W.template selfadjointView<Eigen::Lower>().rankUpdate(G.adjoint());
      return;
    }
    // Row panel r (rows r … r + w − 1) is zero right of column r + w − 1: it adds its Gram to
    // W's leading (r + w) × (r + w) block only.
    for (Eigen::Index r = 0; r < n; r += kGramPanel) {
      const Eigen::Index w = std::min(kGramPanel, n - r);
      W.topLeftCorner(r + w, r + w).template selfadjointView<Eigen::Lower>().rankUpdate(G.block(r, 0, w, r + w).adjoint());
    }
    return;
  }
  if (n <= kGramBlock) {
    multiply(G.adjoint(), G, W, 1.0, false);
    return;
  }
  const Eigen::Index k = n / 2, m = n - k;
  gram_of_lower<Scalar>(G.topLeftCorner(k, k), W.topLeftCorner(k, k));
  gram_of_lower<Scalar>(G.bottomRightCorner(m, m), W.bottomRightCorner(m, m));
  const auto B = G.bottomLeftCorner(m, k);
  multiply(B.adjoint(), B, W.topLeftCorner(k, k), 1.0, true);                                          // + Bᴴ B
  multiply<Shape::upper>(G.bottomRightCorner(m, m).adjoint(), B, W.bottomLeftCorner(m, k), 1.0, false);  // Cᴴ B
  W.topRightCorner(k, m) = W.bottomLeftCorner(m, k).adjoint();
}

}  // namespace

void gram_of_lower_factor(const Eigen::MatrixXd& G, Eigen::MatrixXd& W) {
  W.resize(G.rows(), G.cols());
  gram_of_lower<double>(G, W);
}

void gram_of_lower_factor(const Eigen::MatrixXcd& G, Eigen::MatrixXcd& W) {
  W.resize(G.rows(), G.cols());
  gram_of_lower<std::complex<double>>(G, W);
  // gram_of_lower writes the lower triangle only (the loops' diagonal real, the rank-k updates'
  // with a rounding-sized imaginary part): W is made Hermitian from it (its readers take either).
  W.diagonal() = W.diagonal().real().cast<std::complex<double>>();
  for_each_entry_below_diagonal(W.rows(), [&W](Eigen::Index i, Eigen::Index j) { W(j, i) = std::conj(W(i, j)); });
}

namespace {

// inverse_by_sweeps at the smallest padded size (4, 8, 12, 16, 24 or 32) that holds A.
template <class Matrix>
bool inverse_by_sweeps_impl(const Matrix& A, double shift, Matrix& W) {
  const Eigen::Index n = A.rows();
  eigen_assert(n <= kSweepInverseMaxSize);
  static_assert(kSweepInverseMaxSize <= 32, "a padded copy larger than P = 32");
  if (n <= 4) return inverse_by_padded_sweeps<4>(A, shift, W);
  if (n <= 8) return inverse_by_padded_sweeps<8>(A, shift, W);
  if (n <= 12) return inverse_by_padded_sweeps<12>(A, shift, W);
  if (n <= 16) return inverse_by_padded_sweeps<16>(A, shift, W);
  if (n <= 24) return inverse_by_padded_sweeps<24>(A, shift, W);
  return inverse_by_padded_sweeps<32>(A, shift, W);
}

}  // namespace

bool inverse_by_sweeps(const Eigen::MatrixXd& A, double shift, Eigen::MatrixXd& W) {
  return inverse_by_sweeps_impl(A, shift, W);
}
bool inverse_by_sweeps(const Eigen::MatrixXcd& A, double shift, Eigen::MatrixXcd& W) {
  return inverse_by_sweeps_impl(A, shift, W);
}

void invert_lower_factor(const Eigen::MatrixXd& L, Eigen::MatrixXd& inverse) {
  inverse.resize(L.rows(), L.cols());
  invert_lower(L, inverse);
}

namespace {

// Complex L⁻¹ (n × n) by panels of kInversePanel columns from the last one up (LAPACK's trtri
// order): with the rows below panel j already inverted (X₂₂ = L₂₂⁻¹, lower triangular), the panel's
// diagonal block is X₁₁ = L₁₁⁻¹ (invert_complex_lower_small) and the block below it X₂₁ = −X₂₂ L₂₁
// X₁₁, two products with a triangular operand. Eigen's complex kernels take them as they are (the
// three-product form's splitting costs more than it saves on panels this narrow).
void invert_lower_by_panels(const Eigen::MatrixXcd& L, Eigen::MatrixXcd& inverse) {
  const Eigen::Index width = kInversePanel;
  const Eigen::Index n = L.rows();
  inverse.setZero();
  Eigen::MatrixXcd product(n, width);  // X₂₂ L₂₁, (rows below the panel) × width
  for (Eigen::Index j = (n - 1) / width * width; j >= 0; j -= width) {
    const Eigen::Index w = std::min(width, n - j), below = n - j - w;
    invert_complex_lower_small(L.block(j, j, w, w), inverse.block(j, j, w, w));
    if (below == 0) continue;
    auto X22_L21 = product.topRows(below);
    X22_L21.noalias() = inverse.block(j + w, j + w, below, below).triangularView<Eigen::Lower>() * L.block(j + w, j, below, w);
    inverse.block(j + w, j, below, w).noalias() = -X22_L21 * inverse.block(j, j, w, w).triangularView<Eigen::Lower>();
  }
}

}  // namespace

void invert_lower_factor(const Eigen::MatrixXcd& L, Eigen::MatrixXcd& inverse) {
  const Eigen::Index n = L.rows();
  inverse.resize(n, n);
  if (n <= kSplitInverseMaxSize) return invert_complex_lower_small(L, inverse);
  invert_lower_by_panels(L, inverse);
}

StepLength::StepLength(int n) : trial_(n, n), trial_factor_(n, n) {}

// The grid's points: the corrector's ratio down to kFineGridFloor (14 points from 1), then
// kPredictorStepRatio a point, kCoarseGridTries of those (the predictor's last point 0.7²⁹ ≈ 3.2e-5,
// the corrector's 0.488·0.7²⁹ ≈ 1.6e-5: a boundary closer than that gives 0, a stalled step). A
// corrector's step below ½ is rare, and 0.95 a point would take 224 tests to reach 1e-5.
constexpr double kFineGridFloor = 0.5;
constexpr int kCoarseGridTries = 30;

template <class FormTrial, class PassesAt, class LowestEstimate>
double StepLength::step(Eigen::Index n, double tau, FormTrial form_trial, PassesAt passes_at,
                        LowestEstimate lowest_estimate, bool factor_next) {
  if (n <= kGridStepMaxSize) return on_grid(tau, form_trial, passes_at, factor_next);
  const double lmin = lowest_estimate();
  const double alpha = lmin < 0 ? std::min(1.0, -tau / lmin) : 1.0;
  if (tau >= 1.0) return alpha;
  return shrink_until_passes(alpha, [&](double a) {
    form_trial(a);
    return positive_definite();
  });
}

template <class FormTrial, class PassesAt>
double StepLength::on_grid(double tau, FormTrial form_trial, PassesAt passes_at, bool factor_next) {
  const bool predictor = tau >= 1.0;
  int coarse_tries = 0;
  for (double alpha = 1.0; coarse_tries < kCoarseGridTries;) {
    // (the corrector keeps P + αΔ itself formed, and with factor_next tested and factored, for
    // take_tested)
    if (passes_at(alpha / tau) && (predictor || (form_trial(alpha), !factor_next || positive_definite()))) return alpha;
    const bool fine = !predictor && alpha > kFineGridFloor;
    alpha *= fine ? kCorrectorStepRatio : kPredictorStepRatio;
    if (!fine) ++coarse_tries;
  }
  return 0.0;
}

double StepLength::full(const Eigen::MatrixXd& P, const Eigen::MatrixXd& L, const Eigen::MatrixXd& inverse,
                        const Eigen::MatrixXd& delta, double tau, bool factor_next) {
  if (!delta.allFinite()) return 0.0;
  return step(
      P.rows(), tau, [&](double a) { trial_ = P + a * delta; },
      [&](double a) { return sum_passes_cholesky_test(P, a, delta); },
      [&] {
        return lanczos_min_eig(L, inverse, tau,
                               [&](const Eigen::VectorXd& u, Eigen::VectorXd& w) { w.noalias() = delta * u; });
      },
      factor_next);
}

double StepLength::block_diagonal(const Eigen::MatrixXd& P, const Eigen::MatrixXd& L, const Eigen::MatrixXd& inverse,
                                  const Eigen::MatrixXd& D, int d, double tau, bool factor_next) {
  const Eigen::Index n = P.rows();
  if (!D.allFinite()) return 0.0;
  const auto form_trial = [&](double a) {  // trial_ = P + a Δ, Δ added blockwise
    trial_ = P;
    for (Eigen::Index i = 0; i < n; i += d) trial_.block(i, i, d, d) += a * D.middleRows(i, d).leftCols(d);
  };
  const auto passes_at = [&](double a) { return block_sum_passes_cholesky_test(P, a, D, d); };
  return step(n, tau, form_trial, passes_at, [&] {
    return lanczos_min_eig(L, inverse, tau, [&](const Eigen::VectorXd& u, Eigen::VectorXd& w) {
      w.resize(n);  // Δ u block by block
      for (Eigen::Index i = 0; i < n; i += d) w.segment(i, d).noalias() = D.middleRows(i, d).leftCols(d) * u.segment(i, d);
    });
  }, factor_next);
}

namespace {

// The padded kernels below read an n × n symmetric A by its columns: column(j) returns a function
// whose value at i is A(i, j), for 0 ≤ i < n (only the lower triangle's, j ≤ i, decide), so that a
// sum such as P + aΔ is formed in the kernel's own copy rather than into an n × n matrix first. They
// factor A = W D⁻¹ Wᵀ (LDLᵀ with W = L D, no square roots in the chain from one pivot to the
// next) on a P × P zero-padded copy on the stack (n ≤ P, P a multiple of 8, leading dimension P),
// every update over whole 8-row blocks from the block that holds the column's diagonal; A is
// positive definite when every pivot d_j is positive (and finite: usable_pivot).

// A's Cholesky factor from W and 1/d into the lower triangle of L (n × n): column j of W scaled
// by 1/√d_j, computed after the last pivot, off the chain from pivot to pivot.
template <int P>
void scale_out_factor(int n, const double* l, const double* reciprocal, Eigen::MatrixXd& L) {
  for (int j = 0; j < n; ++j) {
    const double* w = l + j * P;
    const double scale = std::sqrt(reciprocal[j]);  // 1/√d_j
    double* __restrict out = &L(0, j);
    for (int i = j; i < n; ++i) out[i] = w[i] * scale;
  }
}

// Column j of the padded copy, rows j & ~7 … P − 1: A's entries from row j to n − 1, zeros elsewhere.
template <int P, class Entry>
void load_padded_column(int n, int j, Entry entry, double* __restrict c) {
  for (int i = j & ~7; i < P; ++i) c[i] = i >= j && i < n ? entry(i) : 0.0;
}

// Right-looking: the whole copy first, then each pivot's rank-1 update of the columns after it.
// A test (L null) copies whole columns, so column(j)'s function is also called above the
// diagonal; those entries reach only rows above the diagonal, never a pivot. With L given, A's
// Cholesky factor goes to its lower triangle on success. A test that fails at pivot k has updated
// every column k times, where a left-looking one has formed only k columns; against the
// left-looking kernel (P ≤ 32, positive definite or failing at the last pivot: n = 8 / 12 / 16 /
// 24 / 32 61 / 115 / 165 / 297 / 523 ns against 123 / 173 / 274 / 440 / 711; failing at the middle
// pivot, n = 24 218 against 160; BENCHMARKS.md, session 52). The grid's first tests mostly pass or
// fail near the boundary, at the last pivots.
template <int P, class Column>
bool padded_right_ldlt(int n, Column column, Eigen::MatrixXd* L) {
  alignas(64) double l[P * P];
  alignas(64) double reciprocal[P];  // 1/d_k
  for (int j = 0; j < n; ++j) {
    if (L) {  // (cholesky_lower reads A's lower triangle only: whole columns took random C of rank 3
              // at N = 5 4 % longer, whatever its callers leave above the diagonal)
      load_padded_column<P>(n, j, column(j), l + j * P);
    } else {  // the grid's P and Δ, whole columns (faster than from row j & ~7: N = 8 … 16 0.96–0.97)
      const auto entry = column(j);
      double* __restrict c = l + j * P;
      for (int i = 0; i < P; ++i) c[i] = i < n ? entry(i) : 0.0;
    }
  }
  for (int k = 0; k < n; ++k) {
    const double* w = l + k * P;  // W's column k
    const double pivot = w[k];
    if (!usable_pivot(pivot)) return false;
    reciprocal[k] = 1.0 / pivot;
    for (int j = k + 1; j < n; ++j) {
      double* __restrict c = l + j * P;
      const double x = w[j] * reciprocal[k];  // L(j, k)
      for (int i = j & ~7; i < P; ++i) c[i] -= w[i] * x;
    }
  }
  if (L) scale_out_factor<P>(n, l, reciprocal, *L);
  return true;
}

// Left-looking: column j is A's, less its multiples of W's finished columns, four at a time, so
// columns are formed only as they are reached and a test that fails at pivot k has read k
// columns. With L given, A's Cholesky factor goes to its lower triangle on success (column j of
// W scaled by 1/√d_j, after the last pivot, off the chain). Against the LLᵀ kernel it replaced
// (n = 24 / 36 / 48, positive definite: 550 / 947 / 1477 ns; failing at the middle pivot 211 /
// 395 / 573): 440 / 787 / 1297 and 160 / 300 / 460 ns (BENCHMARKS.md, session 52).
template <int P, class Column>
bool padded_left_ldlt(int n, Column column, Eigen::MatrixXd* L) {
  alignas(64) double l[P * P];
  alignas(64) double reciprocal[P];  // 1/d_k
  for (int j = 0; j < n; ++j) {
    double* __restrict c = l + j * P;
    const int from = j & ~7;
    load_padded_column<P>(n, j, column(j), c);
    int k = 0;
    for (; k + 3 < j; k += 4) {
      const double *w0 = l + k * P, *w1 = w0 + P, *w2 = w1 + P, *w3 = w2 + P;
      const double x0 = w0[j] * reciprocal[k], x1 = w1[j] * reciprocal[k + 1], x2 = w2[j] * reciprocal[k + 2],
                   x3 = w3[j] * reciprocal[k + 3];
      for (int i = from; i < P; ++i) c[i] -= w0[i] * x0 + w1[i] * x1 + w2[i] * x2 + w3[i] * x3;
    }
    for (; k < j; ++k) {
      const double* w0 = l + k * P;
      const double x0 = w0[j] * reciprocal[k];
      for (int i = from; i < P; ++i) c[i] -= w0[i] * x0;
    }
    const double pivot = c[j];
    if (!usable_pivot(pivot)) return false;
    reciprocal[j] = 1.0 / pivot;
    for (int i = from; i < j; ++i) c[i] = 0.0;  // (above the diagonal: the later columns' updates
                                                // read these rows only into their own rows above it)
  }
  if (L) scale_out_factor<P>(n, l, reciprocal, *L);
  return true;
}

// The padded kernel for n ≤ 48 rows, at the smallest padded size that holds n: right-looking up
// to kRightLdltMaxSize rows, left-looking above, where its early failures save more (n = 36 / 48:
// 756 / 1348 ns right-looking against 787 / 1297 when positive definite, 582 / 1054 against 300 /
// 460 failing at the middle pivot; BENCHMARKS.md, session 52). The grid's tests (L null) and
// cholesky_lower (the factor into L).
constexpr int kRightLdltMaxSize = 32;
template <class Column>
bool padded_ldlt(Eigen::Index n, Column column, Eigen::MatrixXd* L) {
  static_assert(kGridStepMaxSize <= 48 && kPaddedCholeskyMaxSize <= 48, "a padded copy larger than P = 48");
  eigen_assert(n <= 48);
  const int size = static_cast<int>(n);
  if (n <= 8) return padded_right_ldlt<8>(size, column, L);
  if (n <= 16) return padded_right_ldlt<16>(size, column, L);
  if (n <= 24) return padded_right_ldlt<24>(size, column, L);
  if (n <= kRightLdltMaxSize) return padded_right_ldlt<32>(size, column, L);
  if (n <= 40) return padded_left_ldlt<40>(size, column, L);
  return padded_left_ldlt<48>(size, column, L);
}

bool padded_cholesky(const Eigen::MatrixXd& A, Eigen::MatrixXd& L) {
  return padded_ldlt(A.rows(), [&](int j) { return [a = &A(0, j)](int i) { return a[i]; }; }, &L);
}

}  // namespace

bool sum_passes_cholesky_test(const Eigen::MatrixXd& P, double a, const Eigen::MatrixXd& delta) {
  return padded_ldlt(P.rows(), [&](int j) {
    return [p = &P(0, j), e = &delta(0, j), a](int i) { return p[i] + a * e[i]; };
  }, nullptr);
}

bool block_sum_passes_cholesky_test(const Eigen::MatrixXd& P, double a, const Eigen::MatrixXd& D, int d) {
  return padded_ldlt(P.rows(), [&](int j) {
    const int block_end = (j / d + 1) * d;  // rows j … block_end − 1 of column j lie in Δ's block
    return [p = &P(0, j), e = &D(0, j % d), a, block_end](int i) { return i < block_end ? p[i] + a * e[i] : p[i]; };
  }, nullptr);
}

bool factor_lower(const Eigen::MatrixXd& A, Eigen::MatrixXd& L) {
  if (A.rows() <= kGridStepMaxSize) return cholesky_lower(A, L);
  L = A;
  return cholesky_in_place(L);
}

bool StepLength::positive_definite() { return factor_lower(trial_, trial_factor_); }

void StepLength::take_tested(Eigen::MatrixXd& next, Eigen::MatrixXd& next_factor) {
  next.swap(trial_);
  next_factor.swap(trial_factor_);
}

void StepLength::take_trial(Eigen::MatrixXd& next) { next.swap(trial_); }

}  // namespace fact::sdp::detail
