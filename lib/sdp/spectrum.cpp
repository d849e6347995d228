// Eigenvalues, for the certificates (S = C − Λ, real n × n, or S = H − diag μ, complex N × N) and
// the Lanczos matrices' lowest eigenvalue (step_length.cpp's estimates): Householder reduction to a
// real symmetric tridiagonal matrix, then the root-free QL iteration of Pal, Walker and Kahan
// (EISPACK's tqlrat) on the squares of its off-diagonal. Eigen's SelfAdjointEigenSolver spent 1–3
// µs of an 8-drone solve's 14 µs in its tridiagonal QR, whose Givens rotations take a square root
// each (BENCHMARKS.md, session 17). The few eigenvectors the staircases need (their spectral start
// and their escapes from saddles) come from inverse iteration on the tridiagonal matrix at those
// eigenvalues, carried back through the stored reflectors, instead of a full decomposition with
// vectors.
#include <cmath>
#include <complex>
#include <limits>
#include <vector>

#include "internal.h"

namespace fact::sdp::detail {
namespace {

double conj_of(double x) { return x; }
std::complex<double> conj_of(const std::complex<double>& x) { return std::conj(x); }

// |x| by √(|x|²) where |x|² can neither underflow nor overflow, by std::abs (libm's hypot for a
// complex x, 20–40 ns a call: 1.2 % of a tight N = 6 solve, whose reductions take n − 1 each)
// elsewhere.
double magnitude(double x) { return std::abs(x); }
double magnitude(const std::complex<double>& x) {
  const double square = std::norm(x);
  return square > 1e-280 && square < 1e280 ? std::sqrt(square) : std::abs(x);
}

// A column below the diagonal whose norm is at most this is reflected with its Householder vector
// on the unit scale: v = x + phase‖x‖e₁ itself would make τ = 2/‖v‖² overflow once ‖x‖² underflows
// (entries near 1e-160 in an O(1) matrix gave τ = ∞ and NaN eigenvalues; review, session 28).
constexpr double kTinyColumn = 1e-100;

// The reflectors of a reduction, for eigenvectors: step k's H_k = I − τ_k v vᴴ acts on entries
// k + 1 … n − 1 with v stored in column k of the reduced A below the diagonal, and the reduced
// matrix's subdiagonal entry (k + 1, k) is beta_k (complex for complex A; the tridiagonal matrix
// with |beta_k| is the same one up to a diagonal unitary similarity).
template <class Scalar>
struct Reflectors {
  std::vector<double> tau;   // n − 2, real (0: no reflection at that step)
  std::vector<Scalar> beta;  // n − 1
};

// Householder reduction of the self-adjoint A (n × n, lower triangle used; destroyed) to the real
// symmetric tridiagonal matrix with the same eigenvalues: diagonal (n) and subdiagonal (n − 1;
// only its entries' magnitudes are defined). scratch is 2n. Step k reflects the column below the
// diagonal, x (m = n − k − 1 entries), onto −phase(x₀)‖x‖e₁ with H = I − τ v vᴴ,
// v = x + phase(x₀)‖x‖e₁ (x/‖x‖ + phase(x₀)e₁ when ‖x‖ ≤ kTinyColumn, τ = 2/‖v‖² either way), and
// updates the trailing m × m block A₂₂ ← H A₂₂ H = A₂₂ − v wᴴ − w vᴴ with
// w = τ A₂₂ v − (τ² vᴴA₂₂v / 2) v. With `kept`, v overwrites x and τ, beta are recorded.
template <class Matrix, class Vector>
void tridiagonalize_impl(Matrix& A, Eigen::VectorXd& diagonal, Eigen::VectorXd& subdiagonal, Vector& scratch,
                         Reflectors<typename Matrix::Scalar>* kept = nullptr) {
  using Scalar = typename Matrix::Scalar;
  const Eigen::Index n = A.rows(), lda = A.outerStride();
  Scalar* v = scratch.data();      // Householder vector, m
  Scalar* w = scratch.data() + n;  // w above, m
  for (Eigen::Index k = 0; k + 2 < n; ++k) {
    const Eigen::Index m = n - k - 1;  // size of the trailing block
    Scalar* x = &A(k + 1, k);          // the column below the diagonal
    double tail = 0;
    for (Eigen::Index i = 1; i < m; ++i) tail += std::norm(x[i]);
    diagonal[k] = std::real(A(k, k));
    if (tail == 0) {  // already tridiagonal in this column
      subdiagonal[k] = magnitude(x[0]);
      if (kept) {
        kept->tau[k] = 0;
        kept->beta[k] = x[0];
      }
      continue;
    }
    const double norm = std::sqrt(std::norm(x[0]) + tail), size0 = magnitude(x[0]);
    const Scalar phase = size0 > 0 ? x[0] / size0 : Scalar(-1);
    subdiagonal[k] = norm;
    std::copy(x, x + m, v);
    double tau;
    if (norm > kTinyColumn) {
      v[0] += phase * norm;
      tau = 2.0 / (std::norm(v[0]) + tail);
    } else {  // v on the unit scale, x/‖x‖ + phase·e₁ (H depends only on v's direction)
      double length2 = 0;  // ‖v‖²
      for (Eigen::Index i = 0; i < m; ++i) v[i] *= 1.0 / norm;
      v[0] += phase;
      for (Eigen::Index i = 0; i < m; ++i) length2 += std::norm(v[i]);
      tau = 2.0 / length2;
    }
    if (kept) {
      kept->tau[k] = tau;
      kept->beta[k] = -phase * norm;  // H x = −phase(x₀)‖x‖e₁
      std::copy(v, v + m, x);
    }
    Scalar* a22 = &A(k + 1, k + 1);
    for (Eigen::Index i = 0; i < m; ++i) w[i] = 0;
    for (Eigen::Index j = 0; j < m; ++j) {  // w = τ A₂₂ v, one pass over the lower triangle
      const Scalar* __restrict col = a22 + j * lda;
      const Scalar vj = tau * v[j];
      Scalar dot = 0;
      w[j] += std::real(col[j]) * vj;
      for (Eigen::Index i = j + 1; i < m; ++i) {
        w[i] += col[i] * vj;
        dot += conj_of(col[i]) * v[i];
      }
      w[j] += tau * dot;
    }
    double vw = 0;  // Re vᴴ w (real: A₂₂ is self-adjoint)
    for (Eigen::Index i = 0; i < m; ++i) vw += std::real(conj_of(v[i]) * w[i]);
    const double half = 0.5 * tau * vw;
    for (Eigen::Index i = 0; i < m; ++i) w[i] -= half * v[i];
    for (Eigen::Index j = 0; j < m; ++j) {  // A₂₂ −= v wᴴ + w vᴴ on the lower triangle
      Scalar* __restrict col = a22 + j * lda;
      const Scalar vj = conj_of(v[j]), wj = conj_of(w[j]);
      for (Eigen::Index i = j; i < m; ++i) col[i] -= v[i] * wj + w[i] * vj;
    }
  }
  if (n >= 2) {
    diagonal[n - 2] = std::real(A(n - 2, n - 2));
    subdiagonal[n - 2] = magnitude(A(n - 1, n - 2));
    if (kept) kept->beta[n - 2] = A(n - 1, n - 2);
  }
  diagonal[n - 1] = std::real(A(n - 1, n - 1));
}

// The real reduction for n ≤ kPaddedMaxSize on a P × P copy of A whose size is fixed at compile
// time (P ≥ n, a multiple of 4 from 8 on), both triangles filled from A's lower one: every column
// operation is then a whole P-vector, which the compiler vectorises without remainder loops or
// alias checks. The Householder vector v is zero outside the rows k + 1 … n − 1 it acts on, so
// the full-length updates leave values in the rows above that are never read again (each such row
// is only multiplied by the reflection) and that do not enter vᵀw, and the padding rows stay
// zero. The same steps and reflector convention as tridiagonalize_impl, the same result to
// rounding; n = 16 / 24 / 32 / 48: 1.23 / 3.46 / 5.36 / 12.9 µs → 0.83 / 1.66 / 2.73 / 5.99 µs
// (BENCHMARKS.md, session 28).
template <int P>
void tridiagonalize_padded(const Eigen::MatrixXd& original, Eigen::VectorXd& diagonal, Eigen::VectorXd& subdiagonal) {
  using Column = Eigen::Matrix<double, P, 1>;
  const int n = static_cast<int>(original.rows());
  Eigen::Matrix<double, P, P> A;  // A in the leading n × n block (both triangles), zero elsewhere
  A.setZero();
  A.topLeftCorner(n, n) = original.selfadjointView<Eigen::Lower>();
  Column v, w;  // Householder vector and τ A₂₂ v − (τ² vᵀA₂₂v / 2) v on rows k + 1 … n − 1
  for (int k = 0; k + 2 < n; ++k) {
    v = A.col(k);  // the column below the diagonal, x (rows ≥ n are zero)
    const double x0 = v[k + 1];
    for (int i = 0; i <= k + 1; ++i) v[i] = 0;
    const double tail = v.squaredNorm();  // Σ x_i² below x₀
    v[k + 1] = x0;
    diagonal[k] = A(k, k);
    if (tail == 0) {  // already tridiagonal in this column
      subdiagonal[k] = std::abs(x0);
      continue;
    }
    const double norm = std::sqrt(x0 * x0 + tail);
    subdiagonal[k] = norm;
    double tau;
    if (norm > kTinyColumn) {
      v[k + 1] += (x0 > 0 ? norm : -norm);
      tau = 2.0 / (v[k + 1] * v[k + 1] + tail);
    } else {  // on the unit scale, as in tridiagonalize_impl
      v *= 1.0 / norm;
      v[k + 1] += (x0 > 0 ? 1.0 : -1.0);
      tau = 2.0 / v.squaredNorm();
    }
    w.setZero();
    for (int j = k + 1; j < n; ++j) w += A.col(j) * (tau * v[j]);  // τ A₂₂ v (+ unread rows above)
    w -= (0.5 * tau * v.dot(w)) * v;
    for (int j = k + 1; j < n; ++j) A.col(j) -= v * w[j] + w * v[j];  // A₂₂ −= v wᵀ + w vᵀ
  }
  if (n >= 2) {
    diagonal[n - 2] = A(n - 2, n - 2);
    subdiagonal[n - 2] = magnitude(A(n - 1, n - 2));
  }
  diagonal[n - 1] = A(n - 1, n - 1);
}

// Largest n reduced by tridiagonalize_padded: the certificates' matrices up to 64 rows (random low
// rank N = 25 … 32: 0.93–0.94 of the time; session 28, when the exact step lengths' matrices, n ≤
// 48, were reduced here too).
constexpr Eigen::Index kPaddedMaxSize = 64;

// tridiagonalize_padded at the smallest padded size that holds A (n × n, 3 ≤ n ≤ kPaddedMaxSize).
void tridiagonalize_small(const Eigen::MatrixXd& A, Eigen::VectorXd& diagonal, Eigen::VectorXd& subdiagonal) {
  const Eigen::Index n = A.rows();
  if (n <= 8) return tridiagonalize_padded<8>(A, diagonal, subdiagonal);
  if (n <= 12) return tridiagonalize_padded<12>(A, diagonal, subdiagonal);
  if (n <= 16) return tridiagonalize_padded<16>(A, diagonal, subdiagonal);
  if (n <= 20) return tridiagonalize_padded<20>(A, diagonal, subdiagonal);
  if (n <= 24) return tridiagonalize_padded<24>(A, diagonal, subdiagonal);
  if (n <= 32) return tridiagonalize_padded<32>(A, diagonal, subdiagonal);
  if (n <= 40) return tridiagonalize_padded<40>(A, diagonal, subdiagonal);
  if (n <= 48) return tridiagonalize_padded<48>(A, diagonal, subdiagonal);
  if (n <= 56) return tridiagonalize_padded<56>(A, diagonal, subdiagonal);
  return tridiagonalize_padded<64>(A, diagonal, subdiagonal);
}

// The reduction without reflectors: padded for real A with 3 ≤ n ≤ kPaddedMaxSize, in place
// otherwise.
void tridiagonal_form(Eigen::MatrixXd& A, Eigen::VectorXd& diagonal, Eigen::VectorXd& subdiagonal,
                      Eigen::VectorXd& scratch) {
  if (A.rows() >= 3 && A.rows() <= kPaddedMaxSize) return tridiagonalize_small(A, diagonal, subdiagonal);
  tridiagonalize_impl(A, diagonal, subdiagonal, scratch);
}
void tridiagonal_form(Eigen::MatrixXcd& A, Eigen::VectorXd& diagonal, Eigen::VectorXd& subdiagonal,
                      Eigen::VectorXcd& scratch) {
  tridiagonalize_impl(A, diagonal, subdiagonal, scratch);
}

// The smallest pivot solve_shifted_tridiagonal divides by (T scaled to ‖T‖ = 1): growth of at most
// 1e30 a solve keeps the iterate's squared norm in range.
constexpr double kPivotFloor = 1e-30;

// T − σI = P L U for the real symmetric tridiagonal T with diagonal a (n) and off-diagonal e
// (n − 1), by Gaussian elimination with partial pivoting (row i and i + 1 swapped when the
// subdiagonal entry is larger), kept for several solves; a pivot of 0 (σ an eigenvalue to the last
// bit) is replaced by `tiny`, which only scales a solution.
struct ShiftedTridiagonalLU {
  explicit ShiftedTridiagonalLU(Eigen::Index n)
      : inverse_pivot(n), u1(n), u2(n), factor(std::max<Eigen::Index>(n - 1, 0)),
        swapped(static_cast<std::size_t>(std::max<Eigen::Index>(n - 1, 0))) {}
  Eigen::VectorXd inverse_pivot;  // 1 / U's diagonal (each at least kPivotFloor in magnitude), n
  Eigen::VectorXd u1, u2;         // U's two superdiagonals, n (the last entries unused)
  Eigen::VectorXd factor;         // the multiplier that eliminates row i + 1's entry in column i, n − 1
  std::vector<char> swapped;      // rows i and i + 1 swapped before that elimination, n − 1
};

void factor_shifted_tridiagonal(const Eigen::VectorXd& a, const Eigen::VectorXd& e, double sigma, double tiny,
                                ShiftedTridiagonalLU& lu) {
  const Eigen::Index n = a.size();
  Eigen::VectorXd& u0 = lu.inverse_pivot;  // U's diagonal, inverted at the end
  for (Eigen::Index i = 0; i < n; ++i) u0[i] = a[i] - sigma;
  for (Eigen::Index i = 0; i + 1 < n; ++i) lu.u1[i] = e[i];
  double below = n > 1 ? e[0] : 0.0;  // the entry of row i + 1 in column i, still to eliminate
  for (Eigen::Index i = 0; i + 1 < n; ++i) {
    const double next_super = i + 2 < n ? e[i + 1] : 0.0;  // row i + 1's entry in column i + 2
    const std::size_t at = static_cast<std::size_t>(i);
    if (std::abs(u0[i]) >= std::abs(below)) {
      if (u0[i] == 0) u0[i] = tiny;
      lu.factor[i] = below / u0[i];
      u0[i + 1] -= lu.factor[i] * lu.u1[i];
      lu.u2[i] = 0;
      lu.swapped[at] = 0;
    } else {  // swap rows i and i + 1
      lu.factor[i] = u0[i] / below;
      u0[i] = below;
      const double diagonal_next = u0[i + 1];
      u0[i + 1] = lu.u1[i] - lu.factor[i] * diagonal_next;
      lu.u1[i] = diagonal_next;
      lu.u2[i] = next_super;
      if (i + 2 < n) lu.u1[i + 1] = -lu.factor[i] * next_super;
      lu.swapped[at] = 1;
    }
    below = i + 2 < n ? e[i + 1] : 0.0;
  }
  if (n > 0 && u0[n - 1] == 0) u0[n - 1] = tiny;
  // A pivot below kPivotFloor counts as kPivotFloor: an eigenvalue split off by a coupling of
  // 1e-80 … 1e-150 left a pivot that small after a row swap, and the iterate grew until its norm
  // overflowed and normalised to zero (review, session 28). The usual last pivot, ε-sized against
  // ‖T‖ = 1, is far above the floor, so results elsewhere do not change.
  for (Eigen::Index i = 0; i < n; ++i)
    u0[i] = 1.0 / (std::abs(u0[i]) < kPivotFloor ? std::copysign(kPivotFloor, u0[i]) : u0[i]);
}

// Solves (T − σI) x = b in place (b becomes x, n) with factor_shifted_tridiagonal's lu.
void solve_shifted_tridiagonal(const ShiftedTridiagonalLU& lu, Eigen::VectorXd& b) {
  const Eigen::Index n = b.size();
  for (Eigen::Index i = 0; i + 1 < n; ++i) {
    if (lu.swapped[static_cast<std::size_t>(i)]) std::swap(b[i], b[i + 1]);
    b[i + 1] -= lu.factor[i] * b[i];
  }
  for (Eigen::Index i = n - 1; i >= 0; --i) {
    double value = b[i];
    if (i + 1 < n) value -= lu.u1[i] * b[i + 1];
    if (i + 2 < n) value -= lu.u2[i] * b[i + 2];
    b[i] = value * lu.inverse_pivot[i];
  }
}

// A = original, divided by its largest |entry| when that is outside [1e-100, 1e100] (the root-free
// QL squares the off-diagonal, which would underflow or overflow; the solver's scaled S is never
// there, and it is copied unchanged); returns the factor the eigenvalues of A are to be multiplied by.
template <class Matrix>
double copy_in_range(const Matrix& original, Matrix& A) {
  const double largest2 = original.cwiseAbs2().maxCoeff();  // no square roots on the usual path
  if (largest2 >= 1e-200 && largest2 <= 1e200) {
    A = original;
    return 1.0;
  }
  const double largest = original.cwiseAbs().maxCoeff();
  if (largest == 0 || !std::isfinite(largest)) {
    A = original;
    return 1.0;
  }
  A = original / largest;
  return largest;
}

template <class Matrix>
Eigen::VectorXd eigenvalues_impl(const Matrix& original) {
  const Eigen::Index n = original.rows();
  // (the QL iteration turns a NaN into finite values: a certificate must not look valid)
  if (!original.allFinite()) return Eigen::VectorXd::Constant(n, std::numeric_limits<double>::quiet_NaN());
  Matrix A;  // n × n, A's copy in range (the in-place reduction, n > 64 or complex, destroys it)
  const double unit = copy_in_range(original, A);
  Eigen::VectorXd diagonal(n), subdiagonal(std::max<Eigen::Index>(n, 1));  // one spare entry for tqlrat
  Eigen::Matrix<typename Matrix::Scalar, Eigen::Dynamic, 1> scratch(2 * n);
  tridiagonal_form(A, diagonal, subdiagonal, scratch);
  Eigen::VectorXd squares = subdiagonal.cwiseAbs2();  // n (the last entry is tqlrat's zero)
  if (tridiagonal_eigenvalues(diagonal, squares)) return unit * diagonal;
  // 30 QL sweeps without convergence on one eigenvalue (not seen in tests): Eigen's QR.
  return Eigen::SelfAdjointEigenSolver<Matrix>(original, Eigen::EigenvaluesOnly).eigenvalues();
}

}  // namespace

void tridiagonalize(Eigen::MatrixXd& A, Eigen::VectorXd& diagonal, Eigen::VectorXd& subdiagonal, Eigen::VectorXd& scratch) {
  tridiagonal_form(A, diagonal, subdiagonal, scratch);
}

bool tridiagonal_eigenvalues(Eigen::VectorXd& d, Eigen::VectorXd& e2) {
  const Eigen::Index n = d.size();
  if (n <= 1) return true;
  e2[n - 1] = 0;  // stops the search for a negligible off-diagonal entry
  double shifted = 0, norm = 0, b = 0, c = 0;  // total shift; running bound on ‖T‖, ε·it and its square
  for (Eigen::Index l = 0; l < n; ++l) {
    double h = std::abs(d[l]) + std::sqrt(e2[l]);
    if (norm <= h) {
      norm = h;
      b = std::numeric_limits<double>::epsilon() * norm;
      c = b * b;
    }
    Eigen::Index m = l;  // the first negligible squared off-diagonal entry from l on
    while (e2[m] > c) ++m;
    for (int sweep = 0; m != l; ++sweep) {  // until e2[l] is negligible (a break)
      if (sweep == 30) return false;
      // Shift by the eigenvalue of the leading 2 × 2 block nearer to d[l].
      double s = std::sqrt(e2[l]), g = d[l];
      double p = (d[l + 1] - g) / (2.0 * s);
      // √(p² + 1) without libm's hypot (20–40 ns a call, a sixth of tqlrat at n = 5); p² cannot
      // overflow below 1e150, and above it √(p² + 1) = |p| in double.
      double r = std::abs(p) < 1e150 ? std::sqrt(p * p + 1.0) : std::abs(p);
      d[l] = s / (p + std::copysign(r, p));
      h = g - d[l];
      for (Eigen::Index i = l + 1; i < n; ++i) d[i] -= h;
      shifted += h;
      // Rational QL transformation from m − 1 up to l.
      g = d[m] != 0 ? d[m] : b;
      h = g;
      s = 0;
      for (Eigen::Index i = m - 1; i >= l; --i) {
        p = g * h;
        r = p + e2[i];
        e2[i + 1] = s * r;
        s = e2[i] / r;
        d[i + 1] = h + s * (h + d[i]);
        g = d[i] - e2[i] / g;
        if (g == 0) g = b;
        h = g * p / r;
      }
      e2[l] = s * g;
      d[l] = h;
      if (h == 0 || std::abs(e2[l]) <= std::abs(c / h)) break;  // converged (guarded against underflow)
      e2[l] = h * e2[l];
      if (e2[l] == 0) break;
    }
    const double eigenvalue = d[l] + shifted;  // inserted in order among the l found so far
    Eigen::Index i = l;
    for (; i > 0 && eigenvalue < d[i - 1]; --i) d[i] = d[i - 1];
    d[i] = eigenvalue;
  }
  return true;
}

Eigen::VectorXd eigenvalues_of(const Eigen::MatrixXd& A) { return eigenvalues_impl(A); }
Eigen::VectorXd eigenvalues_of(const Eigen::MatrixXcd& A) { return eigenvalues_impl(A); }

namespace {

// Inverse iterations per eigenvector. From the QL eigenvalue (accurate to ε‖T‖) one iteration
// already gives the vector to rounding unless the start is nearly orthogonal to it; the others
// are O(n) each, on one factorisation of T − σI.
constexpr int kInverseIterations = 3;

// Unit eigenvector of T (diagonal a, off-diagonal e) for the eigenvalue sigma, orthogonal to the
// columns 0 … j − 1 of found (n × k, the vectors of lower eigenvalues), into found.col(j); u (n)
// and lu are work space. The start is generic_start_entry's vector j.
void tridiagonal_eigenvector(const Eigen::VectorXd& a, const Eigen::VectorXd& e, double sigma, double tiny, int j,
                             Eigen::MatrixXd& found, Eigen::VectorXd& u, ShiftedTridiagonalLU& lu) {
  const Eigen::Index n = a.size();
  for (Eigen::Index i = 0; i < n; ++i) u[i] = generic_start_entry(i, j);
  const auto unit = [](Eigen::VectorXd& x) {  // (scaled first only if the squared norm overflows)
    if (std::isfinite(x.squaredNorm())) x.normalize(); else x.stableNormalize();
  };
  factor_shifted_tridiagonal(a, e, sigma, tiny, lu);
  for (int step = 0; step < kInverseIterations; ++step) {
    unit(u);
    solve_shifted_tridiagonal(lu, u);
    for (int pass = 0; pass < 2; ++pass)
      for (int i = 0; i < j; ++i) u -= found.col(i).dot(u) * found.col(i);
  }
  unit(u);
  found.col(j) = u;
}

template <class Matrix>
void lowest_eigenpairs_impl(const Matrix& original, int k, Eigen::VectorXd& eigenvalues, Matrix& vectors,
                            bool spectrum = true, double below = std::numeric_limits<double>::infinity()) {
  using Scalar = typename Matrix::Scalar;
  const Eigen::Index n = original.rows();
  if (!original.allFinite()) {  // as eigenvalues_impl: a NaN spectrum, never a finite-looking one
    eigenvalues = Eigen::VectorXd::Constant(n, std::numeric_limits<double>::quiet_NaN());
    vectors = Matrix::Constant(n, k, std::numeric_limits<double>::quiet_NaN());
    return;
  }
  Matrix A;  // n × n: A's copy in range, reduced in place, the reflectors' v below its diagonal
  const double unit = copy_in_range(original, A);
  Eigen::VectorXd diagonal(n), subdiagonal(std::max<Eigen::Index>(n, 1));  // of T, one spare entry for tqlrat
  Eigen::Matrix<Scalar, Eigen::Dynamic, 1> scratch(2 * n);
  Reflectors<Scalar> kept{std::vector<double>(std::max<Eigen::Index>(n - 2, 0)),
                          std::vector<Scalar>(std::max<Eigen::Index>(n - 1, 0))};
  tridiagonalize_impl(A, diagonal, subdiagonal, scratch, &kept);
  const int asked = k;       // (k itself becomes the count of vectors found below)
  const auto wanted = [&] {  // of the `asked` smallest eigenvalues, those below `below`, at least one
    const Eigen::Index below_count = (eigenvalues.head(asked).array() < below).count();
    return static_cast<int>(std::min<Eigen::Index>(asked, std::max<Eigen::Index>(1, below_count)));
  };
  const auto from_eigen = [&] {  // Eigen's decomposition, as eigenvalues_impl's fallback
    const Eigen::SelfAdjointEigenSolver<Matrix> eig(original);
    eigenvalues = eig.eigenvalues();
    vectors = eig.eigenvectors().leftCols(wanted());
  };
  double norm;  // ‖T‖₂ = ‖A‖₂ / unit, or a Gershgorin bound on it
  const Eigen::VectorXd off_diagonal = subdiagonal.head(std::max<Eigen::Index>(n - 1, 0));  // |beta|, n − 1
  if (spectrum || k > 1) {
    eigenvalues = diagonal;
    Eigen::VectorXd squares = subdiagonal.cwiseAbs2();
    if (!tridiagonal_eigenvalues(eigenvalues, squares)) return from_eigen();
    norm = eigenvalues.cwiseAbs().maxCoeff();
  } else {  // one vector and no spectrum: λ_min alone by Laguerre's iteration (lowest_vector)
    const double lowest = lowest_tridiagonal_eigenvalue(diagonal, off_diagonal);
    if (!std::isfinite(lowest)) return from_eigen();
    eigenvalues = Eigen::VectorXd::Constant(1, lowest);
    norm = gershgorin_bounds(diagonal, off_diagonal).radius();
  }
  eigenvalues *= unit;
  k = wanted();
  if (norm == 0) {  // A = 0: every vector is an eigenvector
    vectors = Matrix::Identity(n, k);
    return;
  }
  // The inverse iteration runs on T/‖T‖, so that a zero pivot's stand-in ε and the growth of the
  // iterate (up to 1/ε) stay in range whatever A's scale is.
  const Eigen::VectorXd a = diagonal / norm;        // n
  const Eigen::VectorXd off = off_diagonal / norm;  // |beta| / ‖T‖, n − 1
  const double eps = std::numeric_limits<double>::epsilon();
  Eigen::MatrixXd found(n, k);  // eigenvectors of T, n × k
  Eigen::VectorXd iterate(n);   // tridiagonal_eigenvector's work space
  ShiftedTridiagonalLU lu(n);
  double sigma = 0;             // shift, in units of ‖T‖
  for (int j = 0; j < k; ++j) {
    // A shift equal to the previous one (a repeated eigenvalue) is moved up by 10ε‖T‖: the
    // orthogonalisation then picks the next vector of the eigenspace.
    const double value = eigenvalues[j] / unit / norm;
    sigma = j > 0 ? std::max(value, sigma + 10 * eps) : value;
    tridiagonal_eigenvector(a, off, sigma, eps, j, found, iterate, lu);
  }
  // (a safety net: before kPivotFloor a vector lost to overflow came out zero; review, session 28)
  if (!found.allFinite() || ((found.colwise().norm().array() - 1.0).abs() > 1e-6).any()) return from_eigen();
  // Back to A: x = Q D u, D = diag(d) unitary with d₀ = 1, d_{i+1} = d_i beta_i / |beta_i| (so that
  // D T Dᴴ is the reduced matrix), Q = H₀ H₁ ⋯ H_{n−3}.
  vectors.resize(n, k);
  Scalar phase = 1.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    vectors.row(i) = phase * found.row(i);
    if (i + 1 < n && subdiagonal[i] > 0) phase *= kept.beta[i] / subdiagonal[i];
  }
  for (Eigen::Index step = n - 3; step >= 0; --step) {
    const double tau = kept.tau[step];
    if (tau == 0) continue;
    const Eigen::Index m = n - step - 1;
    const auto v = A.col(step).tail(m);  // the reflector's v
    for (int j = 0; j < k; ++j) {
      auto x = vectors.col(j).tail(m);
      x -= (tau * v.dot(x)) * v;  // H x = x − τ v (vᴴ x)
    }
  }
}

}  // namespace

void lowest_eigenpairs(const Eigen::MatrixXd& A, int k, Eigen::VectorXd& eigenvalues, Eigen::MatrixXd& vectors,
                       double below) {
  lowest_eigenpairs_impl(A, k, eigenvalues, vectors, true, below);
}
void lowest_eigenpairs(const Eigen::MatrixXcd& A, int k, Eigen::VectorXd& eigenvalues, Eigen::MatrixXcd& vectors,
                       double below) {
  lowest_eigenpairs_impl(A, k, eigenvalues, vectors, true, below);
}

Eigen::MatrixXd lowest_vector(const Eigen::MatrixXd& A) {
  Eigen::VectorXd eigenvalues;
  Eigen::MatrixXd vector;
  lowest_eigenpairs_impl(A, 1, eigenvalues, vector, false);
  return vector;
}
Eigen::MatrixXcd lowest_vector(const Eigen::MatrixXcd& A) {
  Eigen::VectorXd eigenvalues;
  Eigen::MatrixXcd vector;
  lowest_eigenpairs_impl(A, 1, eigenvalues, vector, false);
  return vector;
}

}  // namespace fact::sdp::detail
