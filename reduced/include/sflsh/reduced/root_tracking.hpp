#pragma once
// A skeleton that answers contact, root first (docs/reduced.md "Tracking skeleton"): the whole posed layer may
// deviate from the motion by a rigid motion about the posed pelvis c(t), p ↦ R(θ)(p − c) + c + τ, and the six root
// coordinates r = (θ, τ) join the handle coordinates in one Newton solve of one incremental potential,
// x = [q; θ; τ]. The terms of Φ(x) (value [J], gradient, Hessian; a finite-difference test each):
//   RootInertiaTerm   1/(2ĥ²) Σ_i m_i |R(p_i(q) − c) + c + τ − p̃_i|² over every node of the layer: the nodes the
//                     basis moves (p_i(q) = z_i + A_i u_i(q)) and the attached ones, which only the root moves (z_j);
//                     it replaces ReducedInertiaTerm (lumped mass only)
//   RootTrackingTerm  ½ rᵀK r + 1/(2h) (r − r_n)ᵀD(r − r_n): the tracking spring to the motion's pose (r = 0) and
//                     a damper on the root's rate (the backward-Euler dissipation potential), K, D diagonal
//   HeadTerm          a term of q alone (elasticity, gravity) evaluated on the head of x
//   RootPotentialTerm the node potentials (contact) at the deviated positions (reduced_potentials.hpp)
// Gravity stays a term of q: the motion's root is supported (its feet stand on the ground), so gravity acts on the
// soft tissue and does no work on the root's deviation.
#include <sflsh/reduced/reduced_inertia.hpp>
#include <sflsh/reduced/reduced_potentials.hpp>
#include <sflsh/reduced/reduced_terms.hpp>
#include <sflsh/reduced/rotation_vector.hpp>

#include <Eigen/Core>

#include <functional>
#include <vector>

namespace sflsh::reduced {

using Vector6d = Eigen::Matrix<double, 6, 1>;

struct RootTrackingOptions {
  bool enabled = false;
  /// The tracking spring of the root's translation [N/m]; the rotation gets k ρ² [N·m/rad] with ρ² the layer's
  /// mass-weighted mean squared distance to the pivot, so that both swing with the same period.
  double stiffness = 600.0;
  /// The damper of the root's translation [N·s/m]; the rotation gets d ρ² [N·m·s/rad].
  double damping = 120.0;
  /// No spring on the horizontal translation (root = "free" in a scene): a pushed body is not pulled back to
  /// its motion's place (the damper still acts); the rotation and the height are tracked.
  bool free_translation = false;
  /// The pivot c(t) [m] in the problem's posed frame (the posed pelvis); empty: the layer's centre of mass.
  std::function<Eigen::Vector3d(double t)> pivot;
};

/// A term of q evaluated on the first `size` entries of x = [q; r].
class HeadTerm final : public ReducedTerm {
 public:
  HeadTerm(const ReducedTerm& inner, Eigen::Index size) : inner_(inner), size_(size) {}
  std::string_view name() const override { return inner_.name(); }
  double value(const Eigen::VectorXd& x) const override;
  void add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const override;
  void add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const override;

 private:
  const ReducedTerm& inner_;
  Eigen::Index size_;
};

class RootInertiaTerm final : public ReducedTerm {
 public:
  /// `carried`: the attached nodes (not in inertia.inertia_nodes()), their lumped masses [kg].
  RootInertiaTerm(const ReducedInertia& inertia, std::vector<double> carried_mass, Eigen::Index offset);
  std::string_view name() const override { return "inertia"; }
  /// The step: targets p̃ of the inertia nodes and of the carried nodes (3 per node), the carried nodes' skinned
  /// positions z_j at the step's end, the pivot c and ĥ [s]; the inertia must be at the step's end time.
  void set_step(const Eigen::VectorXd& p_tilde, const Eigen::VectorXd& carried_tilde,
                const meshing::RowMatrixX3d& carried_posed, const Eigen::Vector3d& pivot, double h_eff);
  double value(const Eigen::VectorXd& x) const override;
  void add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const override;
  void add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const override;

 private:
  /// Every node's unrotated posed position p_i(q) (inertia nodes, then carried), target and mass.
  void gather(const Eigen::VectorXd& x, meshing::RowMatrixX3d& p) const;

  const ReducedInertia& inertia_;
  std::vector<double> carried_mass_;
  Eigen::Index offset_;
  Eigen::MatrixXd mass_hessian_;  ///< JᵀMJ/ĥ² (the rotation cancels for a lumped mass)
  meshing::RowMatrixX3d target_;  ///< p̃ per node (inertia nodes, then carried)
  meshing::RowMatrixX3d carried_posed_;
  std::vector<double> mass_;
  Eigen::Vector3d pivot_ = Eigen::Vector3d::Zero();
  double h_eff_ = 1.0;
};

class RootTrackingTerm final : public ReducedTerm {
 public:
  RootTrackingTerm(Eigen::Index offset) : offset_(offset) {}
  std::string_view name() const override { return "tracking"; }
  /// K [N/m; N·m/rad], D [N·s/m; N·m·s/rad] per root coordinate (θ then τ), the root at the step's start and h [s].
  void set_step(const Vector6d& stiffness, const Vector6d& damping, const Vector6d& previous, double h);
  double value(const Eigen::VectorXd& x) const override;
  void add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const override;
  void add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const override;

 private:
  Eigen::Index offset_;
  Vector6d stiffness_ = Vector6d::Zero(), damping_rate_ = Vector6d::Zero(), previous_ = Vector6d::Zero();
};

class RootPotentialTerm final : public ReducedTerm {
 public:
  RootPotentialTerm(const ReducedPotentials& potentials, const ReducedInertia& inertia, Eigen::Index offset)
      : potentials_(potentials), inertia_(inertia), offset_(offset) {}
  std::string_view name() const override { return "potential"; }
  void set_pivot(const Eigen::Vector3d& pivot) { pivot_ = pivot; }
  double value(const Eigen::VectorXd& x) const override;
  void add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const override;
  void add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const override;

 private:
  const ReducedPotentials& potentials_;
  const ReducedInertia& inertia_;
  Eigen::Index offset_;
  Eigen::Vector3d pivot_ = Eigen::Vector3d::Zero();
};

}  // namespace sflsh::reduced
