// fact-bench-sdp-kernels: the dense kernels under the SDP interior points, timed alone at each
// size, real and complex: Cholesky, the inverse of a lower-triangular factor, its Gram matrix
// L⁻ᴴ L⁻¹, a dense product (Eigen's; three real products when complex) and a product with a
// triangular operand (multiply<Shape>); real, up to kGridStepMaxSize rows, also cholesky_lower and
// the step-length grid's Cholesky tests (grid_rows). Each row also checks its kernel's result against a
// reference and the run exits 1 when one is off, so a wrong kernel never gets a time.
// Writes kernel,scalar,n,min_us,median_us,residual to --out.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <complex>
#include <cstdio>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "common/cli_checks.h"
#include "complex_product.h"
#include "gaussian_matrix.h"
#include "internal.h"
#include "results_file.h"
#include "stats.h"
#include "step_length.h"

namespace {

using Clock = std::chrono::steady_clock;
namespace sdp = fact::sdp::detail;

// A kernel's residual above this (relative, Frobenius norm) fails the run.
constexpr double kMaxResidual = 1e-10;

struct Row {
  std::string kernel, scalar;
  int n = 0;
  double min_us = 0, median_us = 0, residual = 0;
};

// Per-call times of `run` (µs): `reps` batches of calls lasting at least 2 ms each, the time of
// a batch divided by its calls.
template <class Run>
std::vector<double> time_calls(int reps, Run run) {
  run();  // warm: allocations, caches
  int calls = 1;
  for (;;) {  // calls per batch
    const auto t0 = Clock::now();
    for (int c = 0; c < calls; ++c) run();
    if (std::chrono::duration<double, std::milli>(Clock::now() - t0).count() >= 2.0 || calls >= (1 << 20)) break;
    calls *= 2;
  }
  std::vector<double> us;
  for (int r = 0; r < reps; ++r) {
    const auto t0 = Clock::now();
    for (int c = 0; c < calls; ++c) run();
    us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count() / calls);
  }
  return us;
}

// A rows × cols operand of standard Gaussian entries, from a distribution of its own.
template <class Matrix>
Matrix random_matrix(Eigen::Index rows, Eigen::Index cols, std::mt19937& rng) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  return fact::bench::gaussian_matrix<Matrix>(rows, cols, rng, gauss);
}

double relative(double error, double scale) { return error / std::max(scale, 1e-300); }

// The real interior point's small-size kernels (n ≤ kGridStepMaxSize): cholesky_lower (the factor
// of the Schur complement and of X, Z) and the grid's test of P + aΔ (sum_passes_cholesky_test) on
// a positive definite sum, one whose pivot fails at the middle row and one failing at the last:
// A (positive definite, n × n) with A(k, k) lowered by twice its pivot there, 1/(A_k⁻¹)(k, k) for
// A_k the leading (k + 1) × (k + 1) block (W = A⁻¹ for the last). A test's residual is 0 when it
// decided right and 1 otherwise.
template <class Add>
void grid_rows(const Eigen::MatrixXd& A, const Eigen::MatrixXd& W, int reps, std::mt19937& rng, Add add) {
  const Eigen::Index n = A.rows();
  Eigen::MatrixXd L(n, n);  // A's factor, lower triangle
  std::vector<double> us = time_calls(reps, [&] { sdp::cholesky_lower(A, L); });
  const Eigen::MatrixXd lower = L.triangularView<Eigen::Lower>();
  add("cholesky_lower", us, relative((lower * lower.transpose() - A).norm(), A.norm()));

  const Eigen::MatrixXd H = random_matrix<Eigen::MatrixXd>(n, n, rng);
  const Eigen::MatrixXd delta = H + H.transpose();  // Δ, n × n symmetric
  const double a = 0.5;
  const auto test_row = [&](const std::string& kernel, const Eigen::MatrixXd& sum, bool expected) {
    const Eigen::MatrixXd P = sum - a * delta;  // P + aΔ = sum
    bool passed = false;
    us = time_calls(reps, [&] { passed = sdp::sum_passes_cholesky_test(P, a, delta); });
    add(kernel, us, passed == expected ? 0.0 : 1.0);
  };
  test_row("grid_test_pass", A, true);
  const Eigen::Index middle = n / 2;
  const double middle_pivot = 1.0 / A.topLeftCorner(middle + 1, middle + 1).inverse()(middle, middle);
  Eigen::MatrixXd failing = A;
  failing(middle, middle) -= 2 * middle_pivot;
  test_row("grid_test_fail_middle", failing, false);
  failing = A;
  failing(n - 1, n - 1) -= 2 / W(n - 1, n - 1);
  test_row("grid_test_fail_last", failing, false);
}

