#include <sflsh/core/error.hpp>
#include <sflsh/reduced/coupled_term.hpp>
#include <sflsh/reduced/reduced_potentials.hpp>

#include <algorithm>
#include <optional>

namespace sflsh::reduced {

void CoupledDerivatives::reset(Eigen::Index candidates, Eigen::Index size, bool with_hessian) {
  node_gradient.setZero(candidates, 3);
  gradient.setZero(size);
  if (!with_hessian) return;
  node_hessian.assign(static_cast<std::size_t>(candidates), Eigen::Matrix3d::Zero());
  node_mixed.setZero(3 * candidates, size);
  hessian.setZero(size, size);
}

CoupledTerm::CoupledTerm(CoupledSystem& system, const Subspace& subspace, const ReducedInertia& inertia,
                         Eigen::Index offset)
    : system_(system), subspace_(subspace), inertia_(inertia), offset_(offset) {
  const std::vector<int>& active = inertia.active_nodes();
  for (int node : system.nodes()) {
    const auto it = std::lower_bound(active.begin(), active.end(), node);
    require(it != active.end() && *it == node,
            "reduced: a coupled object acts on node {}, which no basis function moves (it could not respond)", node);
    active_of_.push_back(static_cast<int>(it - active.begin()));
  }
}

void CoupledTerm::begin(double t0, double dt, const meshing::RowMatrixX3d& p_start, const RootFrame* start_frame,
                        const Eigen::Vector3d& pivot) {
  pivot_ = pivot;
  const auto n = static_cast<Eigen::Index>(active_of_.size());
  meshing::RowMatrixX3d start(n, 3), skinned(n, 3);
  for (Eigen::Index e = 0; e < n; ++e) {
    start.row(e) = p_start.row(active_of_[static_cast<std::size_t>(e)]);
    const Eigen::Vector3d z = inertia_.posed_prescribed().row(active_of_[static_cast<std::size_t>(e)]).transpose();
    skinned.row(e) = (start_frame ? start_frame->apply(z) : z).transpose();
  }
  system_.begin_substep(t0, dt, start, skinned);
  candidate_active_.clear();
  for (int c : system_.candidates()) candidate_active_.push_back(active_of_[static_cast<std::size_t>(c)]);
}

meshing::RowMatrixX3d CoupledTerm::candidate_positions(const Eigen::VectorXd& x, meshing::RowMatrixX3d* posed) const {
  const auto n = static_cast<Eigen::Index>(candidate_active_.size());
  meshing::RowMatrixX3d P(n, 3);
  for (Eigen::Index c = 0; c < n; ++c)
    P.row(c) = posed_node(subspace_, inertia_, x, candidate_active_[static_cast<std::size_t>(c)])
                   .transpose();  // q is the head of x
  if (posed) *posed = P;
  if (root_offset_ >= 0) {
    const RootFrame frame = root_frame(x, root_offset_, pivot_);
    for (Eigen::Index c = 0; c < n; ++c) P.row(c) = frame.apply(P.row(c).transpose()).transpose();
  }
  return P;
}

double CoupledTerm::value(const Eigen::VectorXd& x) const {
  return system_.evaluate(candidate_positions(x), x.segment(offset_, system_.size()), nullptr, false);
}

void CoupledTerm::add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const {
  CoupledDerivatives d;
  meshing::RowMatrixX3d posed;
  system_.evaluate(candidate_positions(x, &posed), x.segment(offset_, system_.size()), &d, false);
  gradient.segment(offset_, system_.size()) += d.gradient;
  std::optional<RootFrame> root;
  if (root_offset_ >= 0) root = root_frame(x, root_offset_, pivot_);
  for (std::size_t c = 0; c < candidate_active_.size(); ++c) {
    const auto a = static_cast<std::size_t>(candidate_active_[c]);
    if (root) {  // ∂u/∂τ = g, ∂u/∂θ_k = gᵀ ∂_kR (p − c); the soft tissue sees Rᵀg
      const auto row = static_cast<Eigen::Index>(c);
      const Eigen::Vector3d g = d.node_gradient.row(row).transpose(), dp = posed.row(row).transpose() - pivot_;
      for (int k = 0; k < 3; ++k)
        gradient[root_offset_ + k] += g.dot(root->rotation.dR[static_cast<std::size_t>(k)] * dp);
      gradient.segment<3>(root_offset_ + 3) += g;
      d.node_gradient.row(row) = (root->rotation.R.transpose() * g).transpose();
    }
    const Eigen::Vector3d pulled =
        inertia_.frame().A[a].transpose() * d.node_gradient.row(static_cast<Eigen::Index>(c)).transpose();
    for (SparseRowMatrix::InnerIterator it(subspace_.basis, inertia_.active_nodes()[a]); it; ++it)
      gradient.segment<3>(3 * it.col()) += it.value() * pulled;
  }
}

void CoupledTerm::add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const {
  CoupledDerivatives d;
  const Eigen::Index size = system_.size();
  meshing::RowMatrixX3d posed;
  system_.evaluate(candidate_positions(x, &posed), x.segment(offset_, size), &d, true);
  hessian.block(offset_, offset_, size, size) += d.hessian;
  std::optional<RootFrame> root;
  if (root_offset_ >= 0) root = root_frame(x, root_offset_, pivot_);
  for (std::size_t c = 0; c < candidate_active_.size(); ++c) {
    const auto a = static_cast<std::size_t>(candidate_active_[c]);
    if (root) {
      const auto row = static_cast<Eigen::Index>(c);
      const Eigen::Vector3d p = posed.row(row).transpose(), g = d.node_gradient.row(row).transpose();
      const Eigen::Matrix3d& A = inertia_.frame().A[a];
      const int node = inertia_.active_nodes()[a];
      add_root_node_blocks(subspace_, *root, node, A, p, g, d.node_hessian[c], hessian);
      // Node × y: ∂p/∂x ᵀ M_c, with ∂p/∂θ_k = ∂_kR (p − c), ∂p/∂τ = I and ∂p/∂t_s = b_s R A.
      const Eigen::MatrixXd M = d.node_mixed.middleRows(3 * row, 3);
      Eigen::Matrix3d Y;
      for (int k = 0; k < 3; ++k) Y.col(k) = root->rotation.dR[static_cast<std::size_t>(k)] * (p - pivot_);
      const Eigen::MatrixXd theta_y = Y.transpose() * M;
      hessian.block(root_offset_, offset_, 3, size) += theta_y;
      hessian.block(offset_, root_offset_, size, 3) += theta_y.transpose();
      hessian.block(root_offset_ + 3, offset_, 3, size) += M;
      hessian.block(offset_, root_offset_ + 3, size, 3) += M.transpose();
      const Eigen::MatrixXd mixed = (root->rotation.R * A).transpose() * M;
      for (SparseRowMatrix::InnerIterator si(subspace_.basis, node); si; ++si) {
        hessian.block(3 * si.col(), offset_, 3, size) += si.value() * mixed;
        hessian.block(offset_, 3 * si.col(), size, 3) += si.value() * mixed.transpose();
      }
      continue;
    }
    const Eigen::Matrix3d& A = inertia_.frame().A[a];
    const Eigen::Matrix3d block = A.transpose() * d.node_hessian[c] * A;
    const Eigen::MatrixXd mixed = A.transpose() * d.node_mixed.middleRows(3 * static_cast<Eigen::Index>(c), 3);
    const int node = inertia_.active_nodes()[a];
    for (SparseRowMatrix::InnerIterator si(subspace_.basis, node); si; ++si) {
      const Eigen::Index s = 3 * si.col();
      for (SparseRowMatrix::InnerIterator ri(subspace_.basis, node); ri; ++ri)
        hessian.block<3, 3>(s, 3 * ri.col()) += si.value() * ri.value() * block;
      hessian.block(s, offset_, 3, size) += si.value() * mixed;
      hessian.block(offset_, s, size, 3) += si.value() * mixed.transpose();
    }
  }
}

bool CoupledTerm::accept(const Eigen::VectorXd& x) {
  return system_.accept_substep(candidate_positions(x), x.segment(offset_, system_.size()));
}

void CoupledTerm::commit(const Eigen::VectorXd& x) {
  system_.commit_substep(candidate_positions(x), x.segment(offset_, system_.size()));
}

}  // namespace sflsh::reduced
