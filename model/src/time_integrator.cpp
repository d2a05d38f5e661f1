#include <sflsh/core/error.hpp>
#include <sflsh/model/kinematics.hpp>
#include <sflsh/model/time_integrator.hpp>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/LU>

#include <cmath>
#include <vector>

namespace sflsh::model {

namespace {

/// BDF2 keeps its history while the step grows at most this much (zero-stable below 1 + √2).
constexpr double kMaxBdf2Ratio = 2.0;

}  // namespace

Integrator parse_integrator(std::string_view text, std::string_view where) {
  if (text == "backward_euler") return Integrator::backward_euler;
  if (text == "bdf2") return Integrator::bdf2;
  if (text == "newmark") return Integrator::newmark;
  throw_error("{}: integrator '{}' is not one of backward_euler, bdf2, newmark", where, text);
}

std::string_view to_string(Integrator integrator) {
  switch (integrator) {
    case Integrator::backward_euler:
      return "backward_euler";
    case Integrator::bdf2:
      return "bdf2";
    case Integrator::newmark:
      return "newmark";
  }
  return "backward_euler";
}

InertiaTarget inertia_target(Integrator integrator, const PosedHistory& history, double h) {
  require(std::isfinite(h) && h > 0.0, "integrator: step must be positive, got {}", h);
  require(history.v.size() == history.p.size(), "integrator: {} velocities for {} positions", history.v.size(),
          history.p.size());
  InertiaTarget target;
  target.h = h;
  if (integrator == Integrator::bdf2) {
    const double omega = history.h_previous > 0.0 ? h / history.h_previous : 0.0;
    const bool has_previous =
        history.p_previous.size() == history.p.size() && history.v_previous.size() == history.p.size();
    if (has_previous && omega > 0.0 && omega <= kMaxBdf2Ratio) {
      const double a0 = (1.0 + 2.0 * omega) / (1.0 + omega), a1 = -(1.0 + omega), a2 = omega * omega / (1.0 + omega);
      target.integrator = Integrator::bdf2;
      target.h_eff = h / a0;
      target.p_tilde = -(a1 * history.p + a2 * history.p_previous) / a0 -
                       target.h_eff * (a1 * history.v + a2 * history.v_previous) / a0;
      return target;
    }
    integrator = Integrator::backward_euler;  // start-up (or restart) step
  }
  if (integrator == Integrator::newmark) {
    require(history.a.size() == history.p.size(),
            "Newmark: the accelerations at t_n are missing (initial_acceleration)");
    target.integrator = Integrator::newmark;
    target.h_eff = 0.5 * h;
    target.p_tilde = history.p + h * history.v + 0.25 * h * h * history.a;
    return target;
  }
  target.integrator = Integrator::backward_euler;
  target.h_eff = h;
  target.p_tilde = history.p + h * history.v;
  return target;
}

void advance_history(const InertiaTarget& target, PosedHistory& history, const Eigen::VectorXd& p_new) {
  require(p_new.size() == history.p.size(), "integrator: {} new positions for a history of {}", p_new.size(),
          history.p.size());
  const double h = target.h;
  Eigen::VectorXd v_new, a_new;
  switch (target.integrator) {
    case Integrator::backward_euler:
      v_new = (p_new - history.p) / h;
      a_new = (v_new - history.v) / h;
      break;
    case Integrator::bdf2: {
      const double omega = h / history.h_previous;
      const double a0 = (1.0 + 2.0 * omega) / (1.0 + omega), a1 = -(1.0 + omega), a2 = omega * omega / (1.0 + omega);
      v_new = (a0 * p_new + a1 * history.p + a2 * history.p_previous) / h;
      a_new = (a0 * v_new + a1 * history.v + a2 * history.v_previous) / h;
      break;
    }
    case Integrator::newmark:
      a_new = (p_new - target.p_tilde) / (target.h_eff * target.h_eff);
      v_new = history.v + 0.5 * h * (history.a + a_new);
      break;
  }
  history.p_previous = std::move(history.p);
  history.v_previous = std::move(history.v);
  history.h_previous = h;
  history.p = p_new;
  history.v = std::move(v_new);
  history.a = std::move(a_new);
}

PosedHistory history_of(const State& state, Eigen::VectorXd p) {
  PosedHistory history;
  history.p = std::move(p);
  history.v = state.w;
  history.a = state.a;
  history.p_previous = state.p_previous;
  history.v_previous = state.w_previous;
  history.h_previous = state.h_previous;
  return history;
}

void store_history(const PosedHistory& history, State& state) {
  state.w = history.v;
  state.a = history.a;
  state.p_previous = history.p_previous;
  state.w_previous = history.v_previous;
  state.h_previous = history.h_previous;
}

Eigen::VectorXd initial_acceleration(const Problem& problem, const State& state) {
  const int n = problem.num_nodes();
  const Eigen::Index dofs = problem.num_dofs();
  require(state.x.size() == dofs && state.w.size() == dofs,
          "initial acceleration: state of {} / {} entries, expected {}", state.x.size(), state.w.size(), dofs);
  Eigen::VectorXd a = Eigen::VectorXd::Zero(dofs);
  if (!problem.dynamic()) return a;

  // The prescribed motion's acceleration on every node (kinematics.hpp: free components of x held, prescribed ones
  // following u(t)); free components are replaced below.
  const std::vector<char> constrained = problem.dirichlet.mask(n);
  Eigen::VectorXd x = state.x;
  problem.apply_dirichlet(state.t, x);
  a = kinematic_acceleration(problem, x, state.t);

  // Posed forces r_i = −A_i⁻ᵀ ∇_i E + m_i g on the free components.
  NodeFrame frame;
  problem.frame(state.t, frame);
  const Eigen::VectorXd gradient = evaluate_elastic(problem, x, true).gradient;
  Eigen::VectorXd r(dofs);
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix3d A_inv_t = frame.A[static_cast<std::size_t>(i)].inverse().transpose();
    r.segment<3>(3 * i) = -A_inv_t * gradient.segment<3>(3 * i) + problem.mass[i] * problem.gravity;
  }
  require(r.allFinite(), "initial acceleration: the elastic forces are not finite at t = {} s", state.t);

