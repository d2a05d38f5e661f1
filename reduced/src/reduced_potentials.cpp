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

void add_root_node_blocks(const Subspace& subspace, const RootFrame& root, int node, const Eigen::Matrix3d& A,
                          const Eigen::Vector3d& p, const Eigen::Vector3d& g, const Eigen::Matrix3d& H,
                          Eigen::MatrixXd& hessian) {
  // y = R(p − c) + c + τ: ∂y/∂τ = I, ∂y/∂θ_k = ∂_kR d (d = p − c), ∂y/∂t_s = b_s R A;
  // ∂²u = Jᵀ∇²u J + ∇uᵀ∂²y, with ∂²y/∂θ_k∂θ_l = ∂²_klR d and ∂²y/∂θ_k∂t_s = b_s ∂_kR A.
  const Eigen::Vector3d d = p - root.pivot;
  Eigen::Matrix3d Y;  // columns ∂y/∂θ_k
  for (int k = 0; k < 3; ++k) Y.col(k) = root.rotation.dR[static_cast<std::size_t>(k)] * d;
  const Eigen::Index o = root.offset;
  Eigen::Matrix3d theta_theta = Y.transpose() * H * Y;
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3; ++l)
      theta_theta(k, l) += g.dot(root.rotation.d2R[static_cast<std::size_t>(k)][static_cast<std::size_t>(l)] * d);
  hessian.block<3, 3>(o, o) += theta_theta;
  const Eigen::Matrix3d theta_tau = Y.transpose() * H;
  hessian.block<3, 3>(o, o + 3) += theta_tau;
  hessian.block<3, 3>(o + 3, o) += theta_tau.transpose();
  hessian.block<3, 3>(o + 3, o + 3) += H;
  // Soft tissue × root: per basis function s, b_s [(R A)ᵀ H Y + (∂_kR A)ᵀ g] (θ columns) and b_s (R A)ᵀ H (τ columns).
  const Eigen::Matrix3d RA = root.rotation.R * A;
  Eigen::Matrix3d q_theta = RA.transpose() * H * Y;
  for (int k = 0; k < 3; ++k) q_theta.col(k) += (root.rotation.dR[static_cast<std::size_t>(k)] * A).transpose() * g;
  const Eigen::Matrix3d q_tau = RA.transpose() * H;
  const Eigen::Matrix3d block = RA.transpose() * H * RA;  // A_kᵀ Rᵀ ∇²u_k R A_k
  for (SparseRowMatrix::InnerIterator it(subspace.basis, node); it; ++it) {
    const Eigen::Index s = 3 * it.col();
    for (SparseRowMatrix::InnerIterator ri(subspace.basis, node); ri; ++ri)
      hessian.block<3, 3>(s, 3 * ri.col()) += it.value() * ri.value() * block;
    hessian.block<3, 3>(s, o) += it.value() * q_theta;
    hessian.block<3, 3>(o, s) += it.value() * q_theta.transpose();
    hessian.block<3, 3>(s, o + 3) += it.value() * q_tau;
    hessian.block<3, 3>(o + 3, s) += it.value() * q_tau.transpose();
  }
}

Eigen::Vector3d posed_node(const Subspace& subspace, const ReducedInertia& inertia, const Eigen::VectorXd& q, int a) {
  const auto sa = static_cast<std::size_t>(a);
  Eigen::Vector3d u = Eigen::Vector3d::Zero();
  for (SparseRowMatrix::InnerIterator it(subspace.basis, inertia.active_nodes()[sa]); it; ++it)
    u += it.value() * q.segment<3>(3 * it.col());
  return inertia.posed_prescribed().row(a).transpose() + inertia.frame().A[sa] * u;
}

Eigen::Vector3d ReducedPotentials::posed(const Eigen::VectorXd& q, const ReducedInertia& inertia, int a) const {
  return posed_node(subspace_, inertia, q, a);
}

