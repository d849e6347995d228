// Factors Y of a positive semidefinite X (Y Yᵀ = X, or Y Yᴴ for complex X): the eigendecomposition
// that keeps every direction above a tolerance (factor_psd), Cholesky with diagonal pivoting
// (pivoted_cholesky), and the leading part of X by the two together (leading_factor); the rank
// the Newton polish keeps of such a factor (polish_rank).
#include <algorithm>
#include <cmath>
#include <complex>
#include <vector>

#include "internal.h"

namespace fact::sdp::detail {

int polish_rank(const Eigen::VectorXd& values, int d, int max_rank, bool drop_ghosts) {
  const double largest = values.size() > 0 ? values.maxCoeff() : 0.0;
  const auto ghost = [&](Eigen::Index k) {
    return drop_ghosts && k >= d && values[k] < kGhostBelow * largest && kGhostDrop * values[k] < values[k - 1];
  };
  int rank = 0;
  while (rank < values.size() && rank < max_rank && values[rank] > 1e-6 * largest && !ghost(rank)) ++rank;
  return rank;
}

Eigen::MatrixXd factor_psd(const Eigen::MatrixXd& X, double tol) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(X);
  Eigen::VectorXd w;         // eigenvalues, ascending
  Eigen::MatrixXd vectors;   // their eigenvectors, n × n
  if (eig.info() == Eigen::Success) {
    w = eig.eigenvalues();
    vectors = eig.eigenvectors();
  } else {  // the QR iteration did not converge (its values then come unsorted): Jacobi's SVD of the
            // symmetric PSD X always converges, singular values descending
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(X, Eigen::ComputeFullU);
    w = svd.singularValues().reverse();
    vectors = svd.matrixU().rowwise().reverse();
  }
  const double cutoff = tol * std::max(w.maxCoeff(), 0.0);
  int r = 0;
  while (r < w.size() && w[w.size() - 1 - r] > cutoff) ++r;
  Eigen::MatrixXd Y(X.rows(), r);
  for (int k = 0; k < r; ++k) Y.col(k) = vectors.col(w.size() - 1 - k) * std::sqrt(w[w.size() - 1 - k]);
  return Y;
}

template <class Matrix>
PivotedCholesky<Matrix> pivoted_cholesky_above(const Matrix& Z, double tol) {
  const Eigen::Index n = Z.rows();
  PivotedCholesky<Matrix> f;
  f.Y = Matrix::Zero(n, n);
  f.rest = Z.diagonal().real();
  f.pivoted.assign(n, false);
  for (Eigen::Index& p = f.rank; p < n; ++p) {
    Eigen::Index pivot = -1;
    for (Eigen::Index i = 0; i < n; ++i)
      if (!f.pivoted[i] && (pivot < 0 || f.rest[i] > f.rest[pivot])) pivot = i;
    if (!(f.rest[pivot] > tol)) break;
    // Column p = (Z − Y Yᴴ) e_pivot / √rest_pivot; zero on the rows already pivoted, where
    // Z − Y Yᴴ vanishes.
    f.Y.col(p) = Z.col(pivot);
    if (p > 0) f.Y.col(p).noalias() -= f.Y.leftCols(p) * f.Y.row(pivot).head(p).adjoint();
    f.Y.col(p) /= std::sqrt(f.rest[pivot]);
    f.pivoted[pivot] = true;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (f.pivoted[i] && i != pivot) f.Y(i, p) = 0.0;
      f.rest[i] -= std::norm(f.Y(i, p));
    }
  }
  return f;
}

template PivotedCholesky<Eigen::MatrixXd> pivoted_cholesky_above(const Eigen::MatrixXd& Z, double tol);
template PivotedCholesky<Eigen::MatrixXcd> pivoted_cholesky_above(const Eigen::MatrixXcd& Z, double tol);

template <class Matrix>
Matrix pivoted_cholesky(const Matrix& Z, double cutoff) {
  PivotedCholesky<Matrix> f = pivoted_cholesky_above(Z, cutoff * Z.diagonal().real().maxCoeff());
  f.Y.conservativeResize(Z.rows(), std::max<Eigen::Index>(f.rank, 1));
  return f.Y;
}

template Eigen::MatrixXd pivoted_cholesky(const Eigen::MatrixXd& Z, double cutoff);
template Eigen::MatrixXcd pivoted_cholesky(const Eigen::MatrixXcd& Z, double cutoff);

Eigen::MatrixXd leading_factor(const Eigen::MatrixXd& X, double cutoff) {
  const Eigen::MatrixXd P = pivoted_cholesky(X, cutoff);  // n × r
  const Eigen::Index r = P.cols();
  // Q: an orthonormal basis (n × r) of the range of X P, one subspace-iteration step from P's.
  const Eigen::MatrixXd XP = X * P;
  const Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(XP).householderQ() * Eigen::MatrixXd::Identity(X.rows(), r);
  // Rayleigh–Ritz: X ≈ Q (Qᵀ X Q) Qᵀ, the r × r middle matrix diagonalised, largest first.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> ritz(Q.transpose() * X * Q);
  Eigen::MatrixXd Y = Q * ritz.eigenvectors().rowwise().reverse();  // n × r
  for (Eigen::Index k = 0; k < r; ++k) Y.col(k) *= std::sqrt(std::max(0.0, ritz.eigenvalues()[r - 1 - k]));
  return Y;
}

}  // namespace fact::sdp::detail
