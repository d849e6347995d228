// The zero optimum: when C ⪰ 0 and its null space holds a feasible X, the optimum is 0.
//
// ⟨C, X⟩ ≥ 0 for every X ⪰ 0 when C ⪰ 0, so a feasible X with C X = 0 is optimal, and Λ = 0
// certifies it (S = C ⪰ 0, tr Λ = 0). Such X are X = V P Vᵀ with V the n × k orthonormal basis of
// null(C) and P ⪰ 0 (k × k) meeting the block constraints, which are linear in P:
//     A(P)_i = V_i P V_iᵀ = I_d   for every block i    (V_i: the d × k rows of block i of V),
// N·d(d+1)/2 equations on the k(k+1)/2 entries of P. The paper's plain relaxation with N + 1
// rounds has k = N − 1 and, from N ≈ 10 on, a zero optimum of rank N − 1; a low-rank C of rank
// below about n/2 has one too. The interior point reaches it in 25–30 iterations (its gap falls
// only linearly toward a zero optimum); this finds it in 1–6 Newton steps (1 in most) (BENCHMARKS.md,
// session 22).
//
// The steps are Newton's for the analytic centre of that set (maximise log det P subject to
// A(P) = b) from the infeasible start P = (n/k)·I (tr X = n, as for any feasible X):
//     ΔP = P − P A*(w) P,   M w = 2 A(P) − b,   M_(ia)(jb) = tr(E_a X_ij E_b X_ji),
// X = V P Vᵀ (n × n), E_a the symmetric d × d basis (E_a = e_x e_yᵀ + e_y e_xᵀ for x < y,
// e_x e_xᵀ on the diagonal), A*(w) = Vᵀ blkdiag(Σ_a w_ia E_a) V. A full step meets A(P) = b up to
// rounding, so the first full step that keeps P ≻ 0 ends it; a half step halves the residual. When
// neither keeps P positive definite the set is taken to be empty (NullSpaceOutcome::empty; on 480
// sweep instances every zero optimum was found with full or half steps, in at most 6 steps;
// BENCHMARKS.md, session 22), and the interior point runs.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "internal.h"
#include "step_length.h"

