#pragma once
// A skeleton that answers contact (docs/reduced.md "Tracking skeleton"): the posed layer may deviate from the motion
// by the skeleton's deviation y = D(p) (skeleton_deviation.hpp: the root's rigid motion about the posed pelvis and,
// per tracked joint, a rotation about its posed centre, blended like the skinning), and its coordinates
// r = (θ, τ, φ_1, …, φ_J) join the handle coordinates in one Newton solve of one incremental potential, x = [q; r].
// The terms of Φ(x) (value [J], gradient, Hessian; a finite-difference test each):
//   RootInertiaTerm   1/(2ĥ²) Σ_i m_i |D_i(p_i(q)) − p̃_i|² over every node of the layer: the nodes the basis moves
//                     (p_i(q) = z_i + A_i u_i(q)) and the attached ones, which only the skeleton moves (z_j); it
//                     replaces ReducedInertiaTerm (lumped mass only)
//   RootTrackingTerm  ½ rᵀK r + 1/(2h) (r − r_n)ᵀD(r − r_n) + soft joint limits: the tracking springs to the motion's
//                     pose (r = 0) and dampers on the rates (the backward-Euler dissipation potential), K, D diagonal
//   HeadTerm          a term of q alone (elasticity, gravity) evaluated on the head of x
//   RootPotentialTerm the node potentials (contact) at the deviated positions (reduced_potentials.hpp)
// Gravity stays a term of q: the motion is supported (its feet stand on the ground, its muscles hold its pose), so
// gravity acts on the soft tissue and does no work on the skeleton's deviation.
#include <sflsh/reduced/reduced_inertia.hpp>
#include <sflsh/reduced/reduced_potentials.hpp>
#include <sflsh/reduced/reduced_terms.hpp>
#include <sflsh/reduced/rotation_vector.hpp>
#include <sflsh/reduced/skeleton_deviation.hpp>

#include <Eigen/Core>

#include <functional>
#include <vector>

namespace sflsh::reduced {

using Vector6d = Eigen::Matrix<double, 6, 1>;

/// Joints of a tracking skeleton below the root (docs/reduced.md "Tracking skeleton"): each tracked joint j turns
/// what it carries by φ_j about its posed centre c_j(t), with a spring to the motion's pose, a damper on its rate and a
/// soft limit on |φ_j|.
struct JointTrackingOptions {
  JointTrackingSetup setup;  ///< the skeleton's parents, the tracked joints (empty: the root alone), node weights
  /// The posed centres of the tracked joints at t [m] (the problem's posed frame), in the order of setup.joints.
  std::function<void(double t, std::vector<Eigen::Vector3d>& centres)> centres;
  /// Default spring of joint j: K_j = (2π f)² I_j [N·m/rad], I_j = ⅔ Σ_i m_i ω_ij |p_i − c_j|² the moment of inertia
  /// of what the joint carries about its centre at the start (ω_ij the share of node i on the joint's subtree).
  double frequency = 2.0;  ///< f [Hz]
  /// Default damper D_j = 2 ζ √(K_j I_j) [N·m·s/rad].
  double damping_ratio = 0.7;  ///< ζ
  /// Per tracked joint, overrides of K_j and D_j (≤ 0 or absent: the default).
  std::vector<double> stiffness, damping;
  /// The soft limit ½ k_lim max(0, |φ_j| − φ_max)², k_lim = limit_ratio · K_j; per joint φ_max [rad] (absent: `limit`).
  double limit = 0.5;
  std::vector<double> limits;
  double limit_ratio = 100.0;
};

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
  /// The tracked joints below the root (none by default: the root alone).
  JointTrackingOptions joints;
};

/// Where the deviation's rotations turn during a substep: the pivot c_0 and the tracked joints' centres c_j [m].
struct DeviationPose {
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> centres;
};

/// A term of q evaluated on the first `size` entries of x = [q; r].
class HeadTerm final : public ReducedTerm {
 public:
  HeadTerm(const ReducedTerm& inner, Eigen::Index size) : inner_(inner), size_(size) {}
  std::string_view name() const override { return inner_.name(); }
  double value(const Eigen::VectorXd& x) const override;
  bool add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const override;
  bool add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const override;

