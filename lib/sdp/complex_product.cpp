// Complex matrix products by three real ones (complex_product.h).
#include "complex_product.h"

#include <vector>

namespace fact::sdp::detail {

double* product_scratch(std::size_t count) {
  thread_local std::vector<double> buffer;
  if (buffer.size() < count) buffer.resize(count);
  return buffer.data();
}

void three_real_products(RealMap a, RealMap b, RealMap c, RealMap d, RealMap t1, RealMap t2,
                         Eigen::Ref<Eigen::MatrixXcd, 0, Eigen::OuterStride<>> C, double alpha, bool accumulate) {
  t1.noalias() = a * c;  // ac
  t2.noalias() = b * d;  // bd
  if (accumulate) {
    C.real() += alpha * (t1 - t2);
  } else {
    C.real() = alpha * (t1 - t2);
  }
  t1 += t2;  // ac + bd
  a += b;
  c += d;
  t2.noalias() = a * c;  // (a + b)(c + d)
  if (accumulate) {
    C.imag() += alpha * (t2 - t1);
  } else {
    C.imag() = alpha * (t2 - t1);
  }
}

}  // namespace fact::sdp::detail
