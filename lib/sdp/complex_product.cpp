// Complex matrix products by three real ones (complex_product.h).
#include "complex_product.h"

#include <vector>

namespace fact::sdp::detail {

double* product_scratch(std::size_t count) {
  thread_local std::vector<double> buffer;
  if (buffer.size() < count) buffer.resize(count);
  return buffer.data();
}

template <Shape LhsShape, Shape RhsShape>
void three_real_products(RealMap a, RealMap b, RealMap c, RealMap d, RealMap t1, RealMap t2,
                         Eigen::Ref<Eigen::MatrixXcd, 0, Eigen::OuterStride<>> C, double alpha, bool accumulate) {
  t1.noalias() = shaped_product<LhsShape, RhsShape>(a, c);  // ac
  t2.noalias() = shaped_product<LhsShape, RhsShape>(b, d);  // bd
  if (accumulate) {
    C.real() += alpha * (t1 - t2);
  } else {
    C.real() = alpha * (t1 - t2);
  }
  t1 += t2;  // ac + bd
  a += b;
  c += d;
  t2.noalias() = shaped_product<LhsShape, RhsShape>(a, c);  // (a + b)(c + d)
  if (accumulate) {
    C.imag() += alpha * (t2 - t1);
  } else {
    C.imag() = alpha * (t2 - t1);
  }
}

// The shapes multiply is used with.
#define FACT_THREE_REAL_PRODUCTS(LHS, RHS)                                                                            \
  template void three_real_products<LHS, RHS>(RealMap, RealMap, RealMap, RealMap, RealMap, RealMap,                    \
                                              Eigen::Ref<Eigen::MatrixXcd, 0, Eigen::OuterStride<>>, double, bool);
FACT_THREE_REAL_PRODUCTS(Shape::dense, Shape::dense)
FACT_THREE_REAL_PRODUCTS(Shape::lower, Shape::dense)
FACT_THREE_REAL_PRODUCTS(Shape::upper, Shape::dense)
FACT_THREE_REAL_PRODUCTS(Shape::dense, Shape::lower)
FACT_THREE_REAL_PRODUCTS(Shape::dense, Shape::upper)
#undef FACT_THREE_REAL_PRODUCTS

}  // namespace fact::sdp::detail
