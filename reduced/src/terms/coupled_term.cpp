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

void CoupledTerm::begin(double t0, double dt, const meshing::RowMatrixX3d& p_start, const DeviationFrame* start_frame,
                        const DeviationPose& pose) {
  pose_ = pose;
  const auto n = static_cast<Eigen::Index>(active_of_.size());
  meshing::RowMatrixX3d start(n, 3), skinned(n, 3);
  for (Eigen::Index e = 0; e < n; ++e) {
    start.row(e) = p_start.row(active_of_[static_cast<std::size_t>(e)]);
    const int a = active_of_[static_cast<std::size_t>(e)];
    const Eigen::Vector3d z = inertia_.posed_prescribed().row(a).transpose();
    const int node = inertia_.active_nodes()[static_cast<std::size_t>(a)];
    skinned.row(e) = (start_frame ? start_frame->apply(node, z) : z).transpose();
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
    const DeviationFrame frame = skeleton_->frame(x, root_offset_, pose_.pivot, pose_.centres, false);
    for (Eigen::Index c = 0; c < n; ++c) {
      const int node =
          inertia_.active_nodes()[static_cast<std::size_t>(candidate_active_[static_cast<std::size_t>(c)])];
      P.row(c) = frame.apply(node, P.row(c).transpose()).transpose();
    }
  }
  return P;
}

double CoupledTerm::value(const Eigen::VectorXd& x) const {
  return system_.evaluate(candidate_positions(x), x.segment(offset_, system_.size()), nullptr, false);
}

bool CoupledTerm::add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const {
  CoupledDerivatives d;
  meshing::RowMatrixX3d posed;
  system_.evaluate(candidate_positions(x, &posed), x.segment(offset_, system_.size()), &d, false);
  gradient.segment(offset_, system_.size()) += d.gradient;
  std::optional<DeviationFrame> root;
  if (root_offset_ >= 0) root = skeleton_->frame(x, root_offset_, pose_.pivot, pose_.centres, false);
  for (std::size_t c = 0; c < candidate_active_.size(); ++c) {
    const auto a = static_cast<std::size_t>(candidate_active_[c]);
    const int node = inertia_.active_nodes()[a];
    const auto row = static_cast<Eigen::Index>(c);
    const Eigen::Vector3d g = d.node_gradient.row(row).transpose();
    if (root) {
      add_deviation_node_gradient(subspace_, *root, node, inertia_.frame().A[a], posed.row(row).transpose(), g,
                                  gradient);
      continue;
    }
    const Eigen::Vector3d pulled = inertia_.frame().A[a].transpose() * g;
    for (SparseRowMatrix::InnerIterator it(subspace_.basis, node); it; ++it)
      gradient.segment<3>(3 * it.col()) += it.value() * pulled;
  }
  return gradient.allFinite();
}

bool CoupledTerm::add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const {
  CoupledDerivatives d;
  const Eigen::Index size = system_.size();
  meshing::RowMatrixX3d posed;
  system_.evaluate(candidate_positions(x, &posed), x.segment(offset_, size), &d, true);
  hessian.block(offset_, offset_, size, size) += d.hessian;
  std::optional<DeviationFrame> root;
  if (root_offset_ >= 0) root = skeleton_->frame(x, root_offset_, pose_.pivot, pose_.centres, true);
  Eigen::Matrix<double, 3, Eigen::Dynamic> J;
  for (std::size_t c = 0; c < candidate_active_.size(); ++c) {
    const auto a = static_cast<std::size_t>(candidate_active_[c]);
    if (root) {
      const auto row = static_cast<Eigen::Index>(c);
      const Eigen::Vector3d p = posed.row(row).transpose(), g = d.node_gradient.row(row).transpose();
      const Eigen::Matrix3d& A = inertia_.frame().A[a];
      const int node = inertia_.active_nodes()[a];
      add_deviation_node_blocks(subspace_, *root, node, A, p, g, d.node_hessian[c], hessian);
      // Node × y: ∂y/∂xᵀ M_c, with ∂y/∂r = J and ∂y/∂t_s = b_s L A.
      const Eigen::MatrixXd M = d.node_mixed.middleRows(3 * row, 3);
      root->jacobian(node, p, J);
      const Eigen::MatrixXd r_y = J.transpose() * M;
      hessian.block(root_offset_, offset_, root->size, size) += r_y;
      hessian.block(offset_, root_offset_, size, root->size) += r_y.transpose();
      const Eigen::MatrixXd mixed = (root->linear(node) * A).transpose() * M;
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
  return true;
}

bool CoupledTerm::accept(const Eigen::VectorXd& x) {
  return system_.accept_substep(candidate_positions(x), x.segment(offset_, system_.size()));
}

void CoupledTerm::commit(const Eigen::VectorXd& x) {
  system_.commit_substep(candidate_positions(x), x.segment(offset_, system_.size()));
}

}  // namespace sflsh::reduced
