// Products of complex matrices for the complex form's interior point and Newton (N × N, N up to
// a few hundred), through real matrix products.
//
// Eigen's complex matrix-product kernel runs at about two thirds of its real kernel's rate on a
// machine without AVX-512 (AMD EPYC, AVX2: a 200 × 200 complex product took 3.1 ms, four real
// ones 2.0 ms), and a complex product costs four real ones. Gauss's three-product form (3M),
//     (a + ib)(c + id) = (ac − bd) + i((a + b)(c + d) − ac − bd),
// needs three: 1.5 / 1.6 / 2.2 / 1.8× faster than Eigen's complex product at n = 32 / 64 / 100 /
// 200 there (BENCHMARKS.md, session 35). Its error is normwise as small as the usual product's
// (N. J. Higham, "Stability of a method for multiplying complex matrices with three real matrix
// multiplications", SIAM J. Matrix Anal. Appl. 13(3), 1992: the imaginary part's bound has
// (|a| + |b|)(|c| + |d|) where the usual one has |a||d| + |b||c|).
#pragma once

#include <Eigen/Dense>

namespace fact::sdp::detail {

// Blocks of complex matrices, as the recursive factor kernels pass them (unit inner stride).
using ComplexBlock = Eigen::Ref<Eigen::MatrixXcd, 0, Eigen::OuterStride<>>;
using ConstComplexBlock = Eigen::Ref<const Eigen::MatrixXcd, 0, Eigen::OuterStride<>>;

// Whether an operand enters as itself or as its conjugate transpose.
enum class Op { plain, adjoint };

// Below this, in any of the three dimensions, Eigen's complex product is as fast (n = 8 / 12 /
// 16: 0.96 / 1.09 / 1.15 of its time by three real products, splitting included).
constexpr Eigen::Index kThreeProductMinSize = 16;

// C = α·op(A)·op(B), or C += α·op(A)·op(B) with accumulate; C is m × n, op(A) m × k, op(B) k × n
// (sizes are the caller's to match; C must not overlap A or B). Three real products when m, n
// and k are all at least kThreeProductMinSize, Eigen's complex product otherwise. The real and
// imaginary parts live in a scratch buffer of the calling thread that grows to the largest
// product seen (2mk + 2kn + 2mn doubles: 2.6 MB at m = n = k = 200) and is kept.
void multiply_complex(const ConstComplexBlock& A, Op op_a, const ConstComplexBlock& B, Op op_b, ComplexBlock C,
                      double alpha, bool accumulate);

}  // namespace fact::sdp::detail
