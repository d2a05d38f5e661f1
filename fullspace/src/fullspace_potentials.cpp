// Backward Euler on PETSc: the problem's node potentials (contact, node_potential.hpp) in Φ. Each rank adds
// the terms of the candidates it owns; begin/accept run identically on every rank (every rank keeps the full
// state), so all ranks take the same decisions without communication.
#include "fullspace_solver_impl.hpp"

namespace sflsh::fullspace {

namespace {

Eigen::Vector3d posed(const NodeFrame& frame, const Eigen::VectorXd& x, int node) {
  return frame.A[static_cast<std::size_t>(node)] * x.segment<3>(3 * node) + frame.d.row(node).transpose();
}

}  // namespace

void FullSpaceSolver::Impl::begin_potentials(const RowMatrixX3d& p_n, double t0, double dt) {
  potential_terms.clear();
  if (problem.potentials.empty()) return;
  const auto clock = Clock::now();
  Eigen::VectorXd rest_now = Eigen::Map<const Eigen::VectorXd>(problem.rest.data(), problem.num_dofs());
  problem.apply_dirichlet(t0 + dt, rest_now);
  for (const auto& potential : problem.potentials) {
    const std::vector<int>& nodes = potential->nodes();
    RowMatrixX3d start(static_cast<Eigen::Index>(nodes.size()), 3), skinned(static_cast<Eigen::Index>(nodes.size()), 3);
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      start.row(static_cast<Eigen::Index>(k)) = p_n.row(nodes[k]);
      skinned.row(static_cast<Eigen::Index>(k)) = posed(frame, rest_now, nodes[k]).transpose();
    }
    if (!potential->begin_substep(t0, dt, start, skinned)) continue;
    PotentialTerm term;
    term.potential = potential.get();
    for (int c : potential->candidates()) term.node.push_back(nodes[static_cast<std::size_t>(c)]);
    for (std::size_t c = 0; c < term.node.size(); ++c)
      if (owns(term.node[c])) term.owned.push_back(static_cast<int>(c));
    potential_terms.push_back(std::move(term));
  }
  if (stats) stats->potential_seconds += seconds_since(clock);
}

double FullSpaceSolver::Impl::potential_energy(const Eigen::VectorXd& x) const {
  if (potential_terms.empty()) return 0.0;
  const auto clock = Clock::now();
  double sum = 0.0;
  for (const PotentialTerm& term : potential_terms) {
    for (int c : term.owned) sum += term.potential->evaluate(c, posed(frame, x, term.node[static_cast<std::size_t>(c)]), nullptr, nullptr);
  }
  if (stats) stats->potential_seconds += seconds_since(clock);
  return sum;
}

void FullSpaceSolver::Impl::add_potential_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& g) const {
  if (potential_terms.empty()) return;
  const auto clock = Clock::now();
  for (const PotentialTerm& term : potential_terms) {
    for (int c : term.owned) {
      const int i = term.node[static_cast<std::size_t>(c)];
      Eigen::Vector3d gradient;
      term.potential->evaluate(c, posed(frame, x, i), &gradient, nullptr);
      g.segment<3>(3 * i) += frame.A[static_cast<std::size_t>(i)].transpose() * gradient;   // A_iᵀ ∇u
    }
  }
  if (stats) stats->potential_seconds += seconds_since(clock);
}

std::vector<std::pair<int, Eigen::Matrix3d>> FullSpaceSolver::Impl::potential_hessian_blocks(const Eigen::VectorXd& x) const {
  std::vector<std::pair<int, Eigen::Matrix3d>> blocks;
  if (potential_terms.empty()) return blocks;
  const auto clock = Clock::now();
  for (const PotentialTerm& term : potential_terms) {
    for (int c : term.owned) {
      const int i = term.node[static_cast<std::size_t>(c)];
      const auto si = static_cast<std::size_t>(i);
      Eigen::Vector3d gradient;
      Eigen::Matrix3d hessian;
      term.potential->evaluate(c, posed(frame, x, i), &gradient, &hessian);
      Eigen::Matrix3d block = frame.A[si].transpose() * hessian * frame.A[si];   // A_iᵀ ∇²u A_i
      for (int k = 0; k < 3; ++k) {
        if (!constrained[3 * si + static_cast<std::size_t>(k)]) continue;
        block.row(k).setZero();
        block.col(k).setZero();
      }
      blocks.emplace_back(i, block);
    }
  }
  if (stats) stats->potential_seconds += seconds_since(clock);
  return blocks;
}

bool FullSpaceSolver::Impl::accept_potentials(const Eigen::VectorXd& x_new) {
  if (potential_terms.empty()) return true;
  const auto clock = Clock::now();
  bool accepted = true;
  for (const PotentialTerm& term : potential_terms) {
    RowMatrixX3d p_end(static_cast<Eigen::Index>(term.node.size()), 3);
    for (std::size_t c = 0; c < term.node.size(); ++c) p_end.row(static_cast<Eigen::Index>(c)) = posed(frame, x_new, term.node[c]).transpose();
    accepted = term.potential->accept_substep(p_end) && accepted;   // every potential sees the result
  }
  if (stats) stats->potential_seconds += seconds_since(clock);
  return accepted;
}

}  // namespace sflsh::fullspace
