// Per-frame pose fit and shared-β fit by Levenberg–Marquardt (Eigen's MINPACK port); see pose_fit.hpp.
#include "lm_status.hpp"
#include "pose_gauss_newton.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/progress.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/validate/dynamics_metrics.hpp>
#include <sflsh/validate/pose_fit.hpp>
#include <sflsh/validate/rigidity.hpp>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <unsupported/Eigen/LevenbergMarquardt>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace sflsh::validate {

namespace {

/// The vertices the fit uses (every stride-th, heavy enough) and √w of each; `weights` is w per body vertex.
struct FitRows {
  std::vector<int> vertices;
  Eigen::VectorXd scales;
  Eigen::VectorXd weights;      ///< w_i of every body vertex (the rigid start uses them all)
  Eigen::VectorXd fit_weights;  ///< w of each fit row (scales²)
};

/// w_i per body vertex for the options' weighting.
Eigen::VectorXd vertex_weights(const body::BodyModel& model, const PoseFitOptions& options) {
  const Eigen::Index n = model.num_vertices();
  for (int v : options.soft_vertices)
    require(v >= 0 && v < n, "pose fit: soft-region vertex {} outside the body's {} vertices", v, n);
  if (options.weighting == PoseFitWeighting::rigidity)
    return rigidity_weights(model, options.soft_vertices, options.rigid_depth);
  Eigen::VectorXd weights = Eigen::VectorXd::Ones(n);
  for (int v : options.soft_vertices) weights[v] = options.soft_weight;
  return weights;
}

FitRows fit_rows(const Eigen::VectorXd& weights, const PoseFitOptions& options) {
  FitRows rows;
  rows.weights = weights;
  const bool drop_light = options.weighting == PoseFitWeighting::rigidity;
  for (Eigen::Index i = 0; i < weights.size(); i += options.vertex_stride)
    if (!drop_light || rows.weights[i] >= options.min_weight) rows.vertices.push_back(static_cast<int>(i));
  require(!rows.vertices.empty(), "pose fit: no vertex weighs at least min_weight {}", options.min_weight);
  rows.scales.resize(static_cast<Eigen::Index>(rows.vertices.size()));
  for (std::size_t s = 0; s < rows.vertices.size(); ++s)
    rows.scales[static_cast<Eigen::Index>(s)] = std::sqrt(rows.weights[rows.vertices[s]]);
  rows.fit_weights = rows.scales.cwiseAbs2();
  return rows;
}

/// The temporal prior of one frame: residual √λ_θ (θ − prediction), prediction = 2θ_{t−1} − θ_{t−2}.
struct TemporalPrior {
  bool active = false;
  double scale = 0.0;  ///< √λ_θ
  body::Pose prediction = body::Pose::Zero();
};

/// r_s = √w_s (v_i − y_i) for the fit rows i = vertices[s].
void frame_residual(const RowMatrixX3d& target, const FitRows& rows, const RowMatrixX3d& v, Eigen::VectorXd& r) {
  r.resize(3 * static_cast<Eigen::Index>(rows.vertices.size()));
  for (std::size_t s = 0; s < rows.vertices.size(); ++s) {
    const int i = rows.vertices[s];
    const auto e = static_cast<Eigen::Index>(s);
    r.segment<3>(3 * e) = rows.scales[e] * (v.row(i) - target.row(i)).transpose();
  }
}

/// r(δ) for parameters base + δ. LM works on the offset δ from the warm start, starting at δ = 0 exactly:
/// MINPACK bounds its first step by factor·‖D x₀‖ (factor itself only when x₀ = 0), so a start with tiny
/// non-zero entries (a rest pose, a pose ~1e-17 from zero) would crawl for dozens of iterations.
struct FrameResidual : Eigen::DenseFunctor<double> {
  const PosedModel* model;
  const RowMatrixX3d* target;
  const FitRows* rows;
  PoseParameters base;
  FrameResidual(const PosedModel& m, const RowMatrixX3d& y, const FitRows& fr, const PoseParameters& start)
      : DenseFunctor<double>(kNumPoseParameters, static_cast<int>(3 * fr.vertices.size())),
        model(&m),
        target(&y),
        rows(&fr),
        base(start) {}

