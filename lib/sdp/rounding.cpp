// Rounding: from the SDP solution X = Y Yᵀ (2N × 2N) to N planar rotations.
#include <cmath>
#include <stdexcept>
#include <string>

#include "fact/sdp.h"

namespace fact::sdp {

// The 2 leading directions of X = Y Yᵀ: the top-2 left singular vectors of Y, scaled.
static Eigen::MatrixXd top_two(const Eigen::MatrixXd& Y) {
  if (Y.cols() == 2) return Y;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Y, Eigen::ComputeThinU);
  return svd.matrixU().leftCols(2) * svd.singularValues().head(2).asDiagonal();
}

// Angle θ of the rotation nearest to A (2 × 2), rot(θ) = [[c, −s], [s, c]].
static double nearest_rotation_angle(const Eigen::Matrix2d& A) {
  return std::atan2(A(1, 0) - A(0, 1), A(0, 0) + A(1, 1));
}

std::vector<Eigen::Matrix2d> round_rotations(const Result& result, int reference) {
  if (result.d != 2 || result.Y.rows() != 2 * result.blocks || result.Y.cols() < 2)
    throw std::invalid_argument("round_rotations: needs a d = 2 result with a factor of rank ≥ 2 (d = " +
                                std::to_string(result.d) + ", Y " + std::to_string(result.Y.rows()) + "×" +
                                std::to_string(result.Y.cols()) + ")");
  if (reference < 0 || reference >= result.blocks)
    throw std::invalid_argument("round_rotations: reference = " + std::to_string(reference) + " not in [0, " +
                                std::to_string(result.blocks) + ")");
  Eigen::MatrixXd V = top_two(result.Y);  // 2N × 2, block i ≈ R_iᵀ G for a global G ∈ O(2)
  int votes = 0;
  for (int i = 0; i < result.blocks; ++i) votes += V.block<2, 2>(2 * i, 0).determinant() >= 0 ? 1 : -1;
  if (votes < 0) V.col(1) *= -1.0;  // det G = −1: reflect so the blocks are rotations
  std::vector<double> theta(result.blocks);  // block i ≈ rot(θ_i) = R_iᵀ G
  for (int i = 0; i < result.blocks; ++i) theta[i] = nearest_rotation_angle(V.block<2, 2>(2 * i, 0));
  std::vector<Eigen::Matrix2d> out(result.blocks);
  for (int i = 0; i < result.blocks; ++i)  // R_refᵀ R_i = (R_refᵀ G)(R_iᵀ G)ᵀ = rot(θ_ref − θ_i)
    out[i] = Eigen::Rotation2Dd(theta[reference] - theta[i]).toRotationMatrix();
  return out;
}

std::vector<double> rotation_angles(const std::vector<Eigen::Matrix2d>& rotations) {
  std::vector<double> out;
  for (const auto& R : rotations) {
    double a = std::atan2(R(1, 0), R(0, 0));
    if (a <= -M_PI) a += 2 * M_PI;
    out.push_back(a);
  }
  return out;
}

}  // namespace fact::sdp
