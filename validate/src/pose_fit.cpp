// Per-frame pose fit and shared-β fit by Levenberg–Marquardt (Eigen's MINPACK port); see pose_fit.hpp.
#include <sflsh/validate/pose_fit.hpp>
#include <sflsh/validate/pose_jacobian.hpp>

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/progress.hpp>

#include <unsupported/Eigen/LevenbergMarquardt>
#include <unsupported/Eigen/NumericalDiff>

#include <Eigen/SVD>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace sflsh::validate {

namespace {

using Status = Eigen::LevenbergMarquardtSpace::Status;

std::string status_name(Status s) {
  switch (s) {
    case Eigen::LevenbergMarquardtSpace::RelativeReductionTooSmall: return "relative reduction below tolerance";
    case Eigen::LevenbergMarquardtSpace::RelativeErrorTooSmall: return "relative step below tolerance";
    case Eigen::LevenbergMarquardtSpace::RelativeErrorAndReductionTooSmall: return "relative step and reduction below tolerance";
    case Eigen::LevenbergMarquardtSpace::CosinusTooSmall: return "residual orthogonal to the Jacobian";
    case Eigen::LevenbergMarquardtSpace::TooManyFunctionEvaluation: return "too many evaluations";
    case Eigen::LevenbergMarquardtSpace::FtolTooSmall: return "no further reduction possible";
    case Eigen::LevenbergMarquardtSpace::XtolTooSmall: return "no further step possible";
    case Eigen::LevenbergMarquardtSpace::GtolTooSmall: return "gradient vanished";
    case Eigen::LevenbergMarquardtSpace::UserAsked: return "non-finite residual";
    case Eigen::LevenbergMarquardtSpace::ImproperInputParameters: return "improper input";
    default: return "not run";
  }
}

bool converged(Status s) {
  return s != Eigen::LevenbergMarquardtSpace::TooManyFunctionEvaluation && s != Eigen::LevenbergMarquardtSpace::UserAsked &&
         s != Eigen::LevenbergMarquardtSpace::ImproperInputParameters && s != Eigen::LevenbergMarquardtSpace::NotStarted &&
         s != Eigen::LevenbergMarquardtSpace::Running;
}

/// √w_i per vertex.
Eigen::VectorXd residual_scales(Eigen::Index n, const PoseFitOptions& options) {
  Eigen::VectorXd s = Eigen::VectorXd::Ones(n);
  for (int v : options.soft_vertices) s[v] = std::sqrt(options.soft_weight);
  return s;
}

/// r(θ, trans) = √w_i (v_i − y_i), 3n values, analytic Jacobian.
struct FrameResidual : Eigen::DenseFunctor<double> {
  const PosedModel* model;
  const RowMatrixX3d* target;
  const Eigen::VectorXd* scales;
  FrameResidual(const PosedModel& m, const RowMatrixX3d& y, const Eigen::VectorXd& s)
      : DenseFunctor<double>(kNumPoseParameters, static_cast<int>(3 * y.rows())), model(&m), target(&y), scales(&s) {}

  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& r) const {
    const RowMatrixX3d v = model->posed(x);
    fill(v, r);
    return r.allFinite() ? 0 : -1;  // a negative value stops LM with UserAsked
  }
  int df(const Eigen::VectorXd& x, Eigen::MatrixXd& jacobian) const {
    RowMatrixX3d v;
    model->posed_and_jacobian(x, v, jacobian);
    for (Eigen::Index i = 0; i < v.rows(); ++i) jacobian.middleRows<3>(3 * i) *= (*scales)[i];
    return jacobian.allFinite() ? 0 : -1;
  }
  void fill(const RowMatrixX3d& v, Eigen::VectorXd& r) const {
    r.resize(3 * v.rows());
    for (Eigen::Index i = 0; i < v.rows(); ++i) r.segment<3>(3 * i) = (*scales)[i] * (v.row(i) - target->row(i)).transpose();
  }
};