namespace fact::sdp::detail {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
// A d × d block, d ≤ 2: on the stack.
using BlockMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 2, 2>;

constexpr int kMaxSteps = 10;            // Newton steps before it gives up (the set not taken to be empty)
constexpr double kFeasibleResidual = 1e-9;  // largest |X_ii − I| entry that ends the steps
// Added to M's diagonal, relative to its largest diagonal entry, before it is factored: M is
// singular when the block constraints are dependent on the face (a null space of dimension d that
// holds a feasible X: 3 unknowns in P for 3N equations), and a w in M's null space has A*(w) = 0
// on the face (M w = 0 means ⟨A*(w), X A*(w) X⟩ = 0), so it does not change ΔP; the shift only
// keeps the factor finite.
constexpr double kSystemShift = 1e-12;

// One element of the symmetric d × d basis: e_x e_yᵀ + e_y e_xᵀ (x < y) or e_x e_xᵀ (x = y).
struct BasisElement {
  int x, y;
};

std::vector<BasisElement> symmetric_basis(int d) {
  std::vector<BasisElement> basis;
  for (int x = 0; x < d; ++x) basis.push_back({x, x});
  for (int x = 0; x < d; ++x)
    for (int y = x + 1; y < d; ++y) basis.push_back({x, y});
  return basis;
}

// tr(e_x e_yᵀ B e_z e_wᵀ Bᵀ) = B_yz B_xw, summed over the terms of E_a = (x, y) and E_b = (z, w).
double basis_product(const BasisElement& a, const BasisElement& b, const Eigen::Ref<const MatrixXd>& B) {
  double sum = 0;
  for (int ta = 0; ta < (a.x == a.y ? 1 : 2); ++ta)
    for (int tb = 0; tb < (b.x == b.y ? 1 : 2); ++tb) {
      const int x = ta ? a.y : a.x, y = ta ? a.x : a.y, z = tb ? b.y : b.x, w = tb ? b.x : b.y;
      sum += B(y, z) * B(x, w);
    }
  return sum;
}

// ⟨E_a, B⟩ for a d × d block B.
double basis_inner(const BasisElement& a, const Eigen::Ref<const MatrixXd>& B) {
  return a.x == a.y ? B(a.x, a.x) : B(a.x, a.y) + B(a.y, a.x);
}

// Every matrix of one run. n = d·N rows, k null-space columns, m = N·d(d+1)/2 constraints.
struct Workspace {
  Workspace(Eigen::Index n, Eigen::Index k, Eigen::Index m)
      : Y(n, k), X(n, n), DV(n, k), P(k, k), step(k, k), trial(k, k), AW(k, k), PAW(k, k), M(m, m), system(m),
        rhs(m), w(m) {}
  MatrixXd Y;      // V L, L the Cholesky factor of P: X = Y Yᵀ, n × k
  MatrixXd X;      // V P Vᵀ (lower triangle), n × n
  MatrixXd DV;     // blkdiag(Σ_a w_ia E_a) V, n × k
  MatrixXd P;      // the current P, k × k
  MatrixXd step;   // ΔP, k × k
  MatrixXd trial;  // P + t ΔP, k × k, then its Cholesky factor in the lower triangle
  MatrixXd AW;     // A*(w) = Vᵀ DV, k × k
  MatrixXd PAW;    // P A*(w), k × k
  MatrixXd M;      // Newton system (lower triangle), m × m
  SpdSolver system;  // M + δI factored
  VectorXd rhs, w;  // 2 A(P) − b and its solution, m
};

// ws.w = (M + δI)⁻¹ rhs, δ = max(kSystemShift, m·ε) · max diag M (above Cholesky's own rounding
// for any m); false when even the shifted M does not factor.
bool solve_newton_system(Workspace& ws) {
  const double relative =
      std::max(kSystemShift, static_cast<double>(ws.M.rows()) * std::numeric_limits<double>::epsilon());
  ws.M.diagonal().array() += relative * ws.M.diagonal().maxCoeff();
  if (!ws.system.factor(ws.M)) return false;
  ws.system.solve(ws.rhs, ws.w);
  return true;
}

// Largest |X_ii − I| entry over the blocks.
double block_residual(const MatrixXd& X, int d) {
  double worst = 0;
  for (Eigen::Index i = 0; i < X.rows(); i += d)
    for (int a = 0; a < d; ++a)
      for (int b = 0; b <= a; ++b) worst = std::max(worst, std::abs(X(i + a, i + b) - (a == b ? 1.0 : 0.0)));
  return worst;
}

// ws.M (lower triangle) and ws.rhs at X = ws.X.
void newton_system(const MatrixXd& X, int d, const std::vector<BasisElement>& basis, Workspace& ws) {
  const Eigen::Index blocks = X.rows() / d, q = static_cast<Eigen::Index>(basis.size());
  for (Eigen::Index j = 0; j < blocks; ++j)
    for (Eigen::Index i = j; i < blocks; ++i) {
      const auto B = X.block(d * i, d * j, d, d);  // X_ij (i ≥ j: lower triangle)
      for (Eigen::Index a = 0; a < q; ++a)
        for (Eigen::Index b = 0; b < q; ++b) ws.M(q * i + a, q * j + b) = basis_product(basis[a], basis[b], B);
    }
  for (Eigen::Index i = 0; i < blocks; ++i)
    for (Eigen::Index a = 0; a < q; ++a) {
      const BasisElement& e = basis[a];
      ws.rhs[q * i + a] = 2.0 * basis_inner(e, X.block(d * i, d * i, d, d)) - (e.x == e.y ? 1.0 : 0.0);
    }
}

// X = Y Yᵀ with Y = V L, L the Cholesky factor of P in ws.trial: the lower triangle, and the
// diagonal blocks whole.
void factor_and_form(const MatrixXd& V, int d, Workspace& ws) {
  ws.Y.noalias() = V * ws.trial.triangularView<Eigen::Lower>();
  ws.X.triangularView<Eigen::Lower>().setZero();
  ws.X.selfadjointView<Eigen::Lower>().rankUpdate(ws.Y);
  for (Eigen::Index i = 0; i < ws.X.rows(); i += d)
    for (int a = 0; a < d; ++a)
      for (int b = a + 1; b < d; ++b) ws.X(i + a, i + b) = ws.X(i + b, i + a);
}

// ws.step = ΔP = P − P A*(w) P for the solved w.
void newton_step(const MatrixXd& V, int d, const std::vector<BasisElement>& basis, Workspace& ws) {
  const Eigen::Index q = static_cast<Eigen::Index>(basis.size());
  for (Eigen::Index i = 0; i < V.rows() / d; ++i) {
    BlockMatrix D = BlockMatrix::Zero(d, d);  // Σ_a w_ia E_a, d × d
    for (Eigen::Index a = 0; a < q; ++a) {
      D(basis[a].x, basis[a].y) += ws.w[q * i + a];
      if (basis[a].x != basis[a].y) D(basis[a].y, basis[a].x) += ws.w[q * i + a];
    }
    ws.DV.middleRows(d * i, d).noalias() = D * V.middleRows(d * i, d);
  }
  ws.AW.noalias() = V.transpose() * ws.DV;
  ws.PAW.noalias() = ws.P * ws.AW;
  ws.step = ws.P;
  ws.step.noalias() -= ws.PAW * ws.P;
  symmetrize(ws.step);
}

// P + t ΔP into ws.trial, factored in place; true when positive definite.
bool try_step(double t, Workspace& ws) {
  ws.trial = ws.P + t * ws.step;
  return cholesky_in_place(ws.trial);
}

}  // namespace

