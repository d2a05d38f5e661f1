#pragma once
// Names and the convergence reading of Eigen's Levenberg–Marquardt stopping reasons.
#include <unsupported/Eigen/LevenbergMarquardt>

#include <string>

namespace sflsh::validate::detail {

inline std::string lm_status_name(Eigen::LevenbergMarquardtSpace::Status s) {
  using namespace Eigen::LevenbergMarquardtSpace;
  switch (s) {
    case RelativeReductionTooSmall:
      return "relative reduction below tolerance";
    case RelativeErrorTooSmall:
      return "relative step below tolerance";
    case RelativeErrorAndReductionTooSmall:
      return "relative step and reduction below tolerance";
    case CosinusTooSmall:
      return "residual orthogonal to the Jacobian";
    case TooManyFunctionEvaluation:
      return "too many evaluations";
    case FtolTooSmall:
      return "no further reduction possible";
    case XtolTooSmall:
      return "no further step possible";
    case GtolTooSmall:
      return "gradient vanished";
    case UserAsked:
      return "non-finite residual";
    case ImproperInputParameters:
      return "improper input";
    default:
      return "not run";
  }
}

/// Every stop but running out of evaluations, a non-finite residual or bad input is convergence (the
/// "too small" tolerances mean no further progress is possible at machine precision).
inline bool lm_converged(Eigen::LevenbergMarquardtSpace::Status s) {
  using namespace Eigen::LevenbergMarquardtSpace;
  return s != TooManyFunctionEvaluation && s != UserAsked && s != ImproperInputParameters && s != NotStarted &&
         s != Running;
}

/// Runs `lm` like LevenbergMarquardt::minimize, and also stops as converged once ‖r‖ ≤ `absolute_norm`:
/// on exact (noise-free) data MINPACK's relative tests see only round-off near the zero-residual minimum and
/// would shrink the trust region for dozens of iterations before the step test fires.
struct LmOutcome {
  Eigen::LevenbergMarquardtSpace::Status status = Eigen::LevenbergMarquardtSpace::NotStarted;
  bool absolute = false;  ///< stopped by the absolute residual test
  bool converged() const { return absolute || lm_converged(status); }
  std::string name() const { return absolute ? "residual below the absolute tolerance" : lm_status_name(status); }
};

template <typename Solver, typename Vector>
LmOutcome minimize_until(Solver& lm, Vector& x, double absolute_norm) {
  using namespace Eigen::LevenbergMarquardtSpace;
  LmOutcome out;
  out.status = lm.minimizeInit(x);
  if (out.status == ImproperInputParameters) return out;
  out.status = Running;
  while (out.status == Running) {
    if (lm.fnorm() <= absolute_norm) {
      out.absolute = true;
      break;
    }
    out.status = lm.minimizeOneStep(x);
  }
  return out;
}

}  // namespace sflsh::validate::detail