 private:
  const ReducedTerm& inner_;
  Eigen::Index size_;
};

class RootInertiaTerm final : public ReducedTerm {
 public:
  /// `carried`: the attached nodes (not in inertia.inertia_nodes()), their mesh indices and lumped masses [kg].
  RootInertiaTerm(const ReducedInertia& inertia, const Subspace& subspace, const SkeletonDeviation& skeleton,
                  std::vector<int> carried, std::vector<double> carried_mass, Eigen::Index offset);
  std::string_view name() const override { return "inertia"; }
  /// The step: targets p̃ of the inertia nodes and of the carried nodes (3 per node), the carried nodes' skinned
  /// positions z_j at the step's end, the rotations' centres and ĥ [s]; the inertia must be at the step's end time.
  void set_step(const Eigen::VectorXd& p_tilde, const Eigen::VectorXd& carried_tilde,
                const meshing::RowMatrixX3d& carried_posed, const DeviationPose& pose, double h_eff);
  double value(const Eigen::VectorXd& x) const override;
  bool add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const override;
  bool add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const override;

 private:
  /// Every node's undeviated posed position p_i(q) (inertia nodes, then carried).
  void gather(const Eigen::VectorXd& x, meshing::RowMatrixX3d& p) const;
  int node(Eigen::Index i) const;  ///< the mesh node of row i of gather()

  const ReducedInertia& inertia_;
  const Subspace& subspace_;
  const SkeletonDeviation& skeleton_;
  std::vector<int> carried_;
  std::vector<double> carried_mass_;
  Eigen::Index offset_;
  Eigen::MatrixXd mass_hessian_;  ///< JᵀMJ/ĥ² (a rigid deviation leaves it: LᵀL = I)
  meshing::RowMatrixX3d target_;  ///< p̃ per node (inertia nodes, then carried)
  meshing::RowMatrixX3d carried_posed_;
  std::vector<double> mass_;
  DeviationPose pose_;
  double h_eff_ = 1.0;
};

/// ½ rᵀK r + 1/(2h)(r − r_n)ᵀD(r − r_n) + Σ_j ½ k_lim,j max(0, |φ_j| − φ_max,j)² over r = (θ, τ, φ_1, …, φ_J).
class RootTrackingTerm final : public ReducedTerm {
 public:
  RootTrackingTerm(Eigen::Index offset, Eigen::Index size = 6) : offset_(offset), size_(size) {}
  std::string_view name() const override { return "tracking"; }
  /// K [N/m; N·m/rad], D [N·s/m; N·m·s/rad] per coordinate (θ, τ, then φ_j), r at the step's start and h [s];
  /// per joint, φ_max [rad] and k_lim [N·m/rad] (empty: no limit).
  void set_step(const Eigen::VectorXd& stiffness, const Eigen::VectorXd& damping, const Eigen::VectorXd& previous,
                double h, const Eigen::VectorXd& limit = {}, const Eigen::VectorXd& limit_stiffness = {});
  double value(const Eigen::VectorXd& x) const override;
  bool add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const override;
  bool add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const override;

 private:
  Eigen::Index offset_, size_;
  Eigen::VectorXd stiffness_, damping_rate_, previous_, limit_, limit_stiffness_;
};

class RootPotentialTerm final : public ReducedTerm {
 public:
  RootPotentialTerm(const ReducedPotentials& potentials, const ReducedInertia& inertia,
                    const SkeletonDeviation& skeleton, Eigen::Index offset)
      : potentials_(potentials), inertia_(inertia), skeleton_(skeleton), offset_(offset) {}
  std::string_view name() const override { return "potential"; }
  void set_pose(const DeviationPose& pose) { pose_ = pose; }
  double value(const Eigen::VectorXd& x) const override;
  bool add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const override;
  bool add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const override;

 private:
  const ReducedPotentials& potentials_;
  const ReducedInertia& inertia_;
  const SkeletonDeviation& skeleton_;
  Eigen::Index offset_;
  DeviationPose pose_;
};

}  // namespace sflsh::reduced