// The rows of one scalar type (Matrix: Eigen::MatrixXd or Eigen::MatrixXcd) at size n.
template <class Matrix>
void kernel_rows(const std::string& scalar, int n, int reps, std::mt19937& rng, std::vector<Row>& rows) {
  const Matrix B = random_matrix<Matrix>(n, n, rng);
  const Matrix A = B * B.adjoint() + static_cast<double>(n) * Matrix::Identity(n, n);  // n × n, positive definite
  auto add = [&](const std::string& kernel, const std::vector<double>& us, double residual) {
    rows.push_back({kernel, scalar, n, *std::min_element(us.begin(), us.end()), fact::bench::median(us), residual});
  };

  Matrix L = A;  // n × n: A's Cholesky factor, lower triangle, zeros above
  std::vector<double> us = time_calls(reps, [&] {
    L = A;
    sdp::cholesky_in_place(L);
  });
  L = Matrix(L.template triangularView<Eigen::Lower>());
  add("cholesky", us, relative((L * L.adjoint() - A).norm(), A.norm()));

  Matrix L_inv;  // n × n: L⁻¹, lower triangular
  us = time_calls(reps, [&] { sdp::invert_lower_factor(L, L_inv); });
  add("invert_lower", us, (L * L_inv - Matrix::Identity(n, n)).norm() / std::sqrt(static_cast<double>(n)));

  Matrix W;  // n × n: L⁻ᴴ L⁻¹ = A⁻¹
  us = time_calls(reps, [&] { sdp::gram_of_lower_factor(L_inv, W); });
  const Matrix W_reference = L_inv.adjoint() * L_inv;
  add("gram_of_lower", us, relative((W - W_reference).norm(), W_reference.norm()));

  const Matrix P = random_matrix<Matrix>(n, n, rng);  // n × n dense operand
  Matrix C;                                           // n × n product
  us = time_calls(reps, [&] { sdp::multiply(P, W, C, 1.0, false); });
  add("multiply_dense", us, relative((C - P * W).norm(), P.norm() * W.norm()));

  us = time_calls(reps, [&] { sdp::multiply<sdp::Shape::dense, sdp::Shape::lower>(P, L_inv, C, 1.0, false); });
  add("multiply_lower", us, relative((C - P * L_inv).norm(), P.norm() * L_inv.norm()));

  if constexpr (Eigen::NumTraits<typename Matrix::Scalar>::IsComplex) {  // the reference for 3M
    us = time_calls(reps, [&] { C.noalias() = P * W; });
    add("eigen_complex_product", us, 0.0);
  } else if (n <= sdp::kGridStepMaxSize) {
    grid_rows(A, W, reps, rng, add);
  }
}

std::string csv_of(const std::vector<Row>& rows) {
  std::ostringstream out;
  out << "kernel,scalar,n,min_us,median_us,residual\n";
  char line[160];
  for (const Row& r : rows) {
    std::snprintf(line, sizeof line, "%s,%s,%d,%.3f,%.3f,%.2e\n", r.kernel.c_str(), r.scalar.c_str(), r.n, r.min_us,
                  r.median_us, r.residual);
    out << line;
  }
  return out.str();
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> sizes{32, 48, 64, 100, 128, 200, 400};
  int reps = 9;
  std::string out = "bench/results/sdp_kernels.csv";
  CLI::App cli{"fact-bench-sdp-kernels: the SDP interior points' dense kernels (Cholesky, triangular inverse, Gram,\n"
               "products dense and triangular), real and complex, timed alone; each result checked. Writes --out."};
  cli.add_option("--sizes", sizes, "matrix sizes n (n × n)")->delimiter(',')->check(CLI::Range(2, 2000))->capture_default_str();
  cli.add_option("--reps", reps, "timed batches per kernel (min and median reported)")
      ->check(fact::app::decimal_integer())
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cli.add_option("--out", out, "CSV file written")->capture_default_str();
  if (const int code = fact::app::parse_command_line(cli, argc, argv); code >= 0) return code;

  std::mt19937 rng(5);
  std::vector<Row> rows;
  std::printf("%-22s %-8s %5s %10s %10s %9s\n", "kernel", "scalar", "n", "min_us", "median_us", "residual");
  bool wrong = false;
  for (std::size_t s = 0; s < sizes.size(); ++s) {
    const std::size_t first = rows.size();
    kernel_rows<Eigen::MatrixXd>("real", sizes[s], reps, rng, rows);
    kernel_rows<Eigen::MatrixXcd>("complex", sizes[s], reps, rng, rows);
    for (std::size_t i = first; i < rows.size(); ++i) {
      const Row& r = rows[i];
      const bool off = !(r.residual <= kMaxResidual);
      wrong = wrong || off;
      std::printf("%-22s %-8s %5d %10.2f %10.2f %9.1e%s\n", r.kernel.c_str(), r.scalar.c_str(), r.n, r.min_us, r.median_us,
                  r.residual, off ? "  WRONG" : "");
    }
    std::fprintf(stderr, "[%zu/%zu] n = %d done\n", s + 1, sizes.size(), sizes[s]);
  }
  try {
    fact::bench::write_results_file(out, csv_of(rows));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fact-bench-sdp-kernels: %s\n", e.what());
    return 1;
  }
  std::printf("wrote %s\n", out.c_str());
  if (wrong) {
    std::fprintf(stderr, "fact-bench-sdp-kernels: a kernel's residual is above %.0e (rows marked WRONG)\n", kMaxResidual);
    return 1;
  }
  return 0;
}
