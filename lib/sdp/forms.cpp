// The tight complex form and the real embedding of Hermitian problems.
#include <stdexcept>
#include <string>

#include "internal.h"

namespace fact::sdp {

Eigen::MatrixXd complex_form(const Eigen::MatrixXd& Q) {
  if (Q.rows() != Q.cols() || Q.rows() % 2 != 0)
    throw std::invalid_argument("complex_form: Q is " + std::to_string(Q.rows()) + "×" + std::to_string(Q.cols()) +
                                ", must be 2N×2N");
  Eigen::Matrix2d J;  // the 90° rotation
  J << 0, -1, 1, 0;
  Eigen::MatrixXd out = Q;
  for (Eigen::Index i = 0; i < Q.rows(); i += 2)
    for (Eigen::Index j = 0; j < Q.cols(); j += 2)
      out.block<2, 2>(i, j) += J.transpose() * Q.block<2, 2>(i, j) * J;  // (Kᵀ Q K)_ij = Jᵀ Q_ij J
  return out;
}

Eigen::MatrixXd real_embedding(const Eigen::MatrixXcd& H) {
  if (H.rows() != H.cols()) throw std::invalid_argument("real_embedding: H must be square");
  return detail::real_factor(H);
}

namespace detail {

Eigen::MatrixXd real_factor(const Eigen::MatrixXcd& Y) {
  Eigen::MatrixXd out(2 * Y.rows(), 2 * Y.cols());  // block (i, k) = [[Re y, −Im y], [Im y, Re y]]
  for (Eigen::Index k = 0; k < Y.cols(); ++k)
    for (Eigen::Index i = 0; i < Y.rows(); ++i) {
      const double re = Y(i, k).real(), im = Y(i, k).imag();
      out.block<2, 2>(2 * i, 2 * k) << re, -im, im, re;
    }
  return out;
}

Eigen::MatrixXcd complex_of_real_factor(const Eigen::MatrixXd& Y_real) {
  Eigen::MatrixXcd Y(Y_real.rows() / 2, Y_real.cols() / 2);  // y_ik = Y_real(2i, 2k) + i·Y_real(2i+1, 2k)
  for (Eigen::Index k = 0; k < Y.cols(); ++k)
    for (Eigen::Index i = 0; i < Y.rows(); ++i) Y(i, k) = {Y_real(2 * i, 2 * k), Y_real(2 * i + 1, 2 * k)};
  return Y;
}

}  // namespace detail

}  // namespace fact::sdp
