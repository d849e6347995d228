// Gauss–Newton and Levenberg–Marquardt on r(θ) = [Σ_j R(θ_j) s_jk]_k, the comparison peers of the
// certifying rotation SDP. See rotation_baselines.h for the problem and the conventions.
//
// Internally the solvers work with F = ½‖r‖² (so ∇F = Jᵀr = g and the Gauss–Newton model is
// L(h) = ½‖r + J h‖²); the result reports ‖r‖² = 2F, the SDP's objective.
#include "rotation_baselines.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace fact::baselines {
namespace {

// ---------------------------------------------------------------- input checks

std::string vector_text(const Eigen::Vector2d& v) {
  std::ostringstream text;
  text << "(" << v.x() << ", " << v.y() << ")";
  return text.str();
}

[[noreturn]] void reject(const std::string& what) { throw std::invalid_argument("rotation baselines: " + what); }

// Returns N after checking that sums is K ≥ 1 rounds of the same N ≥ 2 finite vectors.
int checked_drones(const Sums& sums) {
  if (sums.empty()) reject("sums has 0 rounds, need at least 1");
  const std::size_t n = sums.front().size();
  if (n < 2) reject("sums[0] has " + std::to_string(n) + " drones, need at least 2");
  for (std::size_t k = 0; k < sums.size(); ++k) {
    if (sums[k].size() != n)
      reject("sums[" + std::to_string(k) + "] has " + std::to_string(sums[k].size()) + " drones, expected " +
             std::to_string(n));
    for (std::size_t j = 0; j < n; ++j)
      if (!sums[k][j].allFinite())
        reject("sums[" + std::to_string(k) + "][" + std::to_string(j) + "] = " + vector_text(sums[k][j]) +
               " is not finite");
  }
  return static_cast<int>(n);
}

void check_reference(int reference, int drones) {
  if (reference < 0 || reference >= drones)
    reject("reference = " + std::to_string(reference) + " is not a drone index in [0, " + std::to_string(drones) + ")");
}

void check_yaw(const std::vector<double>& yaw, int drones) {
  if (static_cast<int>(yaw.size()) != drones)
    reject("yaw has " + std::to_string(yaw.size()) + " entries, expected one per drone (" + std::to_string(drones) + ")");
  for (std::size_t j = 0; j < yaw.size(); ++j)
    if (!std::isfinite(yaw[j])) reject("yaw[" + std::to_string(j) + "] = " + std::to_string(yaw[j]) + " is not finite");
}

void check_tolerance(const char* name, double value) {
  if (!(value >= 0) || !std::isfinite(value))
    reject(std::string("options.") + name + " = " + std::to_string(value) + " must be finite and ≥ 0");
}

void check_options(const BaselineOptions& o) {
  if (o.max_iterations < 1) reject("options.max_iterations = " + std::to_string(o.max_iterations) + " must be ≥ 1");
  if (o.random_starts < 0) reject("options.random_starts = " + std::to_string(o.random_starts) + " must be ≥ 0");
  check_tolerance("gradient_tolerance", o.gradient_tolerance);
  check_tolerance("step_tolerance", o.step_tolerance);
  check_tolerance("cost_tolerance", o.cost_tolerance);
}

// ---------------------------------------------------------------- residual and Jacobian

// r(θ), 2K, into r (resized).
void residual_into(const Sums& sums, const std::vector<double>& yaw, Eigen::VectorXd& r) {
  const int rounds = static_cast<int>(sums.size());
  const int drones = static_cast<int>(yaw.size());
  r.setZero(2 * rounds);
  for (int j = 0; j < drones; ++j) {
    const Eigen::Matrix2d rot = Eigen::Rotation2Dd(yaw[j]).toRotationMatrix();  // f_j → f_ref, 2 × 2
    for (int k = 0; k < rounds; ++k) r.segment<2>(2 * k) += rot * sums[k][j];
  }
}

// ∂r/∂θ_free, 2K × (N − 1), into jac (resized). ∂(R(θ) s)/∂θ = R(θ + π/2) s.
void jacobian_into(const Sums& sums, const std::vector<double>& yaw, int reference, Eigen::MatrixXd& jac) {
  const int rounds = static_cast<int>(sums.size());
  const int drones = static_cast<int>(yaw.size());
  jac.resize(2 * rounds, drones - 1);
  for (int j = 0, col = 0; j < drones; ++j) {
    if (j == reference) continue;
    const Eigen::Matrix2d rot_prime = Eigen::Rotation2Dd(yaw[j] + M_PI / 2).toRotationMatrix();  // dR/dθ, 2 × 2
    for (int k = 0; k < rounds; ++k) jac.block<2, 1>(2 * k, col) = rot_prime * sums[k][j];
    ++col;
  }
}

double sum_of_squares(const Sums& sums) {  // Σ_jk ‖s_jk‖² = tr Q
  double total = 0;
  for (const auto& round : sums)
    for (const Eigen::Vector2d& s : round) total += s.squaredNorm();
  return total;
}

// yaw with `step` (N − 1, free-yaw order) added to every yaw but the reference's.
std::vector<double> stepped(const std::vector<double>& yaw, const Eigen::VectorXd& step, int reference) {
  std::vector<double> out = yaw;
  for (int j = 0, col = 0; j < static_cast<int>(yaw.size()); ++j)
    if (j != reference) out[j] += step[col++];
  return out;
}

// ---------------------------------------------------------------- one local search

struct Problem {
  const Sums& sums;
  int reference;
  double scale;  // Σ_jk ‖s_jk‖², the gradient tolerance's unit
  const BaselineOptions& options;
};

// The iterate and its linearisation.
struct Point {
  std::vector<double> yaw;  // N
  Eigen::VectorXd r;        // r(θ), 2K
  double half_cost = 0;     // F = ½‖r‖²
  Eigen::MatrixXd jac;      // J, 2K × (N − 1)
  Eigen::MatrixXd normal;   // JᵀJ, (N − 1) × (N − 1)
  Eigen::VectorXd g;        // Jᵀr = ∇F, N − 1
};

double half_cost_at(const Problem& p, const std::vector<double>& yaw) {
  Eigen::VectorXd r;
  residual_into(p.sums, yaw, r);
  return 0.5 * r.squaredNorm();
}

void move_to(const Problem& p, std::vector<double> yaw, Point& x) {
  x.yaw = std::move(yaw);
  residual_into(p.sums, x.yaw, x.r);
  x.half_cost = 0.5 * x.r.squaredNorm();
  jacobian_into(p.sums, x.yaw, p.reference, x.jac);
  x.normal.setZero(x.jac.cols(), x.jac.cols());
  x.normal.selfadjointView<Eigen::Lower>().rankUpdate(x.jac.transpose());
  x.normal.triangularView<Eigen::StrictlyUpper>() = x.normal.transpose();
  x.g.noalias() = x.jac.transpose() * x.r;
}

bool gradient_small(const Problem& p, const Point& x) {
  return x.g.lpNorm<Eigen::Infinity>() <= p.options.gradient_tolerance * p.scale;
}

struct Run {
  std::vector<double> yaw;  // N, unwrapped
  int iterations = 0;
  Stop stop = Stop::iteration_cap;
};

// Gauss–Newton direction −(JᵀJ)⁻¹ Jᵀr; steepest descent −g / max diag(JᵀJ) when the normal
// matrix is singular enough that the solve fails or does not point downhill.
Eigen::VectorXd gauss_newton_direction(const Point& x) {
  Eigen::LDLT<Eigen::MatrixXd> ldlt(x.normal);
  Eigen::VectorXd delta = ldlt.solve(-x.g);
  if (ldlt.info() == Eigen::Success && delta.allFinite() && x.g.dot(delta) < 0) return delta;
  const double curvature = std::max(x.normal.diagonal().maxCoeff(), std::numeric_limits<double>::min());
  return -x.g / curvature;
}

Run run_gauss_newton(const Problem& p, std::vector<double> start) {
  constexpr double kArmijo = 1e-4;  // sufficient-decrease fraction
  constexpr int kHalvings = 60;
  Point x;
  move_to(p, std::move(start), x);
  Run run;
  for (;;) {
    if (gradient_small(p, x)) { run.stop = Stop::gradient; break; }
    if (run.iterations == p.options.max_iterations) { run.stop = Stop::iteration_cap; break; }
    const Eigen::VectorXd delta = gauss_newton_direction(x);
    ++run.iterations;
    if (delta.lpNorm<Eigen::Infinity>() <= p.options.step_tolerance) { run.stop = Stop::step; break; }
    const double slope = x.g.dot(delta);  // dF/dα at α = 0, < 0
    double alpha = 1.0;
    bool accepted = false;
    std::vector<double> trial;
    double trial_cost = 0;
    for (int h = 0; h < kHalvings && !accepted; ++h, alpha *= 0.5) {
      trial = stepped(x.yaw, alpha * delta, p.reference);
      trial_cost = half_cost_at(p, trial);
      accepted = trial_cost <= x.half_cost + kArmijo * alpha * slope;
    }
    if (!accepted) { run.stop = Stop::no_progress; break; }
    const double old_cost = x.half_cost;
    move_to(p, std::move(trial), x);
    if (old_cost - x.half_cost <= p.options.cost_tolerance * old_cost) { run.stop = Stop::cost_change; break; }
  }
  run.yaw = std::move(x.yaw);
  return run;
}

// Levenberg–Marquardt with Nielsen's damping update (Madsen, Nielsen & Tingleff, "Methods for
// non-linear least squares problems", 2004, Alg. 3.16): μ₀ = 10⁻³ max diag(JᵀJ); after a step
// with gain ratio ρ > 0, μ ← μ · max(1/3, 1 − (2ρ − 1)³) and ν ← 2; otherwise μ ← μν, ν ← 2ν.
Run run_levenberg_marquardt(const Problem& p, std::vector<double> start) {
  constexpr double kTau = 1e-3;
  Point x;
  move_to(p, std::move(start), x);
  const double max_curvature = x.normal.size() > 0 ? x.normal.diagonal().maxCoeff() : 0.0;
  const double damping_limit = 1e30 * (1.0 + max_curvature);
  double mu = std::max(kTau * max_curvature, std::numeric_limits<double>::min());
  double nu = 2.0;
  Run run;
  const Eigen::Index free = x.g.size();
  for (;;) {
    if (gradient_small(p, x)) { run.stop = Stop::gradient; break; }
    if (run.iterations == p.options.max_iterations) { run.stop = Stop::iteration_cap; break; }
    const Eigen::LLT<Eigen::MatrixXd> llt(x.normal + mu * Eigen::MatrixXd::Identity(free, free));
    const Eigen::VectorXd h = llt.solve(-x.g);  // LM step, N − 1
    ++run.iterations;
    double gain = -1.0;  // ρ = actual / predicted decrease of F
    std::vector<double> trial;
    if (llt.info() == Eigen::Success && h.allFinite()) {
      if (h.lpNorm<Eigen::Infinity>() <= p.options.step_tolerance) { run.stop = Stop::step; break; }
      trial = stepped(x.yaw, h, p.reference);
      const double predicted = 0.5 * h.dot(mu * h - x.g);  // L(0) − L(h) > 0
      gain = (x.half_cost - half_cost_at(p, trial)) / predicted;
    }
    if (gain > 0) {
      const double old_cost = x.half_cost;
      move_to(p, std::move(trial), x);
      mu *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * gain - 1.0, 3));
      nu = 2.0;
      if (old_cost - x.half_cost <= p.options.cost_tolerance * old_cost) { run.stop = Stop::cost_change; break; }
    } else {
      mu *= nu;
      nu *= 2.0;
      if (mu > damping_limit) { run.stop = Stop::no_progress; break; }
    }
  }
  run.yaw = std::move(x.yaw);
  return run;
}