  // M_FF a_F = r_F − M_FC a_C, with M ⊗ I₃ at component level.
  const Eigen::SparseMatrix<double, Eigen::RowMajor> M = problem.mass_matrix();
  std::vector<Eigen::Index> free_index(static_cast<std::size_t>(dofs), -1);
  Eigen::Index num_free = 0;
  for (Eigen::Index d = 0; d < dofs; ++d)
    if (!constrained[static_cast<std::size_t>(d)]) free_index[static_cast<std::size_t>(d)] = num_free++;
  if (num_free == 0) return a;
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::VectorXd rhs(num_free);
  for (Eigen::Index d = 0; d < dofs; ++d) {
    const Eigen::Index row = free_index[static_cast<std::size_t>(d)];
    if (row < 0) continue;
    rhs[row] = r[d];
    const int i = static_cast<int>(d / 3), axis = static_cast<int>(d % 3);
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(M, i); it; ++it) {
      const Eigen::Index col_dof = 3 * it.col() + axis;
      const Eigen::Index col = free_index[static_cast<std::size_t>(col_dof)];
      if (col >= 0) {
        entries.emplace_back(row, col, it.value());
      } else {
        rhs[row] -= it.value() * a[col_dof];
      }
    }
  }
  Eigen::SparseMatrix<double> M_ff(num_free, num_free);
  M_ff.setFromTriplets(entries.begin(), entries.end());
  // CG with the diagonal preconditioner: a consistent or lumped mass matrix is spectrally equivalent to its
  // diagonal (condition number ≤ 5 for linear tets, whatever the mesh size), so CG converges in a few dozen
  // iterations at any size, where a sparse Cholesky factor of a 10⁵-tet layer took seconds and grows
  // superlinearly (docs/decisions.md "Initial acceleration by CG").
  const Eigen::VectorXd diagonal = M_ff.diagonal();
  require((diagonal.array() > 0.0).all(), "initial acceleration: a free node has no mass");
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> cg(M_ff);
  cg.setTolerance(1e-14);  // relative residual: round-off level for a matrix this well conditioned
  cg.setMaxIterations(1000);
  const Eigen::VectorXd a_free = cg.solve(rhs);
  require(cg.info() == Eigen::Success && a_free.allFinite(),
          "initial acceleration: the mass system did not converge (relative residual {:.3g} after {} iterations)",
          cg.error(), cg.iterations());
  for (Eigen::Index d = 0; d < dofs; ++d) {
    const Eigen::Index row = free_index[static_cast<std::size_t>(d)];
    if (row >= 0) a[d] = a_free[row];
  }
  return a;
}

}  // namespace sflsh::model