/// r(β) over a set of frames with fixed poses; central differences supply the Jacobian.
struct ShapeResidual : Eigen::DenseFunctor<double> {
  const body::BodyModel* model;
  const std::vector<const RowMatrixX3d*>* targets;
  const std::vector<PoseParameters>* poses;
  const std::vector<RowMatrixX3d>* correctives;   // B_P(θ_f), fixed with the poses
  const Eigen::VectorXd* scales;
  Eigen::Matrix3d world_from_body;
  ShapeResidual(const body::BodyModel& m, const std::vector<const RowMatrixX3d*>& y, const std::vector<PoseParameters>& p,
                const std::vector<RowMatrixX3d>& bp, const Eigen::VectorXd& s, const Eigen::Matrix3d& r)
      : DenseFunctor<double>(body::kNumBetas, static_cast<int>(3 * m.num_vertices() * static_cast<Eigen::Index>(y.size()))),
        model(&m), targets(&y), poses(&p), correctives(&bp), scales(&s), world_from_body(r) {}

  int operator()(const Eigen::VectorXd& beta, Eigen::VectorXd& r) const {
    const RowMatrixX3d shaped = body::shaped_template(*model, beta);
    const body::JointPositions joints = body::regress_joints(*model, shaped);
    const Eigen::Index n = model->num_vertices();
    r.resize(3 * n * static_cast<Eigen::Index>(targets->size()));
    for (std::size_t f = 0; f < targets->size(); ++f) {
      const PoseParameters& p = (*poses)[f];
      const body::Kinematics kin = body::forward_kinematics(*model, joints, pose_of(p), trans_of(p));
      const RowMatrixX3d v = body::linear_blend_skinning(*model, kin, shaped + (*correctives)[f]) * world_from_body.transpose();
      const RowMatrixX3d& y = *(*targets)[f];
      for (Eigen::Index i = 0; i < n; ++i)
        r.segment<3>(3 * (n * static_cast<Eigen::Index>(f) + i)) = (*scales)[i] * (v.row(i) - y.row(i)).transpose();
    }
    return r.allFinite() ? 0 : -1;
  }
};

template <typename Solver>
void configure(Solver& lm, const PoseFitOptions& options) {
  lm.setMaxfev(options.max_evaluations);
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

}  // namespace

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
  const PosedModel posed_model(model, shaped, joints, options.world_from_body);
  const Eigen::VectorXd scales = residual_scales(n, options);
  FrameResidual residual(posed_model, target, scales);
  Eigen::LevenbergMarquardt<FrameResidual> lm(residual);
  configure(lm, options);
  Eigen::VectorXd x = parameters;
  const Status status = lm.minimize(x);
  FrameFitReport report;
  report.iterations = static_cast<int>(lm.iterations());
  report.evaluations = static_cast<int>(lm.nfev());
  report.status = status_name(status);
  report.converged = converged(status);
  require(status != Eigen::LevenbergMarquardtSpace::UserAsked && x.allFinite(),
          "pose fit: the residual became non-finite (NaN/Inf) after {} evaluations", report.evaluations);
  parameters = x;
  const RowMatrixX3d v = posed_model.posed(parameters);
  std::vector<char> soft(static_cast<std::size_t>(n), 0);
  for (int s : options.soft_vertices) soft[static_cast<std::size_t>(s)] = 1;
  report.rms = rms_over(v, target, nullptr);
  report.rms_rigid = rms_over(v, target, &soft);
  return report;
}

namespace {

/// One LM solve for β with the poses of `frames` fixed; returns the new β.
body::Betas fit_shape(const body::BodyModel& model, const std::vector<RowMatrixX3d>& registered, const std::vector<int>& frames,
                      const std::vector<PoseParameters>& poses, const body::Betas& beta, const PoseFitOptions& options) {
  std::vector<const RowMatrixX3d*> targets;
  std::vector<RowMatrixX3d> correctives;
  for (std::size_t s = 0; s < frames.size(); ++s) {
    targets.push_back(&registered[static_cast<std::size_t>(frames[s])]);
    correctives.push_back(body::pose_correctives(model, pose_of(poses[s])));
  }
  const Eigen::VectorXd scales = residual_scales(model.num_vertices(), options);
  const ShapeResidual residual(model, targets, poses, correctives, scales, options.world_from_body);
  Eigen::NumericalDiff<ShapeResidual, Eigen::Central> differentiated(residual);
  Eigen::LevenbergMarquardt<Eigen::NumericalDiff<ShapeResidual, Eigen::Central>> lm(differentiated);
  configure(lm, options);
  Eigen::VectorXd x = beta;
  const Status status = lm.minimize(x);
  require(status != Eigen::LevenbergMarquardtSpace::UserAsked && x.allFinite(), "shape fit: the residual became non-finite (NaN/Inf)");
  if (!converged(status)) logger()->warn("shape fit: β did not converge ({})", status_name(status));
  return x;
}

}  // namespace

