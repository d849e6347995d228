#include "instances.h"

#include <random>

#include "fact/rotation_cost.h"
#include "fact/sdp.h"

namespace fact::bench {

Eigen::MatrixXd synthetic_cost(int drones, double noise, bool tight, std::uint64_t seed) {
  return synthetic_cost(drones, drones + 1, noise, tight, seed);
}

Eigen::MatrixXd synthetic_cost(int drones, int rounds, double noise, bool tight, std::uint64_t seed) {
  SyntheticOptions options;
  options.drones = drones;
  options.rounds = rounds;
  options.noise = noise;
  options.seed = seed;
  const Eigen::MatrixXd q = paper_cost(make_synthetic_rounds(options).sums);  // 2N × 2N
  return tight ? sdp::complex_form(q) : q;
}

Eigen::MatrixXd random_psd(int n, int rank, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  Eigen::MatrixXd b(n, rank);  // C's factor, n × rank
  for (int j = 0; j < rank; ++j)
    for (int i = 0; i < n; ++i) b(i, j) = gauss(rng);
  return b * b.transpose();
}

}  // namespace fact::bench
