#include <sflsh/core/error.hpp>
#include <sflsh/reduced/reduced_inertia.hpp>

#include <algorithm>

namespace sflsh::reduced {

ReducedInertia::ReducedInertia(const model::Problem& problem, const Subspace& subspace)
    : problem_(problem), subspace_(subspace), active_(subspace.active_nodes()) {
  require(subspace.num_nodes() == problem.num_nodes(), "reduced inertia: subspace has {} nodes, problem {}",
          subspace.num_nodes(), problem.num_nodes());
  kind_ = problem.mass_kind == model::MassKind::consistent && problem.dynamic() ? model::MassKind::consistent
                                                                                : model::MassKind::lumped;
  nodes_ = active_;
  if (kind_ == model::MassKind::consistent) build_consistent(problem);
  for (int i : nodes_) mass_.push_back(problem.mass.size() ? problem.mass[i] : 0.0);
  skinned_ = dynamic_cast<const model::SkinnedTrajectory*>(problem.trajectory.get());
  if (skinned_) {
    if (kind_ == model::MassKind::lumped) {
      pairs_ = JointPairMass::lumped(*skinned_, subspace, active_,
                                     std::vector<double>(mass_.begin(), mass_.begin() + num_active()));
    } else {
      // M restricted to the active nodes (the columns of the CSR rows below num_active()).
      std::vector<Eigen::Triplet<double>> entries;
      for (int a = 0; a < num_active(); ++a)
        for (int e = row_offset_[static_cast<std::size_t>(a)]; e < row_offset_[static_cast<std::size_t>(a) + 1]; ++e)
          if (row_column_[static_cast<std::size_t>(e)] < num_active())
            entries.emplace_back(a, row_column_[static_cast<std::size_t>(e)], row_value_[static_cast<std::size_t>(e)]);
      Eigen::SparseMatrix<double, Eigen::RowMajor> M(num_active(), num_active());
      M.setFromTriplets(entries.begin(), entries.end());
      pairs_ = JointPairMass::consistent(*skinned_, subspace, active_, M);
    }
  }
  z_.resize(static_cast<Eigen::Index>(nodes_.size()), 3);
}

void ReducedInertia::build_consistent(const model::Problem& problem) {
  const Eigen::SparseMatrix<double, Eigen::RowMajor> M = problem.mass_matrix();
  std::vector<int> index(static_cast<std::size_t>(problem.num_nodes()), -1);  // mesh node → inertia node
  for (std::size_t a = 0; a < active_.size(); ++a) index[static_cast<std::size_t>(active_[a])] = static_cast<int>(a);
  std::vector<int> neighbours;
  for (int i : active_)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(M, i); it; ++it)
      if (index[static_cast<std::size_t>(it.col())] < 0) neighbours.push_back(static_cast<int>(it.col()));
  std::sort(neighbours.begin(), neighbours.end());
  neighbours.erase(std::unique(neighbours.begin(), neighbours.end()), neighbours.end());
  for (int j : neighbours) {
    index[static_cast<std::size_t>(j)] = static_cast<int>(nodes_.size());
    nodes_.push_back(j);
  }
  row_offset_.assign(1, 0);
  for (int i : active_) {
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(M, i); it; ++it) {
      if (it.value() == 0.0) continue;
      row_column_.push_back(index[static_cast<std::size_t>(it.col())]);
      row_value_.push_back(it.value());
    }
    row_offset_.push_back(static_cast<int>(row_column_.size()));
  }
}

void ReducedInertia::set_time(double t, const Eigen::VectorXd& x_prescribed) {
  require(x_prescribed.size() == problem_.num_dofs(), "reduced inertia: prescribed state has {} entries, expected {}",
          x_prescribed.size(), problem_.num_dofs());
  t_ = t;
  if (problem_.trajectory) {
    problem_.trajectory->evaluate_nodes(t, nodes_, frame_);
  } else {
    frame_.A.assign(nodes_.size(), Eigen::Matrix3d::Identity());
    frame_.d = meshing::RowMatrixX3d::Zero(static_cast<Eigen::Index>(nodes_.size()), 3);
  }
  for (std::size_t a = 0; a < nodes_.size(); ++a)
    z_.row(static_cast<Eigen::Index>(a)) =
        (frame_.A[a] * x_prescribed.segment<3>(3 * nodes_[a])).transpose() + frame_.d.row(static_cast<Eigen::Index>(a));
  if (skinned_) skinned_->curve().transforms(t, joints_);
}

