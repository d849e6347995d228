// Least-squares translation with the rotations fixed: a weighted graph Laplacian solve.
#include "internal.h"

#include <Eigen/Dense>
#include <queue>

namespace fact::estimator {
namespace {

std::vector<bool> reachable(int drones, int reference, const std::vector<Correspondence>& cs) {
  std::vector<std::vector<int>> adjacent(drones);
  for (const Correspondence& c : cs) {
    adjacent[c.i].push_back(c.j);
    adjacent[c.j].push_back(c.i);
  }
  std::vector<bool> seen(drones, false);
  std::queue<int> todo;
  todo.push(reference);
  seen[reference] = true;
  while (!todo.empty()) {
    const int i = todo.front();
    todo.pop();
    for (int j : adjacent[i])
      if (!seen[j]) {
        seen[j] = true;
        todo.push(j);
      }
  }
  return seen;
}

// Information (inverse covariance, 3 × 3, f_ref axes) of a correspondence's residual.
Eigen::Matrix3d information(const Correspondence& c, const Eigen::Matrix3d& Ri, const Eigen::Matrix3d& Rj) {
  const Eigen::Matrix3d cov = Ri * c.cov_i * Ri.transpose() + Rj * c.cov_j * Rj.transpose();
  if (cov.isZero()) return Eigen::Matrix3d::Identity() / (c.sigma * c.sigma);
  return cov.inverse();
}

}  // namespace

TranslationSolution solve_translations(int drones, int reference, const std::vector<double>& yaw,
                                       const std::vector<Correspondence>& cs) {
  TranslationSolution out;
  out.t.assign(drones, Eigen::Vector3d::Zero());
  out.connected = reachable(drones, reference, cs);
  // Unknowns: t_i for connected i ≠ reference, numbered 0 … m−1.
  std::vector<int> unknown(drones, -1);
  int m = 0;
  for (int i = 0; i < drones; ++i)
    if (out.connected[i] && i != reference) unknown[i] = m++;
  std::vector<Eigen::Matrix3d> R(drones);
  for (int i = 0; i < drones; ++i) R[i] = yaw_rotation(yaw[i]);
  // Normal equations L t = B: L (3m × 3m) the Laplacian of the 3 × 3 information blocks
  // W = Σ⁻¹ without the reference, B (3m) the right-hand side. Residual r = R_i x_i + t_i − R_j x_j − t_j.
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(3 * m, 3 * m);
  Eigen::VectorXd B = Eigen::VectorXd::Zero(3 * m);
  std::vector<Eigen::Matrix3d> W(cs.size());
  for (size_t k = 0; k < cs.size(); ++k) {
    const Correspondence& c = cs[k];
    if (!out.connected[c.i]) continue;
    W[k] = information(c, R[c.i], R[c.j]);
    const Eigen::Vector3d d = R[c.i] * c.x_i - R[c.j] * c.x_j;
    const int a = unknown[c.i], b = unknown[c.j];
    if (a >= 0) L.block<3, 3>(3 * a, 3 * a) += W[k], B.segment<3>(3 * a) -= W[k] * d;
    if (b >= 0) L.block<3, 3>(3 * b, 3 * b) += W[k], B.segment<3>(3 * b) += W[k] * d;
    if (a >= 0 && b >= 0) L.block<3, 3>(3 * a, 3 * b) -= W[k], L.block<3, 3>(3 * b, 3 * a) -= W[k];
  }
  if (m > 0) {
    const Eigen::VectorXd T = L.ldlt().solve(B);  // 3m
    for (int i = 0; i < drones; ++i)
      if (unknown[i] >= 0) out.t[i] = T.segment<3>(3 * unknown[i]);
  }
  for (size_t k = 0; k < cs.size(); ++k) {
    const Correspondence& c = cs[k];
    if (!out.connected[c.i]) continue;
    const Eigen::Vector3d r = R[c.i] * c.x_i + out.t[c.i] - R[c.j] * c.x_j - out.t[c.j];
    const double n = std::sqrt(r.dot(W[k] * r));
    if (n > out.max_normalised_residual) out.max_normalised_residual = n, out.worst = static_cast<int>(k);
  }
  return out;
}

}  // namespace fact::estimator

