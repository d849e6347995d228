// Cost matrices shared by the SDP tests (test_sdp.cpp, test_sdp_interior_point.cpp).
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "fact/rotation_cost.h"
#include "fact/simgen.h"

namespace fact::test {

// The paper's plain cost (2N × 2N) of a synthetic swarm of `drones` observed over drones + 2
// rounds with 0.05 noise: a noisy instance whose optimum is usually of high rank.
inline Eigen::MatrixXd noisy_plain_cost(int drones, std::uint64_t seed) {
  SyntheticOptions o;
  o.drones = drones;
  o.rounds = drones + 2;
  o.noise = 0.05;
  o.seed = seed;
  return paper_cost(make_synthetic_rounds(o).sums);
}

}  // namespace fact::test
