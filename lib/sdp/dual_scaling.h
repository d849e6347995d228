// The bookkeeping both dual-scaling methods share (complex_dual_scaling.cpp on the Hermitian form,
// dual_scaling.cpp on the real one): the upper bound z̄ that sets μ = (z̄ − dual)/ρ, the best
// primal point's μ, when to give up, and the stopping tests. The methods keep their own matrices
// (the best point's W and Δy) and call `lowers` when a primal point's objective is below z̄.
#pragma once

#include <cmath>
#include <limits>
#include <string>

#include "internal.h"

namespace fact::sdp::detail {

// Iterations without a better primal point after which dual scaling gives up, before the first
// one and between two (solve() then runs the primal–dual method). With the upper bounds solve()
// gives, each of the 42 complex sweep instances (N = 32 … 200, session 37) handed off before it.
constexpr int kDualScalingPatience = 10;

class DualScalingBound {
 public:
  // upper_bound: the objective of some feasible X; rho: the potential parameter ρ.
  DualScalingBound(double upper_bound, double rho) : z_bar_(upper_bound), rho_(rho) {}

  double z_bar() const { return z_bar_; }
  double mu(double dual) const { return (z_bar_ - dual) / rho_; }
  double best_mu() const { return best_mu_; }  // μ of the primal point whose objective is z̄

  // Before an iteration: true, with the reason in out, once kDualScalingPatience iterations have
  // found no better primal point (the iteration that would be the next does not count).
  template <class Outcome>
  bool out_of_patience(Outcome& out) const {
    if (waited_ < kDualScalingPatience) return false;
    out.reason = "dual scaling found no better primal point in " + std::to_string(waited_) + " iterations";
    return true;
  }

  // At the dual objective `dual` and z̄'s relative gap rel_gap: true when the loop stops, with
  // converged (below gap_tol) or handed_off (below handoff_gap) set once a primal point was found,
  // or a reason when z̄ is not above the dual (a caller's bound at or below it, or NaN: μ would not
  // be positive).
  template <class Outcome>
  bool stops(double dual, double rel_gap, double gap_tol, double handoff_gap, Outcome& out) const {
    if (have_primal_ && rel_gap < gap_tol) {
      out.converged = true;
      return true;
    }
    if (have_primal_ && rel_gap < handoff_gap) {
      out.handed_off = true;
      return true;
    }
    if (z_bar_ > dual) return false;
    out.reason = printed("dual scaling: upper bound %g is not above the dual objective %g", z_bar_, dual);
    return true;
  }

  // A primal point X(mu) of this objective: true when it lowers z̄ by more than the rounding of
  // the objective's sum (16ε of |z̄| + |objective|), and it is then the best one (the caller keeps
  // its W and Δy); the wait starts again. (Where the bound is the optimum, N = 1 with X = I the
  // only feasible point, the sum came out 1 ulp below it on some dual paths, and a "better" X was
  // found that is the bound's own.)
  bool lowers(double objective, double mu) {
    const double rounding = 16 * std::numeric_limits<double>::epsilon() * (std::abs(z_bar_) + std::abs(objective));
    if (!(objective < z_bar_ - rounding)) return false;
    z_bar_ = objective;
    best_mu_ = mu;
    have_primal_ = true;
    waited_ = -1;  // (next_iteration makes it 0)
    return true;
  }

  void next_iteration() { ++waited_; }

  // After the loop: the reason when it ran out of iterations; false, with neither flag and a
  // reason, when it found no primal point (the caller returns without X).
  template <class Outcome>
  bool found_primal(Outcome& out, int max_iterations) const {
    if (!out.converged && !out.handed_off && out.reason.empty())
      out.reason = "dual scaling reached " + std::to_string(max_iterations) + " iterations";
    if (have_primal_) return true;
    if (out.reason.empty()) out.reason = "dual scaling found no primal point";
    out.converged = out.handed_off = false;
    return false;
  }

 private:
  double z_bar_;           // the objective of the best feasible X so far, or the caller's bound
  double rho_;             // ρ in μ = (z̄ − dual)/ρ
  double best_mu_ = 0;     // μ of that X
  bool have_primal_ = false;
  int waited_ = 0;         // iterations since the last better primal point (or the start)
};

}  // namespace fact::sdp::detail
