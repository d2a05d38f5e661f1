// Damped Gauss–Newton for one frame's pose (pose_gauss_newton.hpp).
#include "pose_gauss_newton.hpp"

#include <sflsh/core/error.hpp>

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>

namespace sflsh::validate::detail {

namespace {

constexpr int kTheta = 3 * body::kNumJoints;
using Hessian = Eigen::Matrix<double, kNumPoseParameters, kNumPoseParameters>;

double prior_cost(const GaussNewtonSettings& s, const PoseParameters& x) {
  return s.prior_weight > 0.0 ? s.prior_weight * (x.head<kTheta>() - s.prediction).squaredNorm() : 0.0;
}

}  // namespace

GaussNewtonReport solve_pose_gauss_newton(const PosedModel& model, const RowMatrixX3d& target,
                                          const std::vector<int>& rows, const Eigen::VectorXd& weights,
                                          const GaussNewtonSettings& settings, PoseParameters& x) {
  GaussNewtonReport report;
  Hessian hessian;
  PoseParameters gradient;
  double mu = 0.0;  // Levenberg damping, 0 (pure Gauss–Newton) while steps succeed
  double data_cost = model.normal_equations(x, rows, weights, target, hessian, gradient);
  ++report.evaluations;
  report.status = "too many evaluations";
  while (report.evaluations < settings.max_evaluations) {
    require(std::isfinite(data_cost), "pose fit: the residual became non-finite (NaN/Inf) after {} evaluations",
            report.evaluations);
    if (data_cost <= settings.absolute_cost) {
      report.converged = true;
      report.status = "residual below the absolute tolerance";
      break;
    }
    const double cost = data_cost + prior_cost(settings, x);
    // (H + λ_θ P + μ diag) δ = −(g + λ_θ (θ − θ_pred)), P the projection on θ.
    Hessian system = hessian;
    PoseParameters rhs = -gradient;
    if (settings.prior_weight > 0.0) {
      system.diagonal().head<kTheta>().array() += settings.prior_weight;
      rhs.head<kTheta>() -= settings.prior_weight * (x.head<kTheta>() - settings.prediction);
    }
    // A joint no fit vertex moves with has an all-zero block: a tiny ridge keeps the system definite there.
    const double scale = std::max(system.diagonal().maxCoeff(), 1e-300);
    system.diagonal().array() += 1e-12 * scale;
    Hessian damped = system;
    damped.diagonal() += mu * system.diagonal();
    const PoseParameters step = damped.ldlt().solve(rhs);
    require(step.allFinite(), "pose fit: the Gauss–Newton step is not finite after {} evaluations", report.evaluations);
    const PoseParameters trial = x + step;
    const double trial_cost = model.rows_cost(trial, rows, weights, target) + prior_cost(settings, trial);
    ++report.evaluations;
    if (std::isfinite(trial_cost) && trial_cost <= cost) {
      ++report.iterations;
      x = trial;
      mu = mu > 0.0 ? std::max(mu / 10.0, 1e-9) : 0.0;
      const bool small_step = step.norm() <= settings.tolerance * (x.norm() + settings.tolerance);
      const bool small_reduction = cost - trial_cost <= settings.tolerance * cost;
      if (small_step || small_reduction) {
        report.converged = true;
        report.status = small_step ? "relative step below tolerance" : "relative reduction below tolerance";
        break;
      }
      if (report.evaluations >= settings.max_evaluations) break;
      data_cost = model.normal_equations(x, rows, weights, target, hessian, gradient);
      ++report.evaluations;
    } else {
      mu = mu > 0.0 ? 10.0 * mu : 1e-4;
      if (mu > 1e8) {  // no descent even for a tiny gradient step: at the minimum to round-off
        report.converged = true;
        report.status = "no further reduction possible";
        break;
      }
    }
  }
  return report;
}

}  // namespace sflsh::validate::detail
