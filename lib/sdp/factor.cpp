// Factors Y of a positive semidefinite X (Y Yᵀ = X, or Y Yᴴ for complex X): the eigendecomposition
// that keeps every direction above a tolerance (factor_psd), Cholesky with diagonal pivoting
// (pivoted_cholesky), and the leading part of X by the two together (leading_factor).
#include <algorithm>
#include <cmath>
#include <complex>
#include <vector>

#include "internal.h"

namespace fact::sdp::detail {

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
Matrix pivoted_cholesky(const Matrix& Z, double cutoff) {
  const Eigen::Index n = Z.rows();
  Eigen::VectorXd rest = Z.diagonal().real();  // diagonal of Z − Y Yᴴ, n
  const double tol = cutoff * rest.maxCoeff();
  std::vector<bool> pivoted(n, false);
  Matrix Y = Matrix::Zero(n, n);  // columns 0 … p − 1 in use
  Eigen::Index p = 0;
  for (; p < n; ++p) {
    Eigen::Index pivot = -1;
    for (Eigen::Index i = 0; i < n; ++i)
      if (!pivoted[i] && (pivot < 0 || rest[i] > rest[pivot])) pivot = i;
    if (!(rest[pivot] > tol)) break;
    // Column p = (Z − Y Yᴴ) e_pivot / √rest_pivot; zero on the rows already pivoted, where
    // Z − Y Yᴴ vanishes.
    Y.col(p) = Z.col(pivot);
    if (p > 0) Y.col(p).noalias() -= Y.leftCols(p) * Y.row(pivot).head(p).adjoint();
    Y.col(p) /= std::sqrt(rest[pivot]);
    pivoted[pivot] = true;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (pivoted[i] && i != pivot) Y(i, p) = 0.0;
      rest[i] -= std::norm(Y(i, p));
    }
  }
  Y.conservativeResize(n, std::max<Eigen::Index>(p, 1));
  return Y;
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
