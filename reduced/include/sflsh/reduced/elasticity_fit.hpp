#pragma once
// The fit of SFLSH §5: the elasticity parameters that make the reduced model's per-vertex dynamics match
// target dynamics σ* (eq. 6), either
//   - independently per subject ("optimal targets", §3): p = the normalized κ̂_i of one subject (3N), or
//   - shape-dependent (§4): p = (A_i, b_i) for all control points (33N), κ̂_ij = A_iᵀβ_j + b_i (eq. 1),
//     regularized with L² or the local shape metric (eq. 7),
// by bounded trust-region least squares (bounded_least_squares.hpp) on
//   r = [ w (σ(q(p)) − σ*) ; √λ L p ],   w = 1/√(number of σ entries)  (so ‖r_fit‖² is a mean square in mm²),
// with dr_fit/dp = (dσ/dq)(dq/dp) (eq. 8): dσ/dq by one-sided finite differences over the (1 + 3N)
// simulations of every case (run by a SimulationPool), dq/dp analytic. q is clamped into the parameter
// ranges (a clamped entry has dq/dp = 0). The number of control points grows over stages (1 → 12 → 24 → 84),
// each warm-started from the previous one's field; a checkpoint after every iteration lets an interrupted
// fit resume where it stopped.
#include <sflsh/reduced/bounded_least_squares.hpp>
#include <sflsh/reduced/fit_point.hpp>
#include <sflsh/reduced/shape_elasticity.hpp>
#include <sflsh/reduced/simulation_pool.hpp>

#include <nlohmann/json_fwd.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace sflsh::reduced {

/// What the fit must reproduce for one case: σ*_n and σ*_t per region vertex (stacked, 2R, mm).
struct FitTarget {
  const DynamicsCase* simulation = nullptr;
  int subject = 0;        ///< index into FitSpec::betas
  Eigen::VectorXd sigma;  ///< [σ*_n; σ*_t]
};

enum class FitKind { independent, shape };

/// How dσ/dq is computed: one-sided finite differences of every entry (the paper, 1 + 3N simulations per
/// case), or forward sensitivities (one differentiated simulation per case, reduced_sensitivity.hpp) for the
/// Young moduli and, unless FitSpec::thickness_differences, for the thickness too (exact through the retarget,
/// rest_geometry_derivative.hpp); with thickness_differences the thickness columns stay one-sided differences
/// (N more plain simulations per case), kept for checking.
enum class JacobianMethod { finite_differences, sensitivities };
const char* jacobian_method_name(JacobianMethod m);
JacobianMethod parse_jacobian_method(const std::string& name);  ///< "fd" or "sensitivities"

struct FitSpec {
  std::string name;  ///< for logs, checkpoints and reports
  FitKind kind = FitKind::shape;
  Regularizer regularizer = Regularizer::local;
  double lambda = 1.0;                     ///< λ of eq. 7 (shape fits)
  std::vector<body::Betas> betas;          ///< per subject (independent: exactly one)
  std::vector<int> stages{1, 12, 24, 84};  ///< control-point counts, ascending
  int iterations = 8;  ///< trust-region iterations per stage: the safety net (FitStageReport::reason says when it hit)
  /// A stage converges when two accepted iterations together lower its loss by ≤ loss_rtol (relative), when the
  /// projected gradient is ≤ 1e-8 · loss, or when the trust region finds no decreasing step (docs/fit.md).
  double loss_rtol = 1e-3;
  double fd_step = 2e-3;                                    ///< one-sided step in normalized κ̂
  double a_max = 0.25;                                      ///< |A_i(k, c)| bound (normalized κ̂ per unit β)
  JacobianMethod jacobian = JacobianMethod::sensitivities;  ///< measured ≈ 38× cheaper for the Y columns
  /// With sensitivities: false (default) gives exact thickness sensitivities (rest_geometry_derivative.hpp;
  /// checked to ~2e-6 against central differences); true keeps one-sided differences, for checking.
  bool thickness_differences = false;
  std::filesystem::path checkpoint;  ///< empty: none
  /// Continuation: when set (p at N = stages.back()), only the last stage runs, starting here (e.g. the same fit
  /// at a neighbouring λ); part of the checkpoint's fingerprint, with `warm_start_from` naming where it came from.
  Eigen::VectorXd warm_start;
  std::string warm_start_from;
  /// What the fit that ended at `warm_start` computed there (its FitResult::final_point): used where it matches,
  /// so the start is not simulated again. Not part of the fingerprint: it changes the cost, never the result.
  std::shared_ptr<const FitPoint> warm_start_point;
};

/// Shared by every fit of an experiment.
struct FitContext {
  const body::BodyModel* body = nullptr;
  const ReducedModel* model = nullptr;
  ReducedOptions reduced;
  material::ParameterBounds bounds;
  SimulationPool* pool = nullptr;
  /// The parameterization for N control points (kept alive by the caller, e.g. a ParameterizationCache).
  std::function<const LayerParameterization&(int)> parameterization;
  bool progress = true;
};

struct FitStageReport {
  int controls = 0;
  int iterations = 0;
  double loss_fit = 0.0;  ///< ‖r_fit‖² [mm²]
  double loss_reg = 0.0;  ///< ‖r_reg‖²
  double seconds = 0.0;
  long simulations = 0;
  int jacobians = 0;
  std::string reason;  ///< the test that ended the stage (LeastSquaresResult::stopped_by) or "resumed"
  bool resumed = false;
};

/// A stage report as JSON (every field but `resumed`; checkpoints and validate's summary.json) and back.
nlohmann::json stage_report_json(const FitStageReport& stage);
FitStageReport stage_report_from_json(const nlohmann::json& json);

struct FitResult {
  std::string name;
  FitKind kind = FitKind::shape;
  int controls = 0;
  Eigen::VectorXd p;  ///< final parameters (layout of the kind)
  std::vector<FitStageReport> stages;
  bool finished_earlier = false;  ///< read back from a finished checkpoint: nothing was run
  /// σ and the normal-equation terms at p, per target (null when not computed there, e.g. finished earlier): a
  /// warm start from p passes it as FitSpec::warm_start_point. A few MB; drop it when no fit continues from p.
  std::shared_ptr<const FitPoint> final_point;
  /// κ̂ (N × 3, clamped) the fit gives a subject of shape β (independent fits ignore β).
  material::KappaMatrix kappa_normalized(const body::Betas& beta, const material::ParameterBounds& bounds) const;
  material::KappaMatrix kappa(const body::Betas& beta, const material::ParameterBounds& bounds) const;  ///< physical
  ShapeElasticity shape() const;  ///< shape fits only
};

FitResult fit_elasticity(const FitContext& context, const std::vector<FitTarget>& targets, const FitSpec& spec);

/// The normal-equation terms JᵀJ, Jᵀr of the fit at p for N = spec.stages.front() (what one trust-region
/// iteration needs), by the spec's Jacobian method — to compare the methods and time them.
NormalEquations fit_normal_equations(const FitContext& context, const std::vector<FitTarget>& targets,
                                     const FitSpec& spec, const Eigen::VectorXd& p, double* residual_seconds = nullptr,
                                     double* jacobian_seconds = nullptr);

/// Parameterizations per control-point count, built on demand from one base layer.
class ParameterizationCache {
 public:
  explicit ParameterizationCache(const model::BodyLayer& base) : base_(base) {}
  const LayerParameterization& get(int controls);

 private:
  const model::BodyLayer& base_;
  std::map<int, std::unique_ptr<LayerParameterization>> cache_;
};

}  // namespace sflsh::reduced