Eigen::VectorXd ReducedInertia::pull_back_mass(const Eigen::VectorXd& v) const {
  require(v.size() == 3 * static_cast<Eigen::Index>(nodes_.size()),
          "reduced inertia: posed field of {} entries for {} inertia nodes", v.size(), nodes_.size());
  Eigen::VectorXd c = Eigen::VectorXd::Zero(subspace_.num_dofs());
  for (std::size_t a = 0; a < active_.size(); ++a) {
    Eigen::Vector3d y;  // [M v]_i
    if (kind_ == model::MassKind::lumped) {
      if (mass_[a] == 0.0) continue;
      y = mass_[a] * v.segment<3>(3 * static_cast<Eigen::Index>(a));
    } else {
      y.setZero();
      for (int e = row_offset_[a]; e < row_offset_[a + 1]; ++e)
        y += row_value_[static_cast<std::size_t>(e)] * v.segment<3>(3 * row_column_[static_cast<std::size_t>(e)]);
    }
    const Eigen::Vector3d r = frame_.A[a].transpose() * y;
    for (SparseRowMatrix::InnerIterator it(subspace_.basis, active_[a]); it; ++it)
      c.segment<3>(3 * it.col()) += it.value() * r;
  }
  return c;
}

Eigen::VectorXd ReducedInertia::inertia_linear_term(const Eigen::VectorXd& p_tilde, double h_eff) const {
  require(p_tilde.size() == 3 * static_cast<Eigen::Index>(nodes_.size()),
          "reduced inertia: p̃ of {} entries for {} inertia nodes", p_tilde.size(), nodes_.size());
  require(h_eff > 0.0, "reduced inertia: ĥ must be positive, got {}", h_eff);
  const double inv_h2 = 1.0 / (h_eff * h_eff);
  // c = Jᵀ M (z − p̃)/ĥ²
  return pull_back_mass(inv_h2 * (Eigen::Map<const Eigen::VectorXd>(z_.data(), z_.size()) - p_tilde));
}

Eigen::VectorXd ReducedInertia::gravity_linear_term() const {
  Eigen::VectorXd c = Eigen::VectorXd::Zero(subspace_.num_dofs());
  if (problem_.gravity.isZero(0.0)) return c;
  for (std::size_t a = 0; a < active_.size(); ++a) {
    if (mass_[a] == 0.0) continue;
    const Eigen::Vector3d r = -mass_[a] * (frame_.A[a].transpose() * problem_.gravity);  // −m_i A_iᵀ g
    for (SparseRowMatrix::InnerIterator it(subspace_.basis, active_[a]); it; ++it)
      c.segment<3>(3 * it.col()) += it.value() * r;
  }
  return c;
}

Eigen::VectorXd ReducedInertia::linear_term(const meshing::RowMatrixX3d& p_tilde, double h, bool inertia) const {
  Eigen::VectorXd c = gravity_linear_term();
  if (inertia) {
    const meshing::RowMatrixX3d rows = p_tilde;  // contiguous node-major copy
    c += inertia_linear_term(Eigen::Map<const Eigen::VectorXd>(rows.data(), rows.size()), h);
  }
  return c;
}

void ReducedInertia::mass_hessian(double h_eff, Eigen::MatrixXd& H) const {
  const int n = subspace_.num_dofs();
  H.setZero(n, n);
  const double inv_h2 = 1.0 / (h_eff * h_eff);
  if (skinned_) {
    pairs_.add(joints_, joints_, inv_h2, H);
    return;
  }
  for (std::size_t a = 0; a < active_.size(); ++a) {
    if (kind_ == model::MassKind::lumped) {
      if (mass_[a] == 0.0) continue;
      const Eigen::Matrix3d G = inv_h2 * mass_[a] * (frame_.A[a].transpose() * frame_.A[a]);
      for (SparseRowMatrix::InnerIterator si(subspace_.basis, active_[a]); si; ++si)
        for (SparseRowMatrix::InnerIterator ri(subspace_.basis, active_[a]); ri; ++ri)
          H.block<3, 3>(3 * si.col(), 3 * ri.col()) += (si.value() * ri.value()) * G;
      continue;
    }
    for (int e = row_offset_[a]; e < row_offset_[a + 1]; ++e) {
      const int b = row_column_[static_cast<std::size_t>(e)];
      if (b >= num_active()) continue;  // no basis function there
      const auto sb = static_cast<std::size_t>(b);
      const Eigen::Matrix3d G =
          (inv_h2 * row_value_[static_cast<std::size_t>(e)]) * (frame_.A[a].transpose() * frame_.A[sb]);
      for (SparseRowMatrix::InnerIterator si(subspace_.basis, active_[a]); si; ++si)
        for (SparseRowMatrix::InnerIterator ri(subspace_.basis, active_[sb]); ri; ++ri)
          H.block<3, 3>(3 * si.col(), 3 * ri.col()) += (si.value() * ri.value()) * G;
    }
  }
}

