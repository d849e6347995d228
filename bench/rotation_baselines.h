// Local-search baselines for the rotation solve: Gauss–Newton and Levenberg–Marquardt on the
// paper's cost, the comparison peers of the certifying SDP (the paper's Table I).
//
// The published baselines minimised one squared scalar and started every yaw at 0; these
// minimise the whole residual vector, with an analytic Jacobian, from zeros or from many
// random starts:
//
//     r(θ) ∈ R^{2K},   r_k = Σ_j R(θ_j) s_jk   (rows 2k, 2k+1),   R(θ) = [cos θ, −sin θ; sin θ, cos θ],
//     cost(θ) = ‖r(θ)‖² = Σ_k ‖Σ_j R(θ_j) s_jk‖² = tr(Q Z),   Q = paper_cost(sums), Z = Rᵀ R,
//
// which is the SDP's objective ⟨Q, X⟩ at the rank-2 point X = Z, so the two compare directly.
// s_jk = sums[k][j] as in fact/rotation_cost.h. The reference drone's yaw is fixed at 0 (the cost
// is invariant under one common rotation); the unknowns are the other N − 1 yaws.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

namespace fact::baselines {

using Sums = std::vector<std::vector<Eigen::Vector2d>>;  // sums[k][j] = s_jk ∈ R², K rounds × N drones

// r(θ), 2K: rows 2k, 2k+1 hold Σ_j R(θ_j) s_jk. yaw holds all N yaws (radians).
Eigen::VectorXd residual(const Sums& sums, const std::vector<double>& yaw);

// ‖r(θ)‖² (not halved) = tr(Q Z).
double cost(const Sums& sums, const std::vector<double>& yaw);

// ∂r/∂θ over the free yaws, 2K × (N − 1): column f belongs to drone f for f < reference and to
// drone f + 1 otherwise; its rows 2k, 2k+1 are R(θ_j + π/2) s_jk.
Eigen::MatrixXd jacobian(const Sums& sums, const std::vector<double>& yaw, int reference);

// ∇ cost over the free yaws (same order as the Jacobian's columns), N − 1: 2 Jᵀ r.
Eigen::VectorXd gradient(const Sums& sums, const std::vector<double>& yaw, int reference);

enum class Method {
  gauss_newton,         // (JᵀJ) δ = −Jᵀr, then Armijo backtracking (halving) along δ
  levenberg_marquardt,  // (JᵀJ + μI) h = −Jᵀr, μ by Nielsen's gain-ratio rule
};
const char* to_string(Method m);  // "gauss_newton", "levenberg_marquardt"

enum class Stop {
  gradient,       // ‖Jᵀr‖∞ ≤ gradient_tolerance · Σ_jk ‖s_jk‖²
  step,           // the proposed step (full GN step, LM step) had ‖·‖∞ ≤ step_tolerance
  cost_change,    // an accepted step lowered ‖r‖² by ≤ cost_tolerance · ‖r‖²
  iteration_cap,  // max_iterations reached first
  no_progress,    // GN: 60 halvings found no decrease; LM: the damping grew past 1e30·(1 + max diag JᵀJ)
};
const char* to_string(Stop s);  // the enumerator's name

struct BaselineOptions {
  int max_iterations = 100;          // per start: GN steps, or LM linear solves (accepted or not); ≥ 1
  double gradient_tolerance = 1e-13;  // ≥ 0, relative to Σ_jk ‖s_jk‖² (= tr Q)
  double step_tolerance = 1e-12;     // radians, ≥ 0
  double cost_tolerance = 1e-12;     // relative decrease, ≥ 0 (the cost ends about this close to its local minimum)
  int random_starts = 0;             // 0: one start with every yaw 0; M > 0: M starts with the free
                                     // yaws uniform in (−π, π], the lowest final cost kept
  std::uint64_t seed = 1;            // seeds the random starts; the same seed gives the same result
};

struct BaselineResult {
  std::vector<double> yaw;    // N: yaw of f_i relative to f_ref, wrapped to (−π, π]; yaw[reference] = 0
  double cost = 0;            // ‖r‖² at yaw (not halved; the SDP objective's units, m²)
  int iterations = 0;         // of the start that was kept
  int total_iterations = 0;   // over all starts
  int starts = 0;             // starts run (1, or random_starts)
  bool converged = false;     // the kept start stopped on gradient, step or cost_change
  Stop stop = Stop::iteration_cap;  // why the kept start stopped
  double time_us = 0;         // wall time of all starts (input checks excluded), microseconds
};

// Minimises cost(θ) over the free yaws. Throws std::invalid_argument naming the field and value
// when sums is empty, ragged, has fewer than 2 drones or a non-finite entry, when reference is
// not in [0, N), or when an option is out of range.
BaselineResult solve_rotations(const Sums& sums, int reference, Method method, const BaselineOptions& options = {});

inline BaselineResult gauss_newton(const Sums& sums, int reference, const BaselineOptions& options = {}) {
  return solve_rotations(sums, reference, Method::gauss_newton, options);
}
inline BaselineResult levenberg_marquardt(const Sums& sums, int reference, const BaselineOptions& options = {}) {
  return solve_rotations(sums, reference, Method::levenberg_marquardt, options);
}

// θ wrapped to (−π, π].
double wrap_angle(double theta);

}  // namespace fact::baselines
