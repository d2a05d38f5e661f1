#pragma once
// Bound-constrained nonlinear least squares  min ½‖r(p)‖²  s.t.  lower ≤ p ≤ upper  (SFLSH §5: the fit's
// loss r_fitᵀr_fit + r_regᵀr_reg, eqs. 6–7), solved by PETSc TAO's bounded Newton trust-region method
// (TAOBNTR, the counterpart of the trust-region-reflective solver the paper used) on the Gauss–Newton
// model: gradient Jᵀr, Hessian JᵀJ. The caller returns residuals and the normal-equation terms JᵀJ, Jᵀr
// (J itself can be far too large to store: rows = every vertex of every case); both are cached per
// point, so a rejected trial costs residuals only, never a Jacobian.
// TAO runs on PETSC_COMM_SELF: under MPI every rank drives an identical copy of the (small) solve while
// the callbacks share the expensive simulations among ranks; their results are identical on every rank.
#include <Eigen/Core>

#include <functional>
#include <string>

namespace sflsh::reduced {

/// JᵀJ (P × P) and Jᵀr (P) of J = ∂r/∂p.
struct NormalEquations {
  Eigen::MatrixXd JtJ;
  Eigen::VectorXd Jtr;
};

struct LeastSquaresProblem {
  std::function<Eigen::VectorXd(const Eigen::VectorXd& p)> residual;
  /// The normal-equation terms at p, given r(p).
  std::function<NormalEquations(const Eigen::VectorXd& p, const Eigen::VectorXd& r)> normal_equations;
  Eigen::VectorXd lower, upper;
};

struct LeastSquaresOptions {
  int max_iterations = 20;
  double gradient_atol = 1e-8;  ///< stop when ‖proj. gradient‖ ≤ atol
  double gradient_rtol = 1e-6;  ///< … or ≤ rtol · loss
  double gradient_ttol = 1e-4;  ///< … or ≤ ttol · initial ‖gradient‖
  /// Stop (converged) when `loss_window` accepted iterations together lower the loss by ≤ loss_rtol · loss
  /// (0: off). Rejected trial steps, which leave the loss where it was, do not count as iterations here.
  double loss_rtol = 0.0;
  int loss_window = 2;
  double initial_radius = 0.0;  ///< 0: TAO's default
  /// Called after every accepted iteration (and at iteration 0) with the current point and loss ½‖r‖².
  std::function<void(int iteration, const Eigen::VectorXd& p, double loss, double gradient_norm)> monitor;
};

struct LeastSquaresResult {
  Eigen::VectorXd p;
  Eigen::VectorXd residual;  ///< r(p), from the solver's cache (no extra evaluation when p was accepted)
  double loss = 0.0;         ///< ½‖r(p)‖²
  double gradient_norm = 0.0;
  int iterations = 0;
  int residual_evaluations = 0;
  int jacobian_evaluations = 0;
  std::string reason;  ///< TAO's converged reason
  /// The test that ended the solve: "loss_decrease", "projected_gradient", "trust_radius" (TAO could not find a
  /// decreasing step above its radius floor: a minimum to the model's resolution), "iteration_cap" (the safety
  /// net, not convergence) or "line_search".
  std::string stopped_by;
  bool converged = false;  ///< a convergence test was met (loss decrease, projected gradient or trust radius)
};

/// Throws sflsh::Error on inconsistent sizes, a start outside the bounds (it is projected first, with a
/// warning, when it is only slightly outside), non-finite residuals or Jacobians, or a TAO failure.
LeastSquaresResult solve_bounded_least_squares(const LeastSquaresProblem& problem, const Eigen::VectorXd& start,
                                               const LeastSquaresOptions& options = {});

}  // namespace sflsh::reduced