// ---------------------------------------------------------------- starts

// Uniform in (−π, π] from 53 random bits, the same on every standard library.
double random_angle(std::uint64_t& state) {
  state += 0x9E3779B97F4A7C15ULL;  // splitmix64
  std::uint64_t z = state;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  const double unit = static_cast<double>(z >> 11) * 0x1.0p-53;  // [0, 1)
  return M_PI - 2.0 * M_PI * unit;
}

std::vector<double> start_yaws(int drones, int reference, bool random, std::uint64_t& state) {
  std::vector<double> yaw(drones, 0.0);
  if (random)
    for (int j = 0; j < drones; ++j)
      if (j != reference) yaw[j] = random_angle(state);
  return yaw;
}

bool converged(Stop s) { return s == Stop::gradient || s == Stop::step || s == Stop::cost_change; }

}  // namespace

// ---------------------------------------------------------------- public API

double wrap_angle(double theta) {
  double wrapped = std::remainder(theta, 2.0 * M_PI);  // [−π, π]
  if (wrapped <= -M_PI) wrapped += 2.0 * M_PI;
  return wrapped;
}

Eigen::VectorXd residual(const Sums& sums, const std::vector<double>& yaw) {
  check_yaw(yaw, checked_drones(sums));
  Eigen::VectorXd r;
  residual_into(sums, yaw, r);
  return r;
}

