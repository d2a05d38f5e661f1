#pragma once
// Fitting SMPL pose θ_t, root translation trans_t (and shape β) to registrations with the body's topology
// (vertex-to-vertex; docs/physics.md §3.2 "poses are not in the file"). Nonlinear least squares on vertex
// positions,
//   min Σ_i w_i ‖v_i(β, θ_t, trans_t) − y_i(t)‖² + λ_θ ‖θ_t − 2θ_{t−1} + θ_{t−2}‖²,
// so that the soft tissue's dynamics is not explained by pose. Default (PoseFitWeighting::rigidity): w_i the
// rigidity weights of rigidity.hpp (1 off the soft region, (D_0/D_i)⁴ on it, D_i the distance to the bones)
// and a temporal prior λ_θ on the second difference of θ towards the previous two fitted frames (causal).
// PoseFitWeighting::soft_weight is the earlier fit: w_i = soft_weight on the soft region, 1 elsewhere, no prior. Solved
// with Eigen's Levenberg–Marquardt (unsupported/Eigen/LevenbergMarquardt, MINPACK's lmder): per frame with the analytic
// Jacobian of pose_jacobian.hpp, warm-started from the previous frame (frame 0 from a weighted Kabsch alignment of the
// rest shape). When β is not given it is shared over frames and fitted jointly with the poses of a few
// evenly spaced frames by variable projection (Golub & Pereyra 1973; Kaufman 1975): the outer LM over β
// sees the residual with each frame's pose re-optimized for that β, and its Jacobian is the β-Jacobian
// (central differences) projected onto the orthogonal complement of the pose Jacobian's range,
//   J_proj = (I − Q_θ Q_θᵀ) J_β.
// The fit uses every `vertex_stride`-th vertex (the dense QR inside LM costs 6·n_fit·75² flops).
#include <sflsh/body/motion.hpp>
#include <sflsh/body/skinning.hpp>
#include <sflsh/validate/pose_jacobian.hpp>

#include <optional>
#include <string>
#include <vector>

namespace sflsh::validate {

using body::RowMatrixX3d;

/// How the fit weighs vertices.
enum class PoseFitWeighting {
  rigidity,     ///< rigidity weights (rigidity.hpp) and the temporal prior on θ (the default)
  soft_weight,  ///< w_i = soft_weight on the soft region, 1 elsewhere, no temporal prior (the earlier fit)
};

/// "rigidity" / "soft_weight"; parse throws naming the accepted values.
const char* weighting_name(PoseFitWeighting weighting);
PoseFitWeighting parse_weighting(const std::string& name);

struct PoseFitOptions {
  std::vector<int> soft_vertices;  ///< body vertices of the soft region (the layer's region)
  PoseFitWeighting weighting = PoseFitWeighting::rigidity;
  double soft_weight = 0.05;      ///< soft_weight: w_i of the soft vertices (squared-residual weight; 1 elsewhere)
  double rigid_depth = 0.05;      ///< rigidity: D_0 [m], soft vertices nearer the bones count as rigid
  double min_weight = 1e-3;       ///< rigidity: vertices weighing less are left out of the fit
  double temporal_weight = 1e-5;  ///< rigidity: λ_θ [m²/rad²] of the second-difference prior on θ (first fit;
                                  ///< a reweighted fit scales it by (σ_0 / σ_0 after the first fit)²)
  int reweighting_passes = 2;  ///< rigidity: refits with w_i max(f_min, σ_0² / (σ_0² + σ_i²)), σ_i of the last fit
  double min_motion_scale = 1e-6;  ///< rigidity: least σ_0 [m] (σ_0: the RMS σ the last fit leaves off the soft region)
  double min_reweight = 1e-6;      ///< rigidity: f_min, the reweighting factor's floor (a guard only)
  int max_evaluations = 100;       ///< per Levenberg–Marquardt solve (residual evaluations)
  double tolerance = 1e-7;         ///< relative tolerance on the step and on the reduction of the sum of squares
  double absolute_tolerance = 1e-10;  ///< [m] a fit whose weighted RMS residual falls below this is exact
  int vertex_stride = 2;              ///< fit on vertices 0, s, 2s, … (1: every vertex)
  int shape_frames = 4;               ///< frames used for the β fit (evenly spaced, first and last included)
  int shape_evaluations = 60;         ///< outer LM evaluations of the β fit (each re-fits the shape frames' poses)
  Eigen::Matrix3d world_from_body = Eigen::Matrix3d::Identity();  ///< applied to posed vertices before comparing
  bool progress = false;                                          ///< show a progress line
};

/// How one frame's fit went.
struct FrameFitReport {
  int frame = 0;
  double rms = 0.0;        ///< sqrt(mean_i ‖v_i − y_i‖²) over every vertex [m]
  double rms_rigid = 0.0;  ///< the same over the vertices outside the soft region [m]
  int iterations = 0;
  int evaluations = 0;
  bool converged = false;
  std::string status;  ///< Levenberg–Marquardt's stopping reason
};

struct PoseFitResult {
  body::Betas beta = body::Betas::Zero();
  bool beta_fitted = false;
  int shape_iterations = 0;  ///< outer LM iterations of the β fit
  bool shape_converged = true;
  body::Motion motion;  ///< fitted θ_t, trans_t; fps as given; world_from_body of the options
  std::vector<FrameFitReport> frames;
  int unconverged_frames = 0;
  double max_rms = 0.0;   ///< [m]
  double mean_rms = 0.0;  ///< [m]
  double seconds = 0.0;
};

/// The fit of one frame from an initial guess (`parameters` in/out: θ then trans, as pose_jacobian.hpp).
/// Throws sflsh::Error when a residual or the result is not finite.
FrameFitReport fit_frame(const body::BodyModel& model, const RowMatrixX3d& shaped, const body::JointPositions& joints,
                         const RowMatrixX3d& target, const PoseFitOptions& options, PoseParameters& parameters);

/// Initial θ (root orientation only) and trans aligning the unposed shape `shaped` to `target` rigidly
/// (weighted Kabsch about the root joint `root`).
PoseParameters rigid_initial_pose(const RowMatrixX3d& shaped, const Eigen::Vector3d& root, const RowMatrixX3d& target,
                                  const Eigen::VectorXd& weights, const Eigen::Matrix3d& world_from_body);

/// Fits every frame of `registered` (T frames of n×3, world frame, the body's vertex order). β is fitted
/// when `beta` is empty. Frames that do not converge are reported (and logged), not fatal; a non-finite
/// residual is. Throws on size mismatches.
PoseFitResult fit_motion(const body::BodyModel& model, const std::vector<RowMatrixX3d>& registered, double fps,
                         const std::optional<body::Betas>& beta, const PoseFitOptions& options);

}  // namespace sflsh::validate