  int operator()(const Eigen::VectorXd& delta, Eigen::VectorXd& r) const {
    frame_residual(*target, *rows, model->posed(base + delta), r);
    return r.allFinite() ? 0 : -1;  // a negative value stops LM with UserAsked
  }
  int df(const Eigen::VectorXd& delta, Eigen::MatrixXd& jacobian) const {
    RowMatrixX3d v;
    model->posed_and_jacobian(base + delta, v, jacobian, &rows->vertices);
    for (Eigen::Index s = 0; s < rows->scales.size(); ++s) jacobian.middleRows<3>(3 * s) *= rows->scales[s];
    return jacobian.allFinite() ? 0 : -1;
  }
};

template <typename Solver>
void configure(Solver& lm, const PoseFitOptions& options, int max_evaluations) {
  lm.setMaxfev(max_evaluations);
  lm.setXtol(options.tolerance);
  lm.setFtol(options.tolerance);
}

double rms_over(const RowMatrixX3d& v, const RowMatrixX3d& y, const std::vector<char>* exclude) {
  double sum = 0.0;
  Eigen::Index count = 0;
  for (Eigen::Index i = 0; i < v.rows(); ++i) {
    if (exclude && (*exclude)[static_cast<std::size_t>(i)]) continue;
    sum += (v.row(i) - y.row(i)).squaredNorm();
    ++count;
  }
  return count ? std::sqrt(sum / static_cast<double>(count)) : 0.0;
}

/// ‖r‖ below which a fit over `vertices` rows counts as exact: RMS absolute_tolerance per vertex.
double absolute_norm(const PoseFitOptions& options, std::size_t vertices) {
  return options.absolute_tolerance * std::sqrt(static_cast<double>(vertices));
}

/// One solve of a frame's pose on the fit rows; `parameters` in/out. Rigidity weighting: damped Gauss–Newton on
/// the normal equations with the temporal prior (pose_gauss_newton.hpp); soft_weight: MINPACK's LM as before.
FrameFitReport solve_frame(const PosedModel& model, const RowMatrixX3d& target, const FitRows& rows,
                           const PoseFitOptions& options, PoseParameters& parameters, const TemporalPrior& prior = {}) {
  if (options.weighting == PoseFitWeighting::rigidity) {
    detail::GaussNewtonSettings settings;
    settings.max_evaluations = options.max_evaluations;
    settings.tolerance = options.tolerance;
    const double norm = absolute_norm(options, rows.vertices.size());
    settings.absolute_cost = norm * norm;
    if (prior.active) {
      settings.prior_weight = prior.scale * prior.scale;
      settings.prediction = prior.prediction;
    }
    const detail::GaussNewtonReport gn =
        detail::solve_pose_gauss_newton(model, target, rows.vertices, rows.fit_weights, settings, parameters);
    FrameFitReport report;
    report.iterations = gn.iterations;
    report.evaluations = gn.evaluations;
    report.converged = gn.converged;
    report.status = gn.status;
    return report;
  }
  FrameResidual residual(model, target, rows, parameters);
  Eigen::LevenbergMarquardt<FrameResidual> lm(residual);
  configure(lm, options, options.max_evaluations);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(kNumPoseParameters);
  const detail::LmOutcome outcome = detail::minimize_until(lm, x, absolute_norm(options, rows.vertices.size()));
  FrameFitReport report;
  report.iterations = static_cast<int>(lm.iterations());
  report.evaluations = static_cast<int>(lm.nfev());
  report.status = outcome.name();
  report.converged = outcome.converged();
  require(outcome.status != Eigen::LevenbergMarquardtSpace::UserAsked && x.allFinite(),
          "pose fit: the residual became non-finite (NaN/Inf) after {} evaluations", report.evaluations);
  parameters += x;
  logger()->trace("pose fit: {} evaluations, {}", report.evaluations, report.status);
  return report;
}

/// Variable projection over β: residual r(β) = r(β, θ*(β)) over the shape frames, with the poses θ*(β)
/// re-fitted (warm-started) at every evaluation; Jacobian (I − Q_θQ_θᵀ) J_β per frame (Kaufman 1975).
struct ShapeResidual : Eigen::DenseFunctor<double> {
  const body::BodyModel* model;
  const std::vector<const RowMatrixX3d*>* targets;
  const FitRows* rows;
  const PoseFitOptions* options;
  std::vector<PoseParameters>* poses;  // warm starts, updated by every evaluation
  ShapeResidual(const body::BodyModel& m, const std::vector<const RowMatrixX3d*>& y, const FitRows& fr,
                const PoseFitOptions& o, std::vector<PoseParameters>& p)
      : DenseFunctor<double>(body::kNumBetas, static_cast<int>(3 * fr.vertices.size() * y.size())),
        model(&m),
        targets(&y),
        rows(&fr),
        options(&o),
        poses(&p) {}