namespace fact::estimator {

// Linearises r = R(θ_i) x_i + t_i − R(θ_j) x_j − t_j around the solution: ∂r/∂θ_i = R'(θ_i) x_i,
// ∂r/∂t_i = I (and the negatives for j). The information H (4m × 4m, per unknown drone
// [θ; t]) is Σ Jᵀ W J; its inverse is the covariance of every pose relative to the reference.
std::vector<PoseSigma> pose_uncertainty(int drones, int reference, const std::vector<double>& yaw,
                                        const std::vector<Eigen::Vector3d>& t, const std::vector<bool>& connected,
                                        const std::vector<Correspondence>& cs) {
  std::vector<int> unknown(drones, -1);
  int m = 0;
  for (int i = 0; i < drones; ++i)
    if (connected[i] && i != reference) unknown[i] = m++;
  std::vector<PoseSigma> out(drones);
  if (m == 0) return out;
  std::vector<Eigen::Matrix3d> R(drones), dR(drones);  // rotation and its derivative in yaw
  for (int i = 0; i < drones; ++i) {
    R[i] = yaw_rotation(yaw[i]);
    dR[i] = yaw_rotation(yaw[i] + M_PI / 2);
    dR[i](2, 2) = 0;
  }
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(4 * m, 4 * m);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(4 * m);  // gradient Σ Jᵀ W r
  for (const Correspondence& c : cs) {
    if (!connected[c.i] || !connected[c.j]) continue;
    const Eigen::Matrix3d W = information(c, R[c.i], R[c.j]);
    // J: 3 × 8, columns [θ_i, t_i (3), θ_j, t_j (3)].
    Eigen::Matrix<double, 3, 8> J = Eigen::Matrix<double, 3, 8>::Zero();
    J.col(0) = dR[c.i] * c.x_i;
    J.block<3, 3>(0, 1).setIdentity();
    J.col(4) = -dR[c.j] * c.x_j;
    J.block<3, 3>(0, 5) = -Eigen::Matrix3d::Identity();
    const Eigen::Matrix<double, 8, 8> h = J.transpose() * W * J;
    const Eigen::Vector3d r = R[c.i] * c.x_i + t[c.i] - R[c.j] * c.x_j - t[c.j];
    const Eigen::Matrix<double, 8, 1> gr = J.transpose() * (W * r);
    const int u[2] = {unknown[c.i], unknown[c.j]};
    for (int x = 0; x < 2; ++x)
      if (u[x] >= 0) g.segment<4>(4 * u[x]) += gr.segment<4>(4 * x);
    for (int x = 0; x < 2; ++x)
      for (int y = 0; y < 2; ++y)
        if (u[x] >= 0 && u[y] >= 0) H.block<4, 4>(4 * u[x], 4 * u[y]) += h.block<4, 4>(4 * x, 4 * y);
  }
  Eigen::LDLT<Eigen::MatrixXd> ldlt(H);
  const Eigen::MatrixXd C = ldlt.solve(Eigen::MatrixXd::Identity(4 * m, 4 * m));
  const Eigen::VectorXd step = -(C * g);  // Gauss–Newton step to the least-squares poses
  for (int i = 0; i < drones; ++i) {
    if (unknown[i] < 0) continue;
    const int a = 4 * unknown[i];
    out[i].yaw = std::sqrt(std::max(0.0, C(a, a)));
    const Eigen::Matrix3d P = C.block<3, 3>(a + 1, a + 1);
    out[i].position = std::sqrt(std::max(0.0, P.selfadjointView<Eigen::Lower>().eigenvalues().maxCoeff()));
    out[i].yaw_step = std::abs(step(a));
    out[i].position_step = step.segment<3>(a + 1).norm();
    // A singular H (an unobservable direction) must not read as zero uncertainty.
    const bool singular = !(ldlt.vectorD().minCoeff() > 1e-12 * ldlt.vectorD().cwiseAbs().maxCoeff());
    if (ldlt.info() != Eigen::Success || singular || !std::isfinite(out[i].yaw) || !std::isfinite(out[i].position) ||
        !std::isfinite(out[i].yaw_step) || !std::isfinite(out[i].position_step))
      out[i] = PoseSigma{INFINITY, INFINITY, INFINITY, INFINITY};
  }
  return out;
}

}  // namespace fact::estimator