PoseFitResult fit_motion(const body::BodyModel& model, const std::vector<RowMatrixX3d>& registered, double fps,
                         const std::optional<body::Betas>& beta, const PoseFitOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  require(!registered.empty(), "pose fit: no frames");
  require(options.soft_weight >= 0.0 && options.soft_weight <= 1.0, "pose fit: soft_weight must be in [0, 1], got {}", options.soft_weight);
  require(options.max_evaluations > 0 && options.shape_frames > 0 && options.shape_rounds > 0, "pose fit: iteration limits must be positive");
  const Eigen::Index n = model.num_vertices();
  for (std::size_t t = 0; t < registered.size(); ++t) {
    require(registered[t].rows() == n, "pose fit: frame {} has {} vertices, the body has {}", t, registered[t].rows(), n);
    require(registered[t].allFinite(), "pose fit: frame {} has a non-finite vertex position", t);
  }
  const auto T = static_cast<int>(registered.size());
  const Eigen::VectorXd weights = residual_scales(n, options).array().square();

  PoseFitResult result;
  result.beta = beta.value_or(body::Betas::Zero());
  result.beta_fitted = !beta.has_value();

  if (result.beta_fitted) {
    // Shared β by alternation over evenly spaced frames (first and last included).
    const int k = std::min(options.shape_frames, T);
    std::vector<int> frames;
    for (int s = 0; s < k; ++s) frames.push_back(k == 1 ? 0 : static_cast<int>(std::lround(static_cast<double>(s) * (T - 1) / (k - 1))));
    frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
    std::vector<PoseParameters> poses(frames.size());
    for (int round = 0; round < options.shape_rounds; ++round) {
      const RowMatrixX3d shaped = body::shaped_template(model, result.beta);
      const body::JointPositions joints = body::regress_joints(model, shaped);
      for (std::size_t s = 0; s < frames.size(); ++s) {
        const RowMatrixX3d& y = registered[static_cast<std::size_t>(frames[s])];
        if (round == 0) poses[s] = rigid_initial_pose(shaped, joints.row(0).transpose(), y, weights, options.world_from_body);
        fit_frame(model, shaped, joints, y, options, poses[s]);
      }
      const body::Betas next = fit_shape(model, registered, frames, poses, result.beta, options);
      const double change = (next - result.beta).cwiseAbs().maxCoeff();
      result.beta = next;
      result.shape_rounds = round + 1;
      logger()->debug("shape fit round {}: max |Δβ| = {:.3g}", round + 1, change);
      if (change < options.shape_tolerance) break;
    }
  }

  const RowMatrixX3d shaped = body::shaped_template(model, result.beta);
  const body::JointPositions joints = body::regress_joints(model, shaped);
  result.motion.name = "fitted";
  result.motion.source = "pose fit";
  result.motion.fps = fps;
  result.motion.world_from_body = options.world_from_body;
  PoseParameters parameters = rigid_initial_pose(shaped, joints.row(0).transpose(), registered.front(), weights, options.world_from_body);
  Progress progress("pose fit", static_cast<std::size_t>(T), options.progress);
  for (int t = 0; t < T; ++t) {
    FrameFitReport report = fit_frame(model, shaped, joints, registered[static_cast<std::size_t>(t)], options, parameters);  // warm start
    report.frame = t;
    if (!report.converged) {
      ++result.unconverged_frames;
      logger()->warn("pose fit: frame {} did not converge ({}, {} evaluations, RMS {:.2f} mm)", t, report.status, report.evaluations,
                     1e3 * report.rms);
    }
    result.max_rms = std::max(result.max_rms, report.rms);
    result.mean_rms += report.rms / T;
    result.frames.push_back(report);
    result.motion.poses.push_back(pose_of(parameters));
    result.motion.trans.push_back(trans_of(parameters));
    progress.advance();
  }
  progress.finish();
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace sflsh::validate