  PosedModel posed_model(const Eigen::VectorXd& beta) const {
    RowMatrixX3d shaped = body::shaped_template(*model, beta);
    const body::JointPositions joints = body::regress_joints(*model, shaped);
    return PosedModel(*model, std::move(shaped), joints, options->world_from_body);
  }

  /// Re-fits every shape frame's pose at β and returns the stacked residual.
  int operator()(const Eigen::VectorXd& beta, Eigen::VectorXd& r) const {
    if (!beta.allFinite()) return -1;
    const PosedModel m = posed_model(beta);
    const auto block = 3 * static_cast<Eigen::Index>(rows->vertices.size());
    r.resize(block * static_cast<Eigen::Index>(targets->size()));
    for (std::size_t f = 0; f < targets->size(); ++f) {
      solve_frame(m, *(*targets)[f], *rows, *options, (*poses)[f]);
      Eigen::VectorXd rf;
      frame_residual(*(*targets)[f], *rows, m.posed((*poses)[f]), rf);
      r.segment(block * static_cast<Eigen::Index>(f), block) = rf;
    }
    return r.allFinite() ? 0 : -1;
  }

  int df(const Eigen::VectorXd& beta, Eigen::MatrixXd& jacobian) const {
    const auto block = 3 * static_cast<Eigen::Index>(rows->vertices.size());
    jacobian.resize(block * static_cast<Eigen::Index>(targets->size()), body::kNumBetas);
    const PosedModel m = posed_model(beta);
    const double h = 1e-6;  // central differences: O(h²) truncation, round-off ε/h ≈ 1e-10 on O(1) entries
    for (std::size_t f = 0; f < targets->size(); ++f) {
      const PoseParameters& p = (*poses)[f];
      Eigen::MatrixXd j_theta;
      RowMatrixX3d v;
      m.posed_and_jacobian(p, v, j_theta, &rows->vertices);
      Eigen::MatrixXd j_beta(block, body::kNumBetas);
      for (int k = 0; k < body::kNumBetas; ++k) {
        Eigen::VectorXd plus = beta, minus = beta;
        plus[k] += h;
        minus[k] -= h;
        const RowMatrixX3d dv = (posed_model(plus).posed(p) - posed_model(minus).posed(p)) / (2 * h);
        for (std::size_t s = 0; s < rows->vertices.size(); ++s)
          j_beta.block<3, 1>(3 * static_cast<Eigen::Index>(s), k) = dv.row(rows->vertices[s]).transpose();
      }
      for (Eigen::Index s = 0; s < rows->scales.size(); ++s) {
        j_theta.middleRows<3>(3 * s) *= rows->scales[s];
        j_beta.middleRows<3>(3 * s) *= rows->scales[s];
      }
      // Project out the range of the pose Jacobian (only its numerically independent columns).
      const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(j_theta);
      Eigen::MatrixXd rotated = qr.householderQ().adjoint() * j_beta;
      rotated.topRows(qr.rank()).setZero();
      jacobian.middleRows(block * static_cast<Eigen::Index>(f), block) = qr.householderQ() * rotated;
    }
    return jacobian.allFinite() ? 0 : -1;
  }
};

}  // namespace

const char* weighting_name(PoseFitWeighting weighting) {
  return weighting == PoseFitWeighting::rigidity ? "rigidity" : "soft_weight";
}

PoseFitWeighting parse_weighting(const std::string& name) {
  if (name == "rigidity") return PoseFitWeighting::rigidity;
  if (name == "soft_weight") return PoseFitWeighting::soft_weight;
  throw Error(fmt::format("pose fit: unknown weighting '{}', expected rigidity or soft_weight", name));
}