NullSpaceRoom room_in_null_space(int k, Eigen::Index n, int d) {
  // N·d(d+1)/2 constraints on P (k × k): k(k+1)/2 unknowns; a rank-d factor V A (A k × d) has
  // d·k of them, less the d(d−1)/2 of its rotation.
  const long dim = k, constraints = static_cast<long>(n / d) * d * (d + 1) / 2;
  NullSpaceRoom room;
  room.feasible = dim >= d && dim * (dim + 1) / 2 >= constraints;
  room.rank_d = room.feasible && d * dim - d * (d - 1) / 2 >= constraints;
  room.few_points = room.feasible && dim * (dim + 1) / 2 - constraints < static_cast<long>(n / d);
  return room;
}

int pivoted_rank(const Eigen::MatrixXd& C) {
  const Eigen::Index n = C.rows();
  const double tol = eigensolver_error(n, C.diagonal().cwiseAbs().maxCoeff());
  const PivotedCholesky<MatrixXd> f = pivoted_cholesky_above(C, tol);
  const Eigen::Index r = f.rank;
  const auto& L = f.Y;  // C = L Lᵀ on the pivot rows and columns, n × r in use
  const int not_psd = static_cast<int>(n);
  for (Eigen::Index i = 0; i < n; ++i)
    if (!f.pivoted[i] && f.rest[i] < -tol) return not_psd;
  // The remainder C − L Lᵀ on the rows not pivoted: PSD with a diagonal ≤ tol only if every entry
  // is (|a_ij| ≤ √(a_ii a_jj)); an indefinite C with a small diagonal stops early otherwise.
  for (Eigen::Index j = 0; j < n; ++j)
    for (Eigen::Index i = j + 1; !f.pivoted[j] && i < n; ++i)
      if (!f.pivoted[i] && std::abs(C(i, j) - L.row(i).head(r).dot(L.row(j).head(r))) > tol) return not_psd;
  return static_cast<int>(r);
}

NullSpace null_space_of(const Eigen::MatrixXd& C) {
  NullSpace null;
  const Eigen::SelfAdjointEigenSolver<MatrixXd> solver(C);
  null.eigenvalues = solver.eigenvalues();
  const Eigen::VectorXd& eigenvalues = null.eigenvalues;
  const Eigen::Index n = C.rows();
  const double tol = eigensolver_error(n, eigenvalues.cwiseAbs().maxCoeff());
  null.positive_semidefinite = eigenvalues[0] >= -tol;
  null.dimension = static_cast<int>((eigenvalues.array().abs() <= tol).count());
  const Eigen::Index negative = (eigenvalues.array() < -tol).count();  // ascending: they come first
  null.basis = solver.eigenvectors().middleCols(negative, null.dimension);
  return null;
}

bool zero_optimum(const Eigen::MatrixXd& C, int d, const NullSpace& null, NullSpaceOutcome& out) {
  const Eigen::Index n = C.rows(), blocks = n / d, k = null.dimension;
  const std::vector<BasisElement> basis = symmetric_basis(d);
  const Eigen::Index m = blocks * static_cast<Eigen::Index>(basis.size());
  if (!null.positive_semidefinite || k < d) return false;

  const MatrixXd& V = null.basis;  // orthonormal basis of null(C), n × k
  Workspace ws(n, k, m);
  ws.P = MatrixXd::Identity(k, k) * (static_cast<double>(n) / static_cast<double>(k));
  ws.trial = ws.P;
  if (!cholesky_in_place(ws.trial)) return false;
  factor_and_form(V, d, ws);
  for (out.steps = 0;; ++out.steps) {
    if (block_residual(ws.X, d) <= kFeasibleResidual) {
      out.Y = ws.Y;
      if (!project_blocks(out.Y, d)) return false;
      out.certificate.lambda = MatrixXd::Zero(n, d);  // Λ = 0: S = C
      out.certificate.eigenvalues = null.eigenvalues;
      out.certificate.trace_lambda = 0;
      bound_from_spectrum(out.certificate);
      return true;
    }
    if (out.steps == kMaxSteps) return false;
    newton_system(ws.X, d, basis, ws);
    if (!solve_newton_system(ws)) {  // (a step that fails counts, as one neither of whose lengths fits)
      ++out.steps;
      return false;
    }
    newton_step(V, d, basis, ws);
    const double t = try_step(1.0, ws) ? 1.0 : try_step(0.5, ws) ? 0.5 : 0.0;
    if (t == 0.0) {  // neither step keeps P ≻ 0: taken as no feasible P
      ++out.steps;
      out.empty = true;
      return false;
    }
    ws.P += t * ws.step;
    factor_and_form(V, d, ws);
  }
}

}  // namespace fact::sdp::detail
