#pragma once
// The per-frame pose solve of the rigidity-weighted fit (pose_fit.hpp): damped Gauss–Newton (Levenberg's
// damping H + μ diag H) on the 75×75 normal equations, accumulated block-sparsely by PosedModel::normal_equations,
// with the temporal prior λ_θ ‖θ − θ_pred‖² added to H and g. Cheaper than MINPACK's QR of the 3m×75 Jacobian
// by the ratio m·75² / (m·k²·9) with k ≈ 8 joints per vertex.
#include <sflsh/validate/pose_jacobian.hpp>

#include <string>
#include <vector>

namespace sflsh::validate::detail {

struct GaussNewtonSettings {
  int max_evaluations = 100;                   ///< cost evaluations (each trial step is one, each linearization one)
  double tolerance = 1e-7;                     ///< stop when the step or the relative cost reduction falls below it
  double absolute_cost = 0.0;                  ///< stop when the data cost falls below it [m²]
  double prior_weight = 0.0;                   ///< λ_θ [m²/rad²]; 0: no prior
  body::Pose prediction = body::Pose::Zero();  ///< θ_pred of the prior
};

struct GaussNewtonReport {
  int iterations = 0;
  int evaluations = 0;
  bool converged = false;
  std::string status;
};

/// Minimizes Σ_s w_s ‖v_{rows[s]}(x) − y‖² + λ_θ ‖θ(x) − θ_pred‖² from `x` (in/out). Throws when the cost or the
/// step is not finite.
GaussNewtonReport solve_pose_gauss_newton(const PosedModel& model, const RowMatrixX3d& target,
                                          const std::vector<int>& rows, const Eigen::VectorXd& weights,
                                          const GaussNewtonSettings& settings, PoseParameters& x);

}  // namespace sflsh::validate::detail
