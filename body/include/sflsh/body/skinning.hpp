#pragma once
// SMPL's model equations (docs/physics.md §3.1): shape blend shapes, joint regression from the shaped
// template, Rodrigues forward kinematics, pose correctives, linear blend skinning, root translation.
#include <sflsh/body/body_model.hpp>

#include <Eigen/Geometry>

namespace sflsh::body {

using Betas = Eigen::Matrix<double, kNumBetas, 1>;
/// Axis-angle pose θ ∈ R^72: joint k's rotation in entries 3k..3k+2 (k = 0 is the global orientation).
using Pose = Eigen::Matrix<double, 3 * kNumJoints, 1>;
using JointPositions = Eigen::Matrix<double, kNumJoints, 3, Eigen::RowMajor>;

/// Rodrigues' formula: the rotation matrix of axis-angle vector `omega` (exact at ‖ω‖ → 0).
Eigen::Matrix3d rodrigues(const Eigen::Vector3d& omega);

/// T_S = T̄ + B_S(β): the shaped rest template (n×3).
RowMatrixX3d shaped_template(const BodyModel& model, const Betas& beta);

/// J = 𝒥 T_S: joints regressed from the shaped template.
JointPositions regress_joints(const BodyModel& model, const RowMatrixX3d& shaped);

/// Pose feature vector f = concat_{k=1..23} vec_rowmajor(R_k − I) (207 entries).
Eigen::Matrix<double, kNumPoseFeatures, 1> pose_features(const Pose& theta);

/// B_P(θ): pose-corrective offsets (n×3); zero when the model has none.
RowMatrixX3d pose_correctives(const BodyModel& model, const Pose& theta);

/// The world transforms of the joints for one pose.
struct Kinematics {
  std::array<Eigen::Isometry3d, kNumJoints> global;  ///< G_k: joint frame to world (no translation)
  std::array<Eigen::Affine3d, kNumJoints> skinning;  ///< G'_k = G_k [I | −J_k], plus root translation
  JointPositions joints_posed;                       ///< posed joint positions incl. translation
};

/// Forward kinematics: G_0 = [R_0 | J_0], G_k = G_par(k) [R_k | J_k − J_par(k)], then G'_k and `trans`.
Kinematics forward_kinematics(const BodyModel& model, const JointPositions& joints, const Pose& theta,
                              const Eigen::Vector3d& trans);

/// Per-vertex blended transforms A_i = Σ_k w_ik G'_k (used for skinning and inverse skinning), 3×4 each.
std::vector<Eigen::Matrix<double, 3, 4>> blend_transforms(const BodyModel& model, const Kinematics& kin);

/// x_i = Σ_k w_ik G'_k [x̄_i; 1]: linear blend skinning of unposed points (n×3) that belong to the
/// model's vertices in order (row i uses weights row i).
RowMatrixX3d linear_blend_skinning(const BodyModel& model, const Kinematics& kin, const RowMatrixX3d& unposed);

/// Everything one evaluation of the model produces.
struct PosedBody {
  RowMatrixX3d shaped;   ///< T_S (n×3)
  RowMatrixX3d unposed;  ///< T_S + B_P(θ) (n×3)
  RowMatrixX3d posed;    ///< world positions (n×3)
  JointPositions joints_rest;
  Kinematics kinematics;
};

/// The full model: v = Σ_k w_k G'_k(θ, J(β)) (T̄ + B_S(β) + B_P(θ)) + trans.
PosedBody evaluate(const BodyModel& model, const Betas& beta, const Pose& theta, const Eigen::Vector3d& trans);

/// A posing helper that caches the shaped template and joints of one subject (β fixed), so that
/// posing along a motion costs one FK and one LBS per frame.
class Poser {
 public:
  Poser(const BodyModel& model, const Betas& beta);
  const RowMatrixX3d& shaped() const { return shaped_; }
  const JointPositions& joints_rest() const { return joints_; }
  /// World positions (n×3) of the body for pose θ and root translation.
  RowMatrixX3d pose(const Pose& theta, const Eigen::Vector3d& trans) const;
  /// Posed joint positions.
  JointPositions pose_joints(const Pose& theta, const Eigen::Vector3d& trans) const;

 private:
  const BodyModel& model_;
  RowMatrixX3d shaped_;
  JointPositions joints_;
};

}  // namespace sflsh::body
