#pragma once
// SMPL's posed vertices as a function of pose θ (72) and root translation (3), with their analytic Jacobian,
// for the per-frame pose fit (pose_fit.hpp). β is fixed: the shaped template T_S and the joints J(β) are given.
//
//   v_i = R_wb Σ_k w_ik G'_k(θ, trans) [T_S,i + B_P,i(θ); 1]            (docs/physics.md §3.1)
//
// Rotating joint j by dω_j moves every point carried by a joint k below j (k = j included) about the
// posed joint o_j: d(G'_k x) = (G_par(j) S(ω_j) dω_j) × (G'_k x − o_j), with S(ω) the left Jacobian of
// SO(3) (∂R/∂ω_m Rᵀ = [S(ω) e_m]×; Gallego & Yezzi 2015, Eq. 9). Summed over the skinning weights:
//   ∂v_i/∂ω_j = R_wb ( −[P_ij − W_ij o_j]× G_par(j) S(ω_j) + A_i ∂B_P,i/∂ω_j ),
//   P_ij = Σ_{k ⪯ j} w_ik G'_k x_i,  W_ij = Σ_{k ⪯ j} w_ik  (k ⪯ j: k is j or one of its descendants),
//   ∂v_i/∂trans = R_wb Σ_k w_ik.
#include <sflsh/body/skinning.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace sflsh::validate {

using body::RowMatrixX3d;

/// Number of pose-fit parameters per frame: θ (72) then trans (3).
inline constexpr int kNumPoseParameters = 3 * body::kNumJoints + 3;
using PoseParameters = Eigen::Matrix<double, kNumPoseParameters, 1>;

/// S(ω): ∂R(ω)/∂ω_m · R(ω)ᵀ = [S(ω) e_m]× (left Jacobian of SO(3); exact series below |ω| = 1e-6).
Eigen::Matrix3d rotation_left_jacobian(const Eigen::Vector3d& omega);

/// Posed vertices of one subject (fixed β), with an analytic Jacobian.
class PosedModel {
 public:
  /// `shaped` = T_S (n×3), `joints` = J(β). The model must outlive the object.
  PosedModel(const body::BodyModel& model, RowMatrixX3d shaped, const body::JointPositions& joints,
             const Eigen::Matrix3d& world_from_body = Eigen::Matrix3d::Identity());

  /// World positions (n×3) for parameters [θ; trans].
  RowMatrixX3d posed(const PoseParameters& parameters) const;
  /// World positions (all n×3) and ∂v/∂[θ; trans] (3n × 75, row 3i + c); with `rows`, only the listed
  /// vertices' rows, in that order (3·rows.size() × 75, row 3s + c for vertex rows[s]).
  void posed_and_jacobian(const PoseParameters& parameters, RowMatrixX3d& posed, Eigen::MatrixXd& jacobian,
                          const std::vector<int>* rows = nullptr) const;

  /// Σ_s w_s ‖v_{rows[s]} − y_{rows[s]}‖² at `parameters` (only the listed vertices are posed).
  double rows_cost(const PoseParameters& parameters, const std::vector<int>& rows, const Eigen::VectorXd& weights,
                   const RowMatrixX3d& target) const;
  /// The Gauss–Newton normal equations of that cost: H = Σ_s w_s J_sᵀ J_s (75×75), g = Σ_s w_s J_sᵀ (v − y);
  /// returns the cost. Accumulates only the non-zero 3×3 blocks (the joints above each vertex and trans).
  double normal_equations(const PoseParameters& parameters, const std::vector<int>& rows,
                          const Eigen::VectorXd& weights, const RowMatrixX3d& target,
                          Eigen::Matrix<double, kNumPoseParameters, kNumPoseParameters>& hessian,
                          PoseParameters& gradient) const;

  const body::BodyModel& model() const { return model_; }
  const RowMatrixX3d& shaped() const { return shaped_; }
  const body::JointPositions& joints() const { return joints_; }

 private:
  /// What every vertex's Jacobian needs at one pose.
  struct Linearization {
    body::Kinematics kinematics;
    RowMatrixX3d unposed;                               ///< T_S + B_P(θ)
    std::array<Eigen::Matrix3d, body::kNumJoints> g{};  ///< G_par(j) S(ω_j)
    Eigen::MatrixXd corrective_jacobian;                ///< 3n × 69 ∂B_P/∂ω (empty without correctives)
  };
  Linearization linearize(const PoseParameters& parameters) const;
  /// v_i (world) and its 3×75 Jacobian; returns the bit mask of the joints whose columns can be non-zero.
  std::uint32_t vertex_jacobian(const Linearization& lin, Eigen::Index i, Eigen::Vector3d& position,
                                Eigen::Matrix<double, 3, kNumPoseParameters>& block) const;

  const body::BodyModel& model_;
  RowMatrixX3d shaped_;
  body::JointPositions joints_;
  Eigen::Matrix3d world_from_body_;
  std::vector<std::vector<std::pair<int, double>>> weights_;  ///< per vertex: its non-zero skinning weights
  std::array<std::uint32_t, body::kNumJoints> ancestors_{};   ///< bit j of ancestors_[k]: j ⪰ k (k included)
};

/// Splits / joins the parameter vector.
PoseParameters pack_pose(const body::Pose& theta, const Eigen::Vector3d& trans);
body::Pose pose_of(const PoseParameters& parameters);
Eigen::Vector3d trans_of(const PoseParameters& parameters);

}  // namespace sflsh::validate