void ReducedInertia::cross_mass(double t_other, Eigen::MatrixXd& M) const {
  const int n = subspace_.num_dofs();
  M.setZero(n, n);
  if (skinned_) {
    model::JointTransforms other;
    skinned_->curve().transforms(t_other, other);
    pairs_.add(joints_, other, 1.0, M);
    return;
  }
  model::NodeFrame other;
  if (problem_.trajectory) {
    problem_.trajectory->evaluate_nodes(t_other, active_, other);
  } else {
    other.A.assign(active_.size(), Eigen::Matrix3d::Identity());
  }
  for (std::size_t a = 0; a < active_.size(); ++a) {
    if (kind_ == model::MassKind::lumped) {
      if (mass_[a] == 0.0) continue;
      const Eigen::Matrix3d G = mass_[a] * (frame_.A[a].transpose() * other.A[a]);
      for (SparseRowMatrix::InnerIterator si(subspace_.basis, active_[a]); si; ++si)
        for (SparseRowMatrix::InnerIterator ri(subspace_.basis, active_[a]); ri; ++ri)
          M.block<3, 3>(3 * si.col(), 3 * ri.col()) += (si.value() * ri.value()) * G;
      continue;
    }
    for (int e = row_offset_[a]; e < row_offset_[a + 1]; ++e) {
      const int b = row_column_[static_cast<std::size_t>(e)];
      if (b >= num_active()) continue;
      const auto sb = static_cast<std::size_t>(b);
      const Eigen::Matrix3d G = row_value_[static_cast<std::size_t>(e)] * (frame_.A[a].transpose() * other.A[sb]);
      for (SparseRowMatrix::InnerIterator si(subspace_.basis, active_[a]); si; ++si)
        for (SparseRowMatrix::InnerIterator ri(subspace_.basis, active_[sb]); ri; ++ri)
          M.block<3, 3>(3 * si.col(), 3 * ri.col()) += (si.value() * ri.value()) * G;
    }
  }
}

void ReducedInertia::displacement(const Eigen::VectorXd& q, meshing::RowMatrixX3d& u) const {
  u.resize(static_cast<Eigen::Index>(active_.size()), 3);
  for (std::size_t a = 0; a < active_.size(); ++a) {
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    for (SparseRowMatrix::InnerIterator it(subspace_.basis, active_[a]); it; ++it)
      v += it.value() * q.segment<3>(3 * it.col());
    u.row(static_cast<Eigen::Index>(a)) = v.transpose();
  }
}

void ReducedInertia::posed_into(const Eigen::VectorXd& q, double* out) const {
  for (std::size_t a = 0; a < nodes_.size(); ++a) {
    const auto row = static_cast<Eigen::Index>(a);
    Eigen::Map<Eigen::Vector3d> p(out + 3 * a);
    if (a >= active_.size()) {
      p = z_.row(row).transpose();  // no basis function: the skinned prescribed state
      continue;
    }
    Eigen::Vector3d u = Eigen::Vector3d::Zero();
    for (SparseRowMatrix::InnerIterator it(subspace_.basis, active_[a]); it; ++it)
      u += it.value() * q.segment<3>(3 * it.col());
    p = frame_.A[a] * u + z_.row(row).transpose();  // p_i = z_i + A_i u_i
  }
}

void ReducedInertia::posed(const Eigen::VectorXd& q, meshing::RowMatrixX3d& p) const {
  p.resize(static_cast<Eigen::Index>(nodes_.size()), 3);
  posed_into(q, p.data());
}

void ReducedInertia::posed(const Eigen::VectorXd& q, Eigen::VectorXd& p) const {
  p.resize(3 * static_cast<Eigen::Index>(nodes_.size()));
  posed_into(q, p.data());
}

Eigen::VectorXd ReducedInertia::posed_rate(const Eigen::VectorXd& v) const {
  meshing::RowMatrixX3d u;
  displacement(v, u);
  Eigen::VectorXd out = Eigen::VectorXd::Zero(3 * static_cast<Eigen::Index>(nodes_.size()));
  for (std::size_t a = 0; a < active_.size(); ++a)
    out.segment<3>(3 * static_cast<Eigen::Index>(a)) = frame_.A[a] * u.row(static_cast<Eigen::Index>(a)).transpose();
  return out;
}

}  // namespace sflsh::reduced