bool ReducedPotentials::begin(double t0, double dt, const meshing::RowMatrixX3d& p_start, const ReducedInertia& inertia,
                              const RootFrame* root) {
  terms_.clear();
  for (std::size_t k = 0; k < potentials_.size(); ++k) {
    const std::vector<int>& active_of = active_of_[k];
    meshing::RowMatrixX3d start(static_cast<Eigen::Index>(active_of.size()), 3),
        skinned(static_cast<Eigen::Index>(active_of.size()), 3);
    for (std::size_t e = 0; e < active_of.size(); ++e) {
      start.row(static_cast<Eigen::Index>(e)) = p_start.row(active_of[e]);
      const Eigen::Vector3d z = inertia.posed_prescribed().row(active_of[e]).transpose();
      skinned.row(static_cast<Eigen::Index>(e)) = (root ? root->apply(z) : z).transpose();
    }
    if (!potentials_[k]->begin_substep(t0, dt, start, skinned)) continue;
    Term term;
    term.potential = potentials_[k];
    for (int c : term.potential->candidates()) term.active.push_back(active_of[static_cast<std::size_t>(c)]);
    terms_.push_back(std::move(term));
  }
  return active();
}

double ReducedPotentials::energy(const Eigen::VectorXd& q, const ReducedInertia& inertia, const RootFrame* root) const {
  double sum = 0.0;
  for (const Term& term : terms_)
    for (std::size_t c = 0; c < term.active.size(); ++c) {
      const Eigen::Vector3d p = posed(q, inertia, term.active[c]);
      sum += term.potential->evaluate(static_cast<int>(c), root ? root->apply(p) : p, nullptr, nullptr);
    }
  return sum;
}

void ReducedPotentials::add_gradient(const Eigen::VectorXd& q, const ReducedInertia& inertia, Eigen::VectorXd& gradient,
                                     const RootFrame* root) const {
  for (const Term& term : terms_) {
    for (std::size_t c = 0; c < term.active.size(); ++c) {
      const int a = term.active[c];
      Eigen::Vector3d g;
      const Eigen::Vector3d p = posed(q, inertia, a);
      term.potential->evaluate(static_cast<int>(c), root ? root->apply(p) : p, &g, nullptr);
      if (root) {  // ∂u/∂τ = ∇u, ∂u/∂θ_k = ∇uᵀ ∂_kR (p − c); the soft tissue sees Rᵀ∇u
        const Eigen::Vector3d d = p - root->pivot;
        for (int k = 0; k < 3; ++k)
          gradient[root->offset + k] += g.dot(root->rotation.dR[static_cast<std::size_t>(k)] * d);
        gradient.segment<3>(root->offset + 3) += g;
        g = root->rotation.R.transpose() * g;
      }
      const Eigen::Vector3d pulled = inertia.frame().A[static_cast<std::size_t>(a)].transpose() * g;  // A_kᵀ ∇u_k
      for (SparseRowMatrix::InnerIterator it(subspace_.basis, active_nodes_[static_cast<std::size_t>(a)]); it; ++it)
        gradient.segment<3>(3 * it.col()) += it.value() * pulled;
    }
  }
}

void ReducedPotentials::add_hessian(const Eigen::VectorXd& q, const ReducedInertia& inertia, Eigen::MatrixXd& hessian,
                                    const RootFrame* root) const {
  for (const Term& term : terms_) {
    for (std::size_t c = 0; c < term.active.size(); ++c) {
      const int a = term.active[c];
      const auto sa = static_cast<std::size_t>(a);
      Eigen::Vector3d g;
      Eigen::Matrix3d H;
      const Eigen::Vector3d p = posed(q, inertia, a);
      term.potential->evaluate(static_cast<int>(c), root ? root->apply(p) : p, &g, &H);
      const int node = active_nodes_[sa];
      if (root) {
        add_root_node_blocks(subspace_, *root, node, inertia.frame().A[sa], p, g, H, hessian);
        continue;
      }
      const Eigen::Matrix3d& A = inertia.frame().A[sa];
      const Eigen::Matrix3d block = A.transpose() * H * A;  // A_kᵀ ∇²u_k A_k
      for (SparseRowMatrix::InnerIterator si(subspace_.basis, node); si; ++si)
        for (SparseRowMatrix::InnerIterator ri(subspace_.basis, node); ri; ++ri)
          hessian.block<3, 3>(3 * si.col(), 3 * ri.col()) += si.value() * ri.value() * block;
    }
  }
}

bool ReducedPotentials::accept(const Eigen::VectorXd& q, const ReducedInertia& inertia, const RootFrame* root) {
  bool accepted = true;
  for (const Term& term : terms_) {
    meshing::RowMatrixX3d p_end(static_cast<Eigen::Index>(term.active.size()), 3);
    for (std::size_t c = 0; c < term.active.size(); ++c) {
      const Eigen::Vector3d p = posed(q, inertia, term.active[c]);
      p_end.row(static_cast<Eigen::Index>(c)) = (root ? root->apply(p) : p).transpose();
    }
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
