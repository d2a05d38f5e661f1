#include <sflsh/core/error.hpp>
#include <sflsh/reduced/reduced_potentials.hpp>

#include <algorithm>

namespace sflsh::reduced {

ReducedPotentials::ReducedPotentials(const model::Problem& problem, const Subspace& subspace,
                                     const std::vector<int>& active_nodes)
    : subspace_(subspace), active_nodes_(active_nodes) {
  for (const auto& potential : problem.potentials) {
    std::vector<int> active_of;
    for (int node : potential->nodes()) {
      const auto it = std::lower_bound(active_nodes.begin(), active_nodes.end(), node);
      require(it != active_nodes.end() && *it == node,
              "reduced: a contact potential acts on node {}, which no basis function moves (it could not respond)",
              node);
      active_of.push_back(static_cast<int>(it - active_nodes.begin()));
    }
    potentials_.push_back(potential.get());
    active_of_.push_back(std::move(active_of));
  }
}

Eigen::Vector3d ReducedPotentials::posed(const Eigen::VectorXd& q, const ReducedInertia& inertia, int a) const {
  Eigen::Vector3d u = Eigen::Vector3d::Zero();
  for (SparseRowMatrix::InnerIterator it(subspace_.basis, active_nodes_[static_cast<std::size_t>(a)]); it; ++it)
    u += it.value() * q.segment<3>(3 * it.col());
  return inertia.posed_prescribed().row(a).transpose() + inertia.frame().A[static_cast<std::size_t>(a)] * u;
}

bool ReducedPotentials::begin(double t0, double dt, const meshing::RowMatrixX3d& p_start,
                              const ReducedInertia& inertia) {
  terms_.clear();
  for (std::size_t k = 0; k < potentials_.size(); ++k) {
    const std::vector<int>& active_of = active_of_[k];
    meshing::RowMatrixX3d start(static_cast<Eigen::Index>(active_of.size()), 3),
        skinned(static_cast<Eigen::Index>(active_of.size()), 3);
    for (std::size_t e = 0; e < active_of.size(); ++e) {
      start.row(static_cast<Eigen::Index>(e)) = p_start.row(active_of[e]);
      skinned.row(static_cast<Eigen::Index>(e)) = inertia.posed_prescribed().row(active_of[e]);
    }
    if (!potentials_[k]->begin_substep(t0, dt, start, skinned)) continue;
    Term term;
    term.potential = potentials_[k];
    for (int c : term.potential->candidates()) term.active.push_back(active_of[static_cast<std::size_t>(c)]);
    terms_.push_back(std::move(term));
  }
  return active();
}

double ReducedPotentials::energy(const Eigen::VectorXd& q, const ReducedInertia& inertia) const {
  double sum = 0.0;
  for (const Term& term : terms_)
    for (std::size_t c = 0; c < term.active.size(); ++c)
      sum += term.potential->evaluate(static_cast<int>(c), posed(q, inertia, term.active[c]), nullptr, nullptr);
  return sum;
}

void ReducedPotentials::add_gradient(const Eigen::VectorXd& q, const ReducedInertia& inertia,
                                     Eigen::VectorXd& gradient) const {
  for (const Term& term : terms_) {
    for (std::size_t c = 0; c < term.active.size(); ++c) {
      const int a = term.active[c];
      Eigen::Vector3d g;
      term.potential->evaluate(static_cast<int>(c), posed(q, inertia, a), &g, nullptr);
      const Eigen::Vector3d pulled = inertia.frame().A[static_cast<std::size_t>(a)].transpose() * g;  // A_kᵀ ∇u_k
      for (SparseRowMatrix::InnerIterator it(subspace_.basis, active_nodes_[static_cast<std::size_t>(a)]); it; ++it)
        gradient.segment<3>(3 * it.col()) += it.value() * pulled;
    }
  }
}

void ReducedPotentials::add_hessian(const Eigen::VectorXd& q, const ReducedInertia& inertia,
                                    Eigen::MatrixXd& hessian) const {
  for (const Term& term : terms_) {
    for (std::size_t c = 0; c < term.active.size(); ++c) {
      const int a = term.active[c];
      const auto sa = static_cast<std::size_t>(a);
      Eigen::Vector3d g;
      Eigen::Matrix3d H;
      term.potential->evaluate(static_cast<int>(c), posed(q, inertia, a), &g, &H);
      const Eigen::Matrix3d block = inertia.frame().A[sa].transpose() * H * inertia.frame().A[sa];  // A_kᵀ ∇²u_k A_k
      const int node = active_nodes_[sa];
      for (SparseRowMatrix::InnerIterator si(subspace_.basis, node); si; ++si)
        for (SparseRowMatrix::InnerIterator ri(subspace_.basis, node); ri; ++ri)
          hessian.block<3, 3>(3 * si.col(), 3 * ri.col()) += si.value() * ri.value() * block;
    }
  }
}

bool ReducedPotentials::accept(const Eigen::VectorXd& q, const ReducedInertia& inertia) {
  bool accepted = true;
  for (const Term& term : terms_) {
    meshing::RowMatrixX3d p_end(static_cast<Eigen::Index>(term.active.size()), 3);
    for (std::size_t c = 0; c < term.active.size(); ++c)
      p_end.row(static_cast<Eigen::Index>(c)) = posed(q, inertia, term.active[c]).transpose();
    accepted = term.potential->accept_substep(p_end) && accepted;
  }
  return accepted;
}

int ReducedPotentials::max_refinements() const {
  int most = 0;
  for (const Term& term : terms_) most = std::max(most, term.potential->max_refinements());
  return most;
}

}  // namespace sflsh::reduced
