#pragma once
// The paper's dynamics metric (SFLSH §3, §5, Fig. 3, Table 2; precise definition in docs/physics.md §4).
// For a subject with shape β, per-frame pose θ_t, root translation trans_t and registered (or simulated)
// vertices v_i(t):
//   1. A_i(t) = Σ_k w_ik G'_k(θ_t)                                 (blended transform, incl. trans_t)
//   2. ū_i(t) = A_i(t)⁻¹ [R_wbᵀ v_i(t); 1]                          (inverse skinning; R_wb = world_from_body)
//   3. d_i(t) = ū_i(t) − (T̄ + B_S(β) + B_P(θ_t))_i                  (deviation from the SMPL baseline, neutral pose)
//   4. d̃_i(t) = d_i(t) − mean_t d_i                                 (static offset removed)
//   5. σ_i = sqrt(mean_t ‖d̃_i‖²)
//   6. σ_i^n = sqrt(mean_t (n_i·d̃_i)²), σ_i^t = sqrt(mean_t ‖(I − n_in_iᵀ)d̃_i‖²), σ² = σn² + σt²,
//      n_i the area-weighted unit normal of the shaped template T̄ + B_S(β).
// Steps 4–6 use model::DynamicsAmplitude, the accumulator the simulator reports its own σ with, so
// data and simulation share one definition.
#include <sflsh/body/motion.hpp>
#include <sflsh/body/skinning.hpp>

#include <string>
#include <vector>

namespace sflsh::validate {

using body::RowMatrixX3d;

/// Body vertices of the soft-tissue region (meshing::select_region: torso, upper arms, thighs by default).
std::vector<int> soft_region_vertices(const body::BodyModel& model, const std::vector<std::string>& region_names = {});

/// Pulls posed vertices of one subject back to the neutral pose (steps 1–3). β is fixed at construction.
class NeutralPullback {
 public:
  /// The model must outlive the object.
  NeutralPullback(const body::BodyModel& model, const body::Betas& beta);

  /// ū(t) (n×3) [m]: inverse skinning of `posed` (n×3, world frame) for pose θ and root translation.
  /// Throws when a blended transform is singular (|det A_i| < 1e-6), naming the vertex.
  RowMatrixX3d unposed(const body::Pose& theta, const Eigen::Vector3d& trans, const Eigen::Matrix3d& world_from_body,
                       const RowMatrixX3d& posed) const;
  /// d(t) = ū(t) − (T_S + B_P(θ)) (n×3) [m], SFLSH §3 / docs/physics.md §4 step 3.
  RowMatrixX3d deviation(const body::Pose& theta, const Eigen::Vector3d& trans, const Eigen::Matrix3d& world_from_body,
                         const RowMatrixX3d& posed) const;

  const RowMatrixX3d& shaped() const { return shaped_; }    ///< T_S = T̄ + B_S(β) (n×3)
  const RowMatrixX3d& normals() const { return normals_; }  ///< unit normals of T_S (n×3)
  const body::BodyModel& model() const { return model_; }

 private:
  const body::BodyModel& model_;
  RowMatrixX3d shaped_;
  body::JointPositions joints_;
  RowMatrixX3d normals_;
};

/// Per-vertex dynamics amplitudes of one sequence.
struct DynamicsResult {
  Eigen::VectorXd sigma;           ///< σ_i per body vertex [m]
  Eigen::VectorXd sigma_normal;    ///< σ_i^n [m]
  Eigen::VectorXd sigma_tangent;   ///< σ_i^t [m]
  std::vector<int> soft_vertices;  ///< the region the summary means are taken over (ascending)
  int frames = 0;

  /// mean_i σ_i over the soft-region vertices (the Table-2 scalar) [m]; 0 when the region is empty.
  double mean_sigma_soft() const;
  /// mean_i σ_i over every body vertex [m].
  double mean_sigma_all() const;
  double mean_sigma_normal_soft() const;
  double mean_sigma_tangent_soft() const;
  /// Per vertex: 1 inside the soft region, 0 outside.
  std::vector<char> soft_mask() const;
};

/// σ, σ_n, σ_t of registrations `posed` (T frames of n×3, world frame) explained by β and the motion's
/// θ_t, trans_t and world_from_body (T frames too). Throws on size mismatches and non-finite input.
DynamicsResult dynamics_metrics(const body::BodyModel& model, const body::Betas& beta, const body::Motion& motion,
                                const std::vector<RowMatrixX3d>& posed, const std::vector<int>& soft_vertices);

/// "Fraction of dynamics recovered" (SFLSH §5): mean σ over the soft region of `simulated` divided by that
/// of `ground_truth` (the same vertex set is required). Throws when the ground truth has no dynamics.
double fraction_recovered(const DynamicsResult& simulated, const DynamicsResult& ground_truth);

}  // namespace sflsh::validate
