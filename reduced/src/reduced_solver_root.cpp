// The tracking skeleton's part of the reduced solver (reduced_solver.hpp, docs/reduced.md "Tracking skeleton
// (root first)"): the checks and terms set up once, the nodes only the root carries, the pivot and the root's
// rigid transform p ↦ R(θ)(p − c) + c + τ. The Newton step itself is in reduced_solver.cpp.
#include <sflsh/core/error.hpp>
#include <sflsh/reduced/reduced_solver.hpp>
#include <sflsh/reduced/rotation_vector.hpp>

namespace sflsh::reduced {

void ReducedSolver::setup_root() {
  require(options_.integrator == model::Integrator::backward_euler,
          "reduced: a tracking skeleton needs integrator = \"backward_euler\", got \"{}\"",
          model::to_string(options_.integrator));
  require(!options_.quasi_static && problem_.dynamic(), "reduced: a tracking skeleton needs inertia (masses)");
  std::vector<char> inertia_node(static_cast<std::size_t>(problem_.num_nodes()), 0);
  for (int i : inertia_.inertia_nodes()) inertia_node[static_cast<std::size_t>(i)] = 1;
  for (int i = 0; i < problem_.num_nodes(); ++i) {
    if (inertia_node[static_cast<std::size_t>(i)] || problem_.mass[i] <= 0.0) continue;
    carried_.push_back(i);
    carried_mass_.push_back(problem_.mass[i]);
  }
  const auto offset = static_cast<Eigen::Index>(subspace_.num_dofs());
  elastic_head_ = std::make_unique<HeadTerm>(elastic_term_, offset);
  gravity_head_ = std::make_unique<HeadTerm>(gravity_term_, offset);
  root_inertia_term_ = std::make_unique<RootInertiaTerm>(inertia_, carried_mass_, offset);
  root_tracking_term_ = std::make_unique<RootTrackingTerm>(offset);
  root_potential_term_ = std::make_unique<RootPotentialTerm>(potentials_, inertia_, offset);
}

void ReducedSolver::setup_coupled() {
  const auto offset = static_cast<Eigen::Index>(subspace_.num_dofs());
  const Eigen::Index root = options_.root.enabled ? 6 : 0;  // the root's coordinates come first
  coupled_term_ = std::make_unique<CoupledTerm>(*options_.coupled, subspace_, inertia_, offset + root);
  if (options_.root.enabled) {
    coupled_term_->set_root(offset);
    return;  // setup_root() made the head terms
  }
  inertia_head_ = std::make_unique<HeadTerm>(inertia_term_, offset);
  gravity_head_ = std::make_unique<HeadTerm>(gravity_term_, offset);
  elastic_head_ = std::make_unique<HeadTerm>(elastic_term_, offset);
  potential_head_ = std::make_unique<HeadTerm>(potential_term_, offset);
}

void ReducedSolver::carried_posed(double t, const Eigen::VectorXd& x_prescribed, meshing::RowMatrixX3d& p) const {
  p.resize(static_cast<Eigen::Index>(carried_.size()), 3);
  model::NodeFrame frame;
  if (problem_.trajectory) problem_.trajectory->evaluate_nodes(t, carried_, frame);
  for (std::size_t k = 0; k < carried_.size(); ++k) {
    const Eigen::Vector3d x = x_prescribed.segment<3>(3 * carried_[k]);
    const auto row = static_cast<Eigen::Index>(k);
    const Eigen::Vector3d posed =
        problem_.trajectory ? Eigen::Vector3d(frame.A[k] * x + frame.d.row(row).transpose()) : x;
    p.row(row) = posed.transpose();
  }
}

// The pelvis from the options, else the centre of mass of the skinned layer at t.
Eigen::Vector3d ReducedSolver::root_pivot(double t, const meshing::RowMatrixX3d& carried) const {
  if (options_.root.pivot) return options_.root.pivot(t);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double mass = 0.0;
  const std::vector<double>& m = inertia_.lumped_mass();
  for (Eigen::Index i = 0; i < inertia_.posed_prescribed().rows(); ++i) {
    sum += m[static_cast<std::size_t>(i)] * inertia_.posed_prescribed().row(i).transpose();
    mass += m[static_cast<std::size_t>(i)];
  }
  for (Eigen::Index k = 0; k < carried.rows(); ++k) {
    sum += carried_mass_[static_cast<std::size_t>(k)] * carried.row(k).transpose();
    mass += carried_mass_[static_cast<std::size_t>(k)];
  }
  return sum / mass;
}

void ReducedSolver::root_transform(Eigen::Matrix3d& R, Eigen::Vector3d& t) const {
  R.setIdentity();
  t.setZero();
  if (!tracking()) return;
  R = rotation_of_vector(root_.head<3>());
  t = pivot_ - R * pivot_ + root_.tail<3>();  // R(p − c) + c + τ
}

}  // namespace sflsh::reduced
