// The tracking skeleton's part of the reduced solver (reduced_solver.hpp, docs/reduced.md "Tracking skeleton"): the
// checks and terms set up once, the nodes only the deviation carries, the pivot and the joint centres, the springs
// per coordinate and the root's rigid transform p ↦ R(θ)(p − c) + c + τ. The Newton step is in reduced_solver.cpp.
#include <sflsh/core/error.hpp>
#include <sflsh/reduced/reduced_solver.hpp>
#include <sflsh/reduced/rotation_vector.hpp>

#include <algorithm>
#include <cmath>

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
  elastic_head_ = std::make_unique<HeadTerm>(elastic_term_, handle_dofs());
  gravity_head_ = std::make_unique<HeadTerm>(gravity_term_, offset);
  root_inertia_term_ =
      std::make_unique<RootInertiaTerm>(inertia_, subspace_, skeleton_, carried_, carried_mass_, offset);
  root_tracking_term_ = std::make_unique<RootTrackingTerm>(offset, skeleton_.size());
  root_potential_term_ = std::make_unique<RootPotentialTerm>(potentials_, inertia_, skeleton_, offset);
  if (skeleton_.num_joints() > 0) {
    require(static_cast<bool>(options_.root.joints.centres), "reduced: tracked joints need their posed centres");
    require(options_.root.joints.setup.node_weights.size() == static_cast<std::size_t>(problem_.num_nodes()),
            "reduced: tracked joints: skinning weights for {} nodes, the layer has {}",
            options_.root.joints.setup.node_weights.size(), problem_.num_nodes());
  }
}

void ReducedSolver::setup_coupled() {
  const auto offset = static_cast<Eigen::Index>(subspace_.num_dofs());
  const Eigen::Index root = options_.root.enabled ? skeleton_.size() : 0;  // the deviation's coordinates come first
  coupled_term_ = std::make_unique<CoupledTerm>(*options_.coupled, subspace_, inertia_, offset + root);
  if (options_.root.enabled) {
    coupled_term_->set_root(offset, skeleton_);
    return;  // setup_root() made the head terms
  }
  inertia_head_ = std::make_unique<HeadTerm>(inertia_term_, offset);
  gravity_head_ = std::make_unique<HeadTerm>(gravity_term_, offset);
  elastic_head_ = std::make_unique<HeadTerm>(elastic_term_, handle_dofs());
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
  R = rotation_of_vector(deviation_.head<3>());
  t = pose_.pivot - R * pose_.pivot + deviation_.segment<3>(3);  // R(p − c) + c + τ
}

DeviationFrame ReducedSolver::deviation_frame() const {
  const Eigen::VectorXd r = tracking() ? deviation_ : Eigen::VectorXd(Eigen::VectorXd::Zero(skeleton_.size()));
  DeviationPose pose = pose_;
  pose.centres.resize(static_cast<std::size_t>(skeleton_.num_joints()), Eigen::Vector3d::Zero());
  return skeleton_.frame(r, 0, pose.pivot, pose.centres, false);
}

DeviationPose ReducedSolver::deviation_pose(double t, const meshing::RowMatrixX3d& carried) const {
  DeviationPose pose;
  pose.pivot = root_pivot(t, carried);
  if (skeleton_.num_joints() > 0) {
    options_.root.joints.centres(t, pose.centres);
    require(pose.centres.size() == static_cast<std::size_t>(skeleton_.num_joints()),
            "reduced: {} joint centres for {} tracked joints", pose.centres.size(), skeleton_.num_joints());
  }
  return pose;
}

// Root: translation k, d; rotation k ρ², d ρ² with ρ² = ⅔ Σ m|p − c|²/Σ m (the mean over axes of the layer's moment of
// inertia per unit mass), so that both swing with one period. Joint j: K_j = (2πf)² I_j, D_j = 2ζ√(K_j I_j) with
// I_j = ⅔ Σ_i m_i ω_ij |p_i − c_j|², ω_ij the share of node i on the bones the joint turns.
void ReducedSolver::setup_tracking_springs(const meshing::RowMatrixX3d& carried) {
  pose_ = deviation_pose(t_, carried);
  const int joints = skeleton_.num_joints();
  double root_inertia = 0.0, mass = 0.0;
  Eigen::VectorXd joint_inertia = Eigen::VectorXd::Zero(joints);
  const std::vector<double>& m = inertia_.lumped_mass();
  const auto moved = static_cast<Eigen::Index>(inertia_.inertia_nodes().size());
  for (Eigen::Index i = 0; i < moved + carried.rows(); ++i) {
    const bool own = i < moved;
    const Eigen::Vector3d p = own ? Eigen::Vector3d(inertia_.posed_prescribed().row(i).transpose())
                                  : Eigen::Vector3d(carried.row(i - moved).transpose());
    const double mi = own ? m[static_cast<std::size_t>(i)] : carried_mass_[static_cast<std::size_t>(i - moved)];
    const int node =
        own ? inertia_.inertia_nodes()[static_cast<std::size_t>(i)] : carried_[static_cast<std::size_t>(i - moved)];
    root_inertia += mi * (p - pose_.pivot).squaredNorm();
    mass += mi;
    if (joints == 0) continue;
    for (const auto& [bone, w] : skeleton_.node_blend(node))
      for (int j : skeleton_.chain(bone))
        joint_inertia[j] += mi * w * (p - pose_.centres[static_cast<std::size_t>(j)]).squaredNorm();
  }
  const double rho2 = 2.0 / 3.0 * root_inertia / mass;
  const RootTrackingOptions& o = options_.root;
  const JointTrackingOptions& jo = o.joints;
  tracking_stiffness_.resize(skeleton_.size());
  tracking_damping_.resize(skeleton_.size());
  tracking_stiffness_.head<6>() << o.stiffness * rho2 * Eigen::Vector3d::Ones(), o.stiffness * Eigen::Vector3d::Ones();
  tracking_damping_.head<6>() << o.damping * rho2 * Eigen::Vector3d::Ones(), o.damping * Eigen::Vector3d::Ones();
  if (o.free_translation) tracking_stiffness_[3] = tracking_stiffness_[5] = 0.0;  // x and z: the plane (Y up)
  joint_inertia_ = 2.0 / 3.0 * joint_inertia;
  joint_limit_.resize(joints);
  joint_limit_stiffness_.resize(joints);
  const double omega = 2.0 * EIGEN_PI * jo.frequency;
  for (int j = 0; j < joints; ++j) {
    const auto sj = static_cast<std::size_t>(j);
    const double I = std::max(joint_inertia_[j], 1e-9);  // a joint carrying no mass still gets a spring
    const double k = sj < jo.stiffness.size() && jo.stiffness[sj] > 0.0 ? jo.stiffness[sj] : omega * omega * I;
    const double d =
        sj < jo.damping.size() && jo.damping[sj] > 0.0 ? jo.damping[sj] : 2.0 * jo.damping_ratio * std::sqrt(k * I);
    tracking_stiffness_.segment<3>(6 + 3 * j).setConstant(k);
    tracking_damping_.segment<3>(6 + 3 * j).setConstant(d);
    joint_limit_[j] = sj < jo.limits.size() && jo.limits[sj] > 0.0 ? jo.limits[sj] : jo.limit;
    joint_limit_stiffness_[j] = jo.limit_ratio * k;
  }
}

}  // namespace sflsh::reduced