PoseParameters rigid_initial_pose(const RowMatrixX3d& shaped, const Eigen::Vector3d& root, const RowMatrixX3d& target,
                                  const Eigen::VectorXd& weights, const Eigen::Matrix3d& world_from_body) {
  // Weighted Kabsch: y ≈ R x + t in the body frame (targets rotated back by world_from_body).
  const RowMatrixX3d y = target * world_from_body;  // rows R_wbᵀ y_i
  const double total = weights.sum();
  const Eigen::RowVector3d cx = (weights.asDiagonal() * shaped).colwise().sum() / total;
  const Eigen::RowVector3d cy = (weights.asDiagonal() * y).colwise().sum() / total;
  const Eigen::Matrix3d covariance = (shaped.rowwise() - cx).transpose() * weights.asDiagonal() * (y.rowwise() - cy);
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d rotation = svd.matrixV() * d * svd.matrixU().transpose();
  const Eigen::Vector3d t = cy.transpose() - rotation * cx.transpose();
  // SMPL's root rotates about J_0: v = R (x − J_0) + J_0 + trans, so trans = t + R J_0 − J_0.
  PoseParameters p = PoseParameters::Zero();
  const Eigen::AngleAxisd axis_angle(rotation);
  p.head<3>() = axis_angle.angle() * axis_angle.axis();
  p.tail<3>() = t + rotation * root - root;
  return p;
}

FrameFitReport fit_frame(const body::BodyModel& model, const RowMatrixX3d& shaped, const body::JointPositions& joints,
                         const RowMatrixX3d& target, const PoseFitOptions& options, PoseParameters& parameters) {
  const Eigen::Index n = model.num_vertices();
  require(target.rows() == n, "pose fit: {} target vertices for a body of {}", target.rows(), n);
  require(options.vertex_stride >= 1, "pose fit: vertex_stride must be at least 1, got {}", options.vertex_stride);
  const PosedModel posed_model(model, shaped, joints, options.world_from_body);
  const FitRows rows = fit_rows(vertex_weights(model, options), options);
  FrameFitReport report = solve_frame(posed_model, target, rows, options, parameters);
  const RowMatrixX3d v = posed_model.posed(parameters);
  std::vector<char> soft(static_cast<std::size_t>(n), 0);
  for (int s : options.soft_vertices) soft[static_cast<std::size_t>(s)] = 1;
  report.rms = rms_over(v, target, nullptr);
  report.rms_rigid = rms_over(v, target, &soft);
  return report;
}

