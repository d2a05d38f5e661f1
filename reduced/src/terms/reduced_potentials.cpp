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

void add_deviation_node_gradient(const Subspace& subspace, const DeviationFrame& frame, int node,
                                 const Eigen::Matrix3d& A, const Eigen::Vector3d& p, const Eigen::Vector3d& g,
                                 Eigen::VectorXd& gradient) {
  // ∂u/∂r = (∂y/∂r)ᵀ g; the soft tissue sees (L A)ᵀ g.
  Eigen::Matrix<double, 3, Eigen::Dynamic> J;
  frame.jacobian(node, p, J);
  gradient.segment(frame.offset, frame.size) += J.transpose() * g;
  const Eigen::Vector3d pulled = (frame.linear(node) * A).transpose() * g;
  for (SparseRowMatrix::InnerIterator it(subspace.basis, node); it; ++it)
    gradient.segment<3>(3 * it.col()) += it.value() * pulled;
}

void add_deviation_node_blocks(const Subspace& subspace, const DeviationFrame& frame, int node,
                               const Eigen::Matrix3d& A, const Eigen::Vector3d& p, const Eigen::Vector3d& g,
                               const Eigen::Matrix3d& H, Eigen::MatrixXd& hessian) {
  // y = D(p), p = z + A Σ_s b_s t_s: ∂y/∂r = J, ∂y/∂t_s = b_s L A;
  // ∂²u = Jᵀ∇²u J + ∇uᵀ∂²y, with ∂²y/∂r∂r from the frame and ∂²y/∂r_k∂t_s = b_s ∂_kL A.
  Eigen::Matrix<double, 3, Eigen::Dynamic> J;
  frame.jacobian(node, p, J);
  const Eigen::Index o = frame.offset, n = frame.size;
  hessian.block(o, o, n, n) += J.transpose() * H * J;
  frame.add_second(node, p, g, 1.0, hessian.block(o, o, n, n));
  // Soft tissue × deviation: per basis function s, b_s [(L A)ᵀ H J + (∂_kL A)ᵀ g].
  const Eigen::Matrix3d LA = frame.linear(node) * A;
  std::vector<Eigen::Matrix3d> dL;
  frame.linear_derivatives(node, dL);
  Eigen::Matrix<double, 3, Eigen::Dynamic> q_r = LA.transpose() * H * J;
  for (Eigen::Index k = 0; k < n; ++k) q_r.col(k) += (dL[static_cast<std::size_t>(k)] * A).transpose() * g;
  const Eigen::Matrix3d block = LA.transpose() * H * LA;  // A_kᵀ Lᵀ ∇²u_k L A_k
  for (SparseRowMatrix::InnerIterator it(subspace.basis, node); it; ++it) {
    const Eigen::Index s = 3 * it.col();
    for (SparseRowMatrix::InnerIterator ri(subspace.basis, node); ri; ++ri)
      hessian.block<3, 3>(s, 3 * ri.col()) += it.value() * ri.value() * block;
    hessian.block(s, o, 3, n) += it.value() * q_r;
    hessian.block(o, s, n, 3) += it.value() * q_r.transpose();
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
                              const DeviationFrame* root) {
  terms_.clear();
  for (std::size_t k = 0; k < potentials_.size(); ++k) {
    const std::vector<int>& active_of = active_of_[k];
    meshing::RowMatrixX3d start(static_cast<Eigen::Index>(active_of.size()), 3),
        skinned(static_cast<Eigen::Index>(active_of.size()), 3);
    for (std::size_t e = 0; e < active_of.size(); ++e) {
      start.row(static_cast<Eigen::Index>(e)) = p_start.row(active_of[e]);
      const Eigen::Vector3d z = inertia.posed_prescribed().row(active_of[e]).transpose();
      const int node = active_nodes_[static_cast<std::size_t>(active_of[e])];
      skinned.row(static_cast<Eigen::Index>(e)) = (root ? root->apply(node, z) : z).transpose();
    }
    if (!potentials_[k]->begin_substep(t0, dt, start, skinned)) continue;
    Term term;
    term.potential = potentials_[k];
    for (int c : term.potential->candidates()) term.active.push_back(active_of[static_cast<std::size_t>(c)]);
    terms_.push_back(std::move(term));
  }
  return active();
}

template <class Visit>
void ReducedPotentials::each_candidate(const Eigen::VectorXd& q, const ReducedInertia& inertia,
                                       const DeviationFrame* root, Visit&& visit) const {
  for (const Term& term : terms_)
    for (std::size_t c = 0; c < term.active.size(); ++c) {
      const int a = term.active[c];
      const int node = active_nodes_[static_cast<std::size_t>(a)];
      const Eigen::Vector3d p = posed(q, inertia, a);
      visit(term, static_cast<int>(c), a, node, p, root ? root->apply(node, p) : p);
    }
}

double ReducedPotentials::energy(const Eigen::VectorXd& q, const ReducedInertia& inertia,
                                 const DeviationFrame* root) const {
  double sum = 0.0;
  each_candidate(q, inertia, root,
                 [&](const Term& term, int c, int, int, const Eigen::Vector3d&, const Eigen::Vector3d& at) {
                   sum += term.potential->evaluate(c, at, nullptr, nullptr);
                 });
  return sum;
}

void ReducedPotentials::add_gradient(const Eigen::VectorXd& q, const ReducedInertia& inertia, Eigen::VectorXd& gradient,
                                     const DeviationFrame* root) const {
  each_candidate(q, inertia, root,
                 [&](const Term& term, int c, int a, int node, const Eigen::Vector3d& p, const Eigen::Vector3d& at) {
                   Eigen::Vector3d g;
                   term.potential->evaluate(c, at, &g, nullptr);
                   const Eigen::Matrix3d& A = inertia.frame().A[static_cast<std::size_t>(a)];
                   if (root) {
                     add_deviation_node_gradient(subspace_, *root, node, A, p, g, gradient);
                     return;
                   }
                   const Eigen::Vector3d pulled = A.transpose() * g;  // A_kᵀ ∇u_k
                   for (SparseRowMatrix::InnerIterator it(subspace_.basis, node); it; ++it)
                     gradient.segment<3>(3 * it.col()) += it.value() * pulled;
                 });
}

void ReducedPotentials::add_hessian(const Eigen::VectorXd& q, const ReducedInertia& inertia, Eigen::MatrixXd& hessian,
                                    const DeviationFrame* root) const {
  each_candidate(q, inertia, root,
                 [&](const Term& term, int c, int a, int node, const Eigen::Vector3d& p, const Eigen::Vector3d& at) {
                   Eigen::Vector3d g;
                   Eigen::Matrix3d H;
                   term.potential->evaluate(c, at, &g, &H);
                   const Eigen::Matrix3d& A = inertia.frame().A[static_cast<std::size_t>(a)];
                   if (root) {
                     add_deviation_node_blocks(subspace_, *root, node, A, p, g, H, hessian);
                     return;
                   }
                   const Eigen::Matrix3d block = A.transpose() * H * A;  // A_kᵀ ∇²u_k A_k
                   for (SparseRowMatrix::InnerIterator si(subspace_.basis, node); si; ++si)
                     for (SparseRowMatrix::InnerIterator ri(subspace_.basis, node); ri; ++ri)
                       hessian.block<3, 3>(3 * si.col(), 3 * ri.col()) += si.value() * ri.value() * block;
                 });
}

bool ReducedPotentials::accept(const Eigen::VectorXd& q, const ReducedInertia& inertia, const DeviationFrame* root) {
  bool accepted = true;
  for (const Term& term : terms_) {
    meshing::RowMatrixX3d p_end(static_cast<Eigen::Index>(term.active.size()), 3);
    for (std::size_t c = 0; c < term.active.size(); ++c) {
      const int a = term.active[c];
      const Eigen::Vector3d p = posed(q, inertia, a);
      const int node = active_nodes_[static_cast<std::size_t>(a)];
      p_end.row(static_cast<Eigen::Index>(c)) = (root ? root->apply(node, p) : p).transpose();
    }
    accepted = term.potential->accept_substep(p_end) && accepted;
  }
  return accepted;
}

std::string ReducedPotentials::unresolved() const {
  for (const Term& term : terms_)
    if (std::string reason = term.potential->unresolved(); !reason.empty()) return reason;
  return {};
}

int ReducedPotentials::max_refinements() const {
  int most = 0;
  for (const Term& term : terms_) most = std::max(most, term.potential->max_refinements());
  return most;
}

}  // namespace sflsh::reduced
