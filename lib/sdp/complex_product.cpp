// multiply_complex: complex matrix products by three real ones (complex_product.h).
#include "complex_product.h"

#include <algorithm>
#include <complex>
#include <vector>

namespace fact::sdp::detail {
namespace {

using RealMap = Eigen::Map<Eigen::MatrixXd>;

// C (=|+=) α·op(A)·op(B) by Eigen's complex product.
void eigen_product(const ConstComplexBlock& A, Op op_a, const ConstComplexBlock& B, Op op_b, ComplexBlock& C,
                   std::complex<double> alpha, bool accumulate) {
  auto assign = [&](const auto& a, const auto& b) {
    if (accumulate) {
      C.noalias() += alpha * (a * b);
    } else {
      C.noalias() = alpha * (a * b);
    }
  };
  if (op_a == Op::plain && op_b == Op::plain) return assign(A, B);
  if (op_a == Op::plain) return assign(A, B.adjoint());
  if (op_b == Op::plain) return assign(A.adjoint(), B);
  assign(A.adjoint(), B.adjoint());
}

// Doubles of the calling thread's scratch buffer, grown to at least `count` and kept.
double* scratch(std::size_t count) {
  thread_local std::vector<double> buffer;
  if (buffer.size() < count) buffer.resize(count);
  return buffer.data();
}

// re = Re M, im = ±Im M (minus for op = adjoint: the conjugate), both as M is stored (rows × cols).
void split(const ConstComplexBlock& M, Op op, RealMap& re, RealMap& im) {
  re = M.real();
  if (op == Op::adjoint) {
    im = -M.imag();
  } else {
    im = M.imag();
  }
}

// P = op(X)·op(Y) for real X, Y stored as split() left them (op = adjoint: transposed).
void real_product(const RealMap& X, Op op_x, const RealMap& Y, Op op_y, RealMap& P) {
  if (op_x == Op::plain && op_y == Op::plain) {
    P.noalias() = X * Y;
  } else if (op_x == Op::plain) {
    P.noalias() = X * Y.transpose();
  } else if (op_y == Op::plain) {
    P.noalias() = X.transpose() * Y;
  } else {
    P.noalias() = X.transpose() * Y.transpose();
  }
}

}  // namespace

void multiply_complex(const ConstComplexBlock& A, Op op_a, const ConstComplexBlock& B, Op op_b, ComplexBlock C,
                      double alpha, bool accumulate) {
  const Eigen::Index m = C.rows(), n = C.cols(), k = op_a == Op::plain ? A.cols() : A.rows();
  if (std::min({m, n, k}) < kThreeProductMinSize) return eigen_product(A, op_a, B, op_b, C, alpha, accumulate);
  // op(A) = a + ib, op(B) = c + id (a, b m × k; c, d k × n), kept as A and B are stored.
  double* buffer = scratch(static_cast<std::size_t>(2 * (m * k + k * n + m * n)));
  RealMap a(buffer, A.rows(), A.cols()), b(a.data() + a.size(), A.rows(), A.cols());
  RealMap c(b.data() + b.size(), B.rows(), B.cols()), d(c.data() + c.size(), B.rows(), B.cols());
  RealMap t1(d.data() + d.size(), m, n), t2(t1.data() + t1.size(), m, n);  // m × n each
  split(A, op_a, a, b);
  split(B, op_b, c, d);
  real_product(a, op_a, c, op_b, t1);  // ac
  real_product(b, op_a, d, op_b, t2);  // bd
  if (accumulate) {
    C.real() += alpha * (t1 - t2);
  } else {
    C.real() = alpha * (t1 - t2);
  }
  t1 += t2;  // ac + bd
  a += b;    // a + b
  c += d;    // c + d
  real_product(a, op_a, c, op_b, t2);  // (a + b)(c + d)
  if (accumulate) {
    C.imag() += alpha * (t2 - t1);
  } else {
    C.imag() = alpha * (t2 - t1);
  }
}

}  // namespace fact::sdp::detail
