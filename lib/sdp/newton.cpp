// Damped Riemannian Newton at fixed rank on the product of Stiefel manifolds St(d, r)^N.
//
// Cost f(Y) = tr(C Y Yᵀ), Y n × r, block Y_i (d × r) with orthonormal rows.
// With Λ(Y) = SymBlockDiag(C Y Yᵀ) and S = C − Λ(Y) (n × n):
//   Riemannian gradient   grad f = 2 S Y
//   Riemannian Hessian    Hess f[V] = Proj_Y(2 S V)
// Both are written in an orthonormal basis of each block's tangent space,
//   T_i = { Ω Y_i + A N_iᵀ : Ω skew d×d, A d×(r−d) },  N_i r×(r−d) with Y_i N_i = 0,
// which has t = d·r − d(d+1)/2 directions. The Newton system (H + μI) η = −g is N·t square.
#include <cmath>
#include <limits>

#include "internal.h"

namespace fact::sdp::detail {
namespace {

// Orthonormal basis of the tangent space at block Y_i (d × r): t matrices d × r.
std::vector<Eigen::MatrixXd> tangent_basis(const Eigen::MatrixXd& Yi) {
  const Eigen::Index d = Yi.rows(), r = Yi.cols();
  std::vector<Eigen::MatrixXd> basis;
  if (d == 2) {
    Eigen::Matrix2d omega;  // skew, unit Frobenius norm
    omega << 0, -M_SQRT1_2, M_SQRT1_2, 0;
    basis.push_back(omega * Yi);
  }
  if (r > d) {
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(Yi.transpose());  // r × d
    const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(r, r);
    for (Eigen::Index a = 0; a < d; ++a)
      for (Eigen::Index b = d; b < r; ++b) {
        Eigen::MatrixXd e = Eigen::MatrixXd::Zero(d, r);
        e.row(a) = Q.col(b).transpose();
        basis.push_back(e);
      }
  }
  return basis;
}

double cost(const Eigen::MatrixXd& C, const Eigen::MatrixXd& Y) { return (Y.transpose() * C * Y).trace(); }

}  // namespace

int newton_refine(const Eigen::MatrixXd& C, int d, Eigen::MatrixXd& Y, int max_iterations, double grad_tol) {
  const Eigen::Index n = C.rows(), r = Y.cols();
  const int blocks = static_cast<int>(n / d), t = static_cast<int>(d * r - d * (d + 1) / 2);
  if (t == 0) return 0;
  double mu = 1e-8;  // Levenberg–Marquardt damping on the Newton system
  double f = cost(C, Y);
  const double noise = 100.0 * static_cast<double>(n) * std::numeric_limits<double>::epsilon() * C.norm();
  int it = 0;
  for (; it < max_iterations; ++it) {
    const Eigen::MatrixXd S = certificate_matrix(C, lambda_from_factor(C, Y, d), d);  // n × n
    const Eigen::MatrixXd SY = S * Y;                                                // n × r
    std::vector<std::vector<Eigen::MatrixXd>> basis(blocks);
    for (int i = 0; i < blocks; ++i) basis[i] = tangent_basis(Y.middleRows(i * d, d));
    Eigen::VectorXd g(blocks * t);  // gradient coefficients
    for (int i = 0; i < blocks; ++i)
      for (int a = 0; a < t; ++a) g[i * t + a] = 2.0 * basis[i][a].cwiseProduct(SY.middleRows(i * d, d)).sum();
    if (g.norm() < grad_tol) break;
    Eigen::MatrixXd H(blocks * t, blocks * t);  // Hessian in the tangent bases, Nt × Nt
    for (int j = 0; j < blocks; ++j)
      for (int b = 0; b < t; ++b) {
        const Eigen::MatrixXd SB = S.middleCols(j * d, d) * basis[j][b];  // n × r: S_{:,j} B_jb
        for (int i = 0; i < blocks; ++i)
          for (int a = 0; a < t; ++a)
            H(i * t + a, j * t + b) = 2.0 * basis[i][a].cwiseProduct(SB.middleRows(i * d, d)).sum();
      }
    H = 0.5 * (H + H.transpose()).eval();
    bool stepped = false;
    for (int tries = 0; tries < 12 && !stepped; ++tries, mu *= 10) {
      Eigen::LDLT<Eigen::MatrixXd> ldlt(H + mu * Eigen::MatrixXd::Identity(blocks * t, blocks * t));
      if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0).all()) continue;
      const Eigen::VectorXd eta = ldlt.solve(-g);
      Eigen::MatrixXd next = Y;
      for (int i = 0; i < blocks; ++i) {
        Eigen::MatrixXd step = Eigen::MatrixXd::Zero(d, r);
        for (int a = 0; a < t; ++a) step += eta[i * t + a] * basis[i][a];
        next.middleRows(i * d, d) = polar_rows(Y.middleRows(i * d, d) + step);
      }
      const double f_next = cost(C, next);
      if (f_next <= f + noise) {  // near the optimum the decrease is below rounding: accept
        Y = next;
        f = f_next;
        stepped = true;
        mu = std::max(1e-12, mu / 100);
      }
    }
    if (!stepped) break;
  }
  return it;
}

}  // namespace fact::sdp::detail