namespace {

/// σ_0 of the measured rigidity: the RMS dynamics amplitude that the last fit leaves on the vertices outside
/// the soft region, σ_0² = mean_{i ∉ soft} σ_i², at least `least`. Those vertices carry no soft tissue, so
/// their σ is what registration noise and the fit's own pose error alone leave on a vertex.
double rigid_motion_scale(const Eigen::VectorXd& sigma, const std::vector<int>& soft_vertices, double least) {
  std::vector<char> soft(static_cast<std::size_t>(sigma.size()), 0);
  for (int v : soft_vertices) soft[static_cast<std::size_t>(v)] = 1;
  double sum_of_squares = 0.0;
  Eigen::Index count = 0;
  for (Eigen::Index i = 0; i < sigma.size(); ++i) {
    if (soft[static_cast<std::size_t>(i)]) continue;
    sum_of_squares += sigma[i] * sigma[i];
    ++count;
  }
  return count ? std::max(least, std::sqrt(sum_of_squares / static_cast<double>(count))) : least;
}

/// The reweighting factor per vertex, the share of vertex i's variance that the rigid vertices also show,
/// f_i = max(f_min, σ_0² / (σ_0² + σ_i²)) = max(f_min, 1 / (1 + (σ_i / σ_0)²)).
Eigen::VectorXd measured_rigidity(const Eigen::VectorXd& sigma, double scale, double floor) {
  return (1.0 + (sigma / scale).array().square()).inverse().max(floor).matrix();
}

/// λ_θ of a reweighted fit. Each vertex's weight is the inverse of its variance in units of the noise variance
/// σ_0², so the data term is Σ w_i r_i² / σ_0² up to the factor σ_0², and the prior on θ keeps its own angular scale
/// σ_θ: λ_θ = σ_0² / σ_θ². The first fit sets σ_θ (λ_θ given, σ_0 = `first_scale` measured after it), so a later
/// pass whose fit leaves σ_0 = `scale` weighs the prior by λ_θ (σ_0 / σ_0,first)². Without that the prior would
/// grow against the data as the fit improves and σ_0 shrinks, and steer the joints that only soft vertices observe.
double scaled_temporal_weight(double temporal_weight, double scale, double first_scale) {
  const double ratio = scale / first_scale;
  return temporal_weight * ratio * ratio;
}

/// Frame indices of the warm-start chain: every c-th frame, at most 40 frames.
std::vector<int> warm_start_chain(int T) {
  const int chain_stride = std::max(1, T / 40);
  std::vector<int> chain;
  for (int t = 0; t < T; t += chain_stride) chain.push_back(t);
  return chain;
}

/// Indices into a chain of `chain_size` frames, at most `shape_frames`, evenly spaced, first and last included.
std::vector<int> shape_frame_picks(std::size_t chain_size, int shape_frames) {
  const int k = std::min<int>(shape_frames, static_cast<int>(chain_size));
  std::vector<int> picks;  // indices into the chain, evenly spaced, first and last included
  for (int s = 0; s < k; ++s)
    picks.push_back(
        k == 1 ? 0
               : static_cast<int>(std::lround(static_cast<double>(s) * static_cast<double>(chain_size - 1) / (k - 1))));
  picks.erase(std::unique(picks.begin(), picks.end()), picks.end());
  return picks;
}

/// The frames the shape fit uses and their warm-start poses.
struct ShapeFrames {
  std::vector<const RowMatrixX3d*> targets;
  std::vector<PoseParameters> poses;
};

/// Warm starts for the shape frames at β = 0: a chain of pose fits over every c-th frame (≤ 40 frames),
/// each from the previous one (a rest-pose start is fine for frame 0 but slow for a distant pose).
ShapeFrames warm_start_shape_frames(const body::BodyModel& model, const std::vector<RowMatrixX3d>& registered,
                                    const FitRows& rows, const PoseFitOptions& options, const body::Betas& beta) {
  const std::vector<int> chain = warm_start_chain(static_cast<int>(registered.size()));
  const std::vector<int> picks = shape_frame_picks(chain.size(), options.shape_frames);
  ShapeFrames frames;
  const RowMatrixX3d shaped = body::shaped_template(model, beta);
  const body::JointPositions joints = body::regress_joints(model, shaped);
  const PosedModel start_model(model, shaped, joints, options.world_from_body);
  PoseParameters p =
      rigid_initial_pose(shaped, joints.row(0).transpose(), registered.front(), rows.weights, options.world_from_body);
  PoseFitOptions warm = options;  // only warm starts: a few evaluations each
  warm.max_evaluations = std::min(options.max_evaluations, 20);
  std::size_t next = 0;
  for (std::size_t c = 0; c < chain.size() && next < picks.size(); ++c) {
    const RowMatrixX3d& y = registered[static_cast<std::size_t>(chain[c])];
    solve_frame(start_model, y, rows, warm, p);
    if (static_cast<int>(c) == picks[next]) {
      frames.targets.push_back(&y);
      frames.poses.push_back(p);
      ++next;
    }
  }
  return frames;
}

/// Fits the shared β from `beta_start` by variable projection over the shape frames; records it in `result`.
void fit_shared_beta(const body::BodyModel& model, const std::vector<RowMatrixX3d>& registered, const FitRows& rows,
                     const PoseFitOptions& options, const body::Betas& beta_start, PoseFitResult& result) {
  ShapeFrames frames = warm_start_shape_frames(model, registered, rows, options, result.beta);
  ShapeResidual residual(model, frames.targets, rows, options, frames.poses);
  Eigen::LevenbergMarquardt<ShapeResidual> lm(residual);
  configure(lm, options, options.shape_evaluations);
  Eigen::VectorXd x = beta_start;
  const detail::LmOutcome outcome =
      detail::minimize_until(lm, x, absolute_norm(options, rows.vertices.size() * frames.targets.size()));
  require(outcome.status != Eigen::LevenbergMarquardtSpace::UserAsked && x.allFinite(),
          "shape fit: the residual became non-finite (NaN/Inf)");
  result.beta = x;
  result.shape_iterations = static_cast<int>(lm.iterations());
  result.shape_converged = outcome.converged();
  if (!result.shape_converged)
    logger()->warn("shape fit: β did not converge ({}, {} evaluations)", outcome.name(), lm.nfev());
  logger()->debug("shape fit: {} iterations, {} evaluations ({})", lm.iterations(), lm.nfev(), outcome.name());
}

/// The temporal prior of frame t from the frames fitted so far in `motion`; from frame 2 on it also moves the warm
/// start `parameters` to the prediction.
TemporalPrior frame_temporal_prior(const body::Motion& motion, const PoseFitOptions& options, int t,
                                   PoseParameters& parameters) {
  TemporalPrior prior;
  // θ_t − 2θ_{t−1} + θ_{t−2}: the prior pulls towards the constant-velocity prediction, which is also the
  // warm start (trans included). Frame 1 has only θ_0 to go by (first difference), frame 0 its rigid start.
  const auto& poses = motion.poses;
  const auto& trans = motion.trans;
  prior.active = true;
  prior.scale = std::sqrt(options.temporal_weight);
  if (t >= 2) {
    const std::size_t a = static_cast<std::size_t>(t - 1), b = static_cast<std::size_t>(t - 2);
    prior.prediction = 2.0 * poses[a] - poses[b];
    parameters = pack_pose(prior.prediction, 2.0 * trans[a] - trans[b]);
  } else {
    prior.prediction = pose_of(parameters);
  }
  return prior;
}

/// Adds the fit of frame t (of T) to `result`: its report, its pose and translation, the RMS statistics.
void record_frame_fit(const FrameFitReport& report, int t, int T, const PoseParameters& parameters,
                      PoseFitResult& result) {
  if (!report.converged) {
    ++result.unconverged_frames;
    logger()->warn("pose fit: frame {} did not converge ({}, {} evaluations, RMS {:.2f} mm)", t, report.status,
                   report.evaluations, 1e3 * report.rms);
  }
  result.max_rms = std::max(result.max_rms, report.rms);
  result.mean_rms += report.rms / T;
  result.frames.push_back(report);
  result.motion.poses.push_back(pose_of(parameters));
  result.motion.trans.push_back(trans_of(parameters));
}

/// Fits the pose of every frame at `result.beta`, each warm-started from the previous one; fills `result.motion`.
void fit_every_frame(const body::BodyModel& model, const std::vector<RowMatrixX3d>& registered, double fps,
                     const FitRows& rows, const PoseFitOptions& options, PoseFitResult& result) {
  const Eigen::Index n = model.num_vertices();
  const auto T = static_cast<int>(registered.size());
  const Eigen::VectorXd& weights = rows.weights;  // for the rigid start
  const RowMatrixX3d shaped = body::shaped_template(model, result.beta);
  const body::JointPositions joints = body::regress_joints(model, shaped);
  const PosedModel posed_model(model, shaped, joints, options.world_from_body);
  std::vector<char> soft(static_cast<std::size_t>(n), 0);
  for (int s : options.soft_vertices) soft[static_cast<std::size_t>(s)] = 1;
  result.motion.name = "fitted";
  result.motion.source = "pose fit";
  result.motion.fps = fps;
  result.motion.world_from_body = options.world_from_body;
  PoseParameters parameters =
      rigid_initial_pose(shaped, joints.row(0).transpose(), registered.front(), weights, options.world_from_body);
  Progress progress("pose fit", static_cast<std::size_t>(T), options.progress);
  const bool use_prior = options.weighting == PoseFitWeighting::rigidity && options.temporal_weight > 0.0;
  for (int t = 0; t < T; ++t) {
    const RowMatrixX3d& target = registered[static_cast<std::size_t>(t)];
    TemporalPrior prior;
    if (use_prior) prior = frame_temporal_prior(result.motion, options, t, parameters);
    FrameFitReport report =
        solve_frame(posed_model, target, rows, options, parameters, prior);  // warm start from frame t − 1
    report.frame = t;
    const RowMatrixX3d v = posed_model.posed(parameters);
    report.rms = rms_over(v, target, nullptr);
    report.rms_rigid = rms_over(v, target, &soft);
    record_frame_fit(report, t, T, parameters, result);
    progress.advance();
  }
  progress.finish();
}

/// One fit of every frame with the vertex weights `weights`; β fitted (from `initial_beta`) when `beta` is empty.
PoseFitResult fit_motion_weighted(const body::BodyModel& model, const std::vector<RowMatrixX3d>& registered, double fps,
                                  const std::optional<body::Betas>& beta, const body::Betas& initial_beta,
                                  const PoseFitOptions& options, const Eigen::VectorXd& vertex_weight) {
  const auto t0 = std::chrono::steady_clock::now();
  const FitRows rows = fit_rows(vertex_weight, options);

  PoseFitResult result;
  result.beta = beta.value_or(body::Betas::Zero());
  result.beta_fitted = !beta.has_value();
  const body::Betas beta_start = beta.value_or(initial_beta);

  if (result.beta_fitted) fit_shared_beta(model, registered, rows, options, beta_start, result);
  fit_every_frame(model, registered, fps, rows, options, result);
  result.seconds = seconds_since(t0);
  return result;
}

}  // namespace