double cost(const Sums& sums, const std::vector<double>& yaw) { return residual(sums, yaw).squaredNorm(); }

Eigen::MatrixXd jacobian(const Sums& sums, const std::vector<double>& yaw, int reference) {
  const int drones = checked_drones(sums);
  check_yaw(yaw, drones);
  check_reference(reference, drones);
  Eigen::MatrixXd jac;
  jacobian_into(sums, yaw, reference, jac);
  return jac;
}

Eigen::VectorXd gradient(const Sums& sums, const std::vector<double>& yaw, int reference) {
  return 2.0 * jacobian(sums, yaw, reference).transpose() * residual(sums, yaw);
}

const char* to_string(Method m) {
  switch (m) {
    case Method::gauss_newton: return "gauss_newton";
    case Method::levenberg_marquardt: return "levenberg_marquardt";
  }
  return "unknown";
}

const char* to_string(Stop s) {
  switch (s) {
    case Stop::gradient: return "gradient";
    case Stop::step: return "step";
    case Stop::cost_change: return "cost_change";
    case Stop::iteration_cap: return "iteration_cap";
    case Stop::no_progress: return "no_progress";
  }
  return "unknown";
}

BaselineResult solve_rotations(const Sums& sums, int reference, Method method, const BaselineOptions& options) {
  const int drones = checked_drones(sums);
  check_reference(reference, drones);
  check_options(options);
  const auto begin = std::chrono::steady_clock::now();
  const Problem problem{sums, reference, sum_of_squares(sums), options};
  const bool random = options.random_starts > 0;
  std::uint64_t rng_state = options.seed;

  BaselineResult best;
  best.starts = random ? options.random_starts : 1;
  best.cost = std::numeric_limits<double>::infinity();
  for (int start = 0; start < best.starts; ++start) {
    std::vector<double> yaw = start_yaws(drones, reference, random, rng_state);
    Run run = method == Method::gauss_newton ? run_gauss_newton(problem, std::move(yaw))
                                             : run_levenberg_marquardt(problem, std::move(yaw));
    best.total_iterations += run.iterations;
    for (double& angle : run.yaw) angle = wrap_angle(angle);
    Eigen::VectorXd r;
    residual_into(sums, run.yaw, r);
    const double run_cost = r.squaredNorm();
    if (run_cost < best.cost) {
      best.cost = run_cost;
      best.yaw = std::move(run.yaw);
      best.iterations = run.iterations;
      best.stop = run.stop;
      best.converged = converged(run.stop);
    }
  }
  best.time_us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - begin).count();
  return best;
}

}  // namespace fact::baselines
