// Products of complex matrices for the complex form's interior point and Newton (N × N, N up to
// a few hundred), through real matrix products, and of real or complex matrices with a triangular
// operand (multiply).
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

#include <algorithm>
#include <complex>
#include <cstddef>
#include <type_traits>

#include <Eigen/Dense>

namespace fact::sdp::detail {

// Below this, in any of the three dimensions, Eigen's complex product is as fast (n = 8 / 12 /
// 16: 0.96 / 1.09 / 1.15 of its time by three real products, splitting included).
constexpr Eigen::Index kThreeProductMinSize = 16;

// Where an operand's entries may be nonzero: anywhere, or on and below (lower) or on and above
// (upper) its diagonal, the rest zero. A product with a triangular operand (real: one, complex:
// its three real ones) goes through Eigen's triangular product, which skips the zero triangle:
// real 0.65 / 0.62 / 0.56, complex 0.72 / 0.68 / 0.64 of a dense product's time at n = 100 / 128 /
// 200 on the AVX2 machine (BENCHMARKS.md, session 36).
enum class Shape { dense, lower, upper };
// Below this, in any dimension, a triangular operand is multiplied as a dense one: Eigen's
// triangular product was 1.6× slower than the dense one on 16 × 16 blocks (inverse of n = 32),
// as fast on 24 × 24 and 32 × 32 (n = 48, 64), faster from 50 (BENCHMARKS.md, session 36).
constexpr Eigen::Index kTriangularShapeMinSize = 40;

// The calling thread's scratch for the split operands: at least `count` doubles, grown to the
// largest request seen and kept (1.9 MB for a 200 × 200 × 200 product).
double* product_scratch(std::size_t count);

// C = α·(a + ib)(c + id), or C += … with accumulate, for a, b m × k and c, d k × n held in
// scratch (t1, t2 m × n); a and c are overwritten. At most one operand is triangular (a, b for
// LhsShape; c, d for RhsShape), with zeros outside its triangle.
using RealMap = Eigen::Map<Eigen::MatrixXd>;
template <Shape LhsShape, Shape RhsShape>
void three_real_products(RealMap a, RealMap b, RealMap c, RealMap d, RealMap t1, RealMap t2,
                         Eigen::Ref<Eigen::MatrixXcd, 0, Eigen::OuterStride<>> C, double alpha, bool accumulate);

// Eigen's product expression of L and R for their shapes: a triangular operand's product goes
// through Eigen's triangular product, which skips its zero triangle.
template <Shape LhsShape, Shape RhsShape, class Lhs, class Rhs>
auto shaped_product(const Lhs& L, const Rhs& R) {
  static_assert(LhsShape == Shape::dense || RhsShape == Shape::dense, "at most one triangular operand");
  if constexpr (LhsShape == Shape::lower) {
    return L.template triangularView<Eigen::Lower>() * R;
  } else if constexpr (LhsShape == Shape::upper) {
    return L.template triangularView<Eigen::Upper>() * R;
  } else if constexpr (RhsShape == Shape::lower) {
    return L * R.template triangularView<Eigen::Lower>();
  } else if constexpr (RhsShape == Shape::upper) {
    return L * R.template triangularView<Eigen::Upper>();
  } else {
    return L * R;
  }
}

// C = α·L·R, or C += α·L·R with accumulate, by shaped_product. α = ±1 is written as a sum or
// difference, or a product with −L, which Eigen folds into its kernel's factor: no temporary,
// and small blocks keep Eigen's coefficient-by-coefficient product. Any other α (only the
// tests') goes through the evaluated product, since a triangular product has no scalar multiple.
template <Shape LhsShape, Shape RhsShape, class Lhs, class Rhs, class Dest>
void assign_product(const Lhs& L, const Rhs& R, Dest& C, double alpha, bool accumulate) {
  using Scalar = typename std::decay_t<Dest>::Scalar;
  if (alpha == 1.0 && accumulate) {
    C.noalias() += shaped_product<LhsShape, RhsShape>(L, R);
  } else if (alpha == 1.0) {
    C.noalias() = shaped_product<LhsShape, RhsShape>(L, R);
  } else if (alpha == -1.0 && accumulate) {
    C.noalias() -= shaped_product<LhsShape, RhsShape>(L, R);
  } else if (alpha == -1.0) {
    C.noalias() = shaped_product<LhsShape, RhsShape>(-L, R);
  } else {
    using Product = decltype(shaped_product<LhsShape, RhsShape>(L, R));
    const typename Product::PlainObject product = shaped_product<LhsShape, RhsShape>(L, R);
    if (accumulate) {
      C += Scalar(alpha) * product;
    } else {
      C = Scalar(alpha) * product;
    }
  }
}

// C = α·L·R, or C += α·L·R with accumulate, for real or complex expressions L (m × k) and R
// (k × n), e.g. blocks or their adjoints, L of shape LhsShape and R of shape RhsShape (at most one
// triangular, square, its other triangle zero: the products may skip it), and C an m × n block
// that overlaps neither (a matrix is resized to m × n first; a block of another size is a
// caller's error, asserted in debug builds). Below kThreeProductMinSize in any dimension,
// Eigen's product of the operands as given; from it complex operands go through three real
// products, and from kTriangularShapeMinSize a triangular operand's products through Eigen's
// triangular product.
template <Shape LhsShape = Shape::dense, Shape RhsShape = Shape::dense, class Lhs, class Rhs, class Dest>
void multiply(const Lhs& L, const Rhs& R, Dest&& C, double alpha, bool accumulate) {
  // (also asserted in shaped_product; here it fails at compile time on the complex path too,
  // whose three_real_products is instantiated in complex_product.cpp)
  static_assert(LhsShape == Shape::dense || RhsShape == Shape::dense, "at most one triangular operand");
  const Eigen::Index m = L.rows(), k = L.cols(), n = R.cols();
  C.resize(m, n);  // (the three-product path writes through a Ref, which cannot resize)
  if (std::min({m, n, k}) < kThreeProductMinSize) return assign_product<Shape::dense, Shape::dense>(L, R, C, alpha, accumulate);
  if constexpr (LhsShape != Shape::dense || RhsShape != Shape::dense) {
    if (std::min({m, n, k}) < kTriangularShapeMinSize) return multiply(L, R, C, alpha, accumulate);
  }
  if constexpr (!Eigen::NumTraits<typename Lhs::Scalar>::IsComplex) {
    assign_product<LhsShape, RhsShape>(L, R, C, alpha, accumulate);
  } else {
    double* scratch = product_scratch(static_cast<std::size_t>(2 * (m * k + k * n + m * n)));
    RealMap a(scratch, m, k), b(a.data() + a.size(), m, k);
    RealMap c(b.data() + b.size(), k, n), d(c.data() + c.size(), k, n);
    RealMap t1(d.data() + d.size(), m, n), t2(t1.data() + t1.size(), m, n);
    a = L.real();
    b = L.imag();
    c = R.real();
    d = R.imag();
    three_real_products<LhsShape, RhsShape>(a, b, c, d, t1, t2, C, alpha, accumulate);
  }
}

}  // namespace fact::sdp::detail