PoseFitResult fit_motion(const body::BodyModel& model, const std::vector<RowMatrixX3d>& registered, double fps,
                         const std::optional<body::Betas>& beta, const PoseFitOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  require(!registered.empty(), "pose fit: no frames");
  require(options.soft_weight >= 0.0 && options.soft_weight <= 1.0, "pose fit: soft_weight must be in [0, 1], got {}",
          options.soft_weight);
  require(options.max_evaluations > 0 && options.shape_frames > 0 && options.shape_evaluations > 0 &&
              options.vertex_stride >= 1,
          "pose fit: iteration limits and the vertex stride must be positive");
  require(options.rigid_depth > 0.0 && options.min_weight >= 0.0 && options.min_weight <= 1.0 &&
              options.temporal_weight >= 0.0 && options.reweighting_passes >= 0 && options.min_motion_scale > 0.0 &&
              options.min_reweight > 0.0 && options.min_reweight <= 1.0,
          "pose fit: rigid_depth and min_motion_scale must be positive, min_weight in [0, 1], temporal_weight and "
          "reweighting_passes non-negative");
  const Eigen::Index n = model.num_vertices();
  for (std::size_t t = 0; t < registered.size(); ++t) {
    require(registered[t].rows() == n, "pose fit: frame {} has {} vertices, the body has {}", t, registered[t].rows(),
            n);
    require(registered[t].allFinite(), "pose fit: frame {} has a non-finite vertex position", t);
  }
  const Eigen::VectorXd prior_weight = vertex_weights(model, options);
  PoseFitResult result = fit_motion_weighted(model, registered, fps, beta, body::Betas::Zero(), options, prior_weight);
  if (options.weighting == PoseFitWeighting::rigidity && registered.size() >= 2) {
    double first_scale = 0.0;  // σ_0 after the first fit
    for (int pass = 0; pass < options.reweighting_passes; ++pass) {
      // Measured rigidity: the σ_i this fit leaves (docs/physics.md §4) down-weighs the vertices that move on
      // their own, w_i ← w_i max(f_min, σ_0² / (σ_0² + σ_i²)), σ_0 what the vertices off the soft region show,
      // and the fit is repeated (β from the last one).
      const Eigen::VectorXd sigma = dynamics_metrics(model, result.beta, result.motion, registered, {}).sigma;
      const double scale = rigid_motion_scale(sigma, options.soft_vertices, options.min_motion_scale);
      if (pass == 0) first_scale = scale;
      PoseFitOptions pass_options = options;
      pass_options.temporal_weight = scaled_temporal_weight(options.temporal_weight, scale, first_scale);
      logger()->debug("pose fit: reweighting pass {}, σ_0 = {:.4f} mm, λ_θ = {:.3g} m²/rad²", pass + 1, 1e3 * scale,
                      pass_options.temporal_weight);
      const Eigen::VectorXd weight = prior_weight.cwiseProduct(measured_rigidity(sigma, scale, options.min_reweight));
      result = fit_motion_weighted(model, registered, fps, beta, result.beta, pass_options, weight);
    }
  }
  result.seconds = seconds_since(t0);
  return result;
}

}  // namespace sflsh::validate
