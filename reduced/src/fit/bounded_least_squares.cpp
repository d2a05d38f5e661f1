#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/reduced/bounded_least_squares.hpp>

#include <petsctao.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace sflsh::reduced {

namespace {

/// The callbacks' shared state: the last residual and Jacobian and where they were computed.
struct Context {
  const LeastSquaresProblem* problem = nullptr;
  const LeastSquaresOptions* options = nullptr;
  Eigen::VectorXd r_at, r, J_at;
  NormalEquations J;
  bool have_r = false, have_J = false;
  int residual_evaluations = 0, jacobian_evaluations = 0;
  std::string error;                    ///< an exception from a callback, rethrown after TaoSolve returns
  std::vector<double> accepted_losses;  ///< the loss after every accepted iteration (and at the start)
  bool loss_test_met = false;
};

Eigen::VectorXd to_eigen(Vec v) {
  PetscInt n = 0;
  VecGetSize(v, &n);
  const PetscScalar* a = nullptr;
  VecGetArrayRead(v, &a);
  Eigen::VectorXd out = Eigen::Map<const Eigen::VectorXd>(a, n);
  VecRestoreArrayRead(v, &a);
  return out;
}

void from_eigen(const Eigen::VectorXd& x, Vec v) {
  PetscScalar* a = nullptr;
  VecGetArray(v, &a);
  Eigen::Map<Eigen::VectorXd>(a, x.size()) = x;
  VecRestoreArray(v, &a);
}

const Eigen::VectorXd& residual_at(Context& c, const Eigen::VectorXd& p) {
  if (!c.have_r || c.r_at.size() != p.size() || c.r_at != p) {
    c.r = c.problem->residual(p);
    ++c.residual_evaluations;
    require(c.r.allFinite(), "least squares: the residual has non-finite entries");
    c.r_at = p;
    c.have_r = true;
  }
  return c.r;
}

const NormalEquations& jacobian_at(Context& c, const Eigen::VectorXd& p) {
  const Eigen::VectorXd& r = residual_at(c, p);
  if (!c.have_J || c.J_at.size() != p.size() || c.J_at != p) {
    c.J = c.problem->normal_equations(p, r);
    ++c.jacobian_evaluations;
    require(c.J.JtJ.rows() == p.size() && c.J.JtJ.cols() == p.size() && c.J.Jtr.size() == p.size(),
            "least squares: normal equations are {}×{} and {}, expected {} parameters", c.J.JtJ.rows(), c.J.JtJ.cols(),
            c.J.Jtr.size(), p.size());
    require(c.J.JtJ.allFinite() && c.J.Jtr.allFinite(), "least squares: the Jacobian has non-finite entries");
    c.J_at = p;
    c.have_J = true;
  }
  return c.J;
}

template <typename F>
PetscErrorCode guarded(Context& c, F&& f) {
  try {
    f();
    return 0;
  } catch (const std::exception& e) {
    if (c.error.empty()) c.error = e.what();
    return PETSC_ERR_USER;
  }
}

PetscErrorCode objective(Tao, Vec x, PetscReal* f, void* ctx) {
  auto& c = *static_cast<Context*>(ctx);
  return guarded(c, [&] { *f = 0.5 * residual_at(c, to_eigen(x)).squaredNorm(); });
}

PetscErrorCode gradient(Tao, Vec x, Vec g, void* ctx) {
  auto& c = *static_cast<Context*>(ctx);
  return guarded(c, [&] { from_eigen(jacobian_at(c, to_eigen(x)).Jtr, g); });
}

PetscErrorCode hessian(Tao, Vec x, Mat H, Mat, void* ctx) {
  auto& c = *static_cast<Context*>(ctx);
  return guarded(c, [&] {
    Eigen::MatrixXd JtJ = jacobian_at(c, to_eigen(x)).JtJ;  // Gauss–Newton
    // A relative floor on the diagonal keeps the model well posed where a parameter does not (yet) act.
    const double floor = 1e-12 * std::max(JtJ.diagonal().maxCoeff(), 1e-300);
    JtJ.diagonal().array() += floor;
    PetscScalar* a = nullptr;
    MatDenseGetArray(H, &a);
    Eigen::Map<Eigen::MatrixXd>(a, JtJ.rows(), JtJ.cols()) = JtJ;  // column-major, as MATSEQDENSE
    MatDenseRestoreArray(H, &a);
    MatAssemblyBegin(H, MAT_FINAL_ASSEMBLY);
    MatAssemblyEnd(H, MAT_FINAL_ASSEMBLY);
  });
}

PetscErrorCode monitor(Tao tao, void* ctx) {
  auto& c = *static_cast<Context*>(ctx);
  if (!c.options->monitor) return 0;
  return guarded(c, [&] {
    PetscInt it = 0;
    PetscReal f = 0, gnorm = 0, cnorm = 0, xdiff = 0;
    TaoConvergedReason reason;
    TaoGetSolutionStatus(tao, &it, &f, &gnorm, &cnorm, &xdiff, &reason);
    Vec x;
    TaoGetSolution(tao, &x);
    c.options->monitor(static_cast<int>(it), to_eigen(x), f, gnorm);
  });
}

/// TAO's own tests (gradient tolerances, iteration cap), then the relative decrease of the loss over the last
/// `loss_window` accepted iterations (LeastSquaresOptions::loss_rtol).
PetscErrorCode convergence_test(Tao tao, void* ctx) {
  auto& c = *static_cast<Context*>(ctx);
  PetscCall(TaoDefaultConvergenceTest(tao, nullptr));
  TaoConvergedReason reason;
  PetscCall(TaoGetConvergedReason(tao, &reason));
  PetscInt it = 0;
  PetscReal f = 0, gnorm = 0, cnorm = 0, xdiff = 0;
  PetscCall(TaoGetSolutionStatus(tao, &it, &f, &gnorm, &cnorm, &xdiff, nullptr));
  std::vector<double>& losses = c.accepted_losses;
  if (losses.empty() || f < losses.back()) losses.push_back(f);
  if (reason != TAO_CONTINUE_ITERATING || c.options->loss_rtol <= 0.0) return 0;
  const auto window = static_cast<std::size_t>(std::max(1, c.options->loss_window));
  if (losses.size() > window && losses[losses.size() - 1 - window] - f <= c.options->loss_rtol * std::abs(f)) {
    c.loss_test_met = true;
    PetscCall(TaoSetConvergedReason(tao, TAO_CONVERGED_USER));
  }
  return 0;
}

/// The name of the test that ended the solve (LeastSquaresResult::stopped_by).
std::string stopping_test(TaoConvergedReason reason, bool loss_test_met) {
  if (reason == TAO_CONVERGED_USER && loss_test_met) return "loss_decrease";
  if (reason == TAO_CONVERGED_GATOL || reason == TAO_CONVERGED_GRTOL || reason == TAO_CONVERGED_GTTOL)
    return "projected_gradient";
  if (reason == TAO_DIVERGED_TR_REDUCTION || reason == TAO_CONVERGED_STEPTOL) return "trust_radius";
  if (reason == TAO_DIVERGED_MAXITS) return "iteration_cap";
  if (reason == TAO_DIVERGED_LS_FAILURE) return "line_search";
  return TaoConvergedReasons[reason];
}

#define SFLSH_TAO(call)                                                                                   \
  do {                                                                                                    \
    const PetscErrorCode sflsh_tao_error = (call);                                                        \
    if (sflsh_tao_error) {                                                                                \
      if (!context.error.empty()) throw Error(context.error);                                             \
      throw_error("least squares: {} failed (PETSc error {})", #call, static_cast<int>(sflsh_tao_error)); \
    }                                                                                                     \
  } while (0)

}  // namespace

LeastSquaresResult solve_bounded_least_squares(const LeastSquaresProblem& problem, const Eigen::VectorXd& start,
                                               const LeastSquaresOptions& options) {
  const auto n = start.size();
  require(n > 0 && problem.lower.size() == n && problem.upper.size() == n,
          "least squares: {} parameters with {} lower and {} upper bounds", n, problem.lower.size(),
          problem.upper.size());
  require(problem.residual && problem.normal_equations, "least squares: residual and Jacobian callbacks are required");
  require((problem.lower.array() <= problem.upper.array()).all(),
          "least squares: a lower bound exceeds its upper bound");
  require(start.allFinite(), "least squares: the start has non-finite entries");
  const Eigen::VectorXd x0 = start.cwiseMax(problem.lower).cwiseMin(problem.upper);
  if ((x0 - start).lpNorm<Eigen::Infinity>() > 1e-12)
    logger()->debug("least squares: start projected onto the bounds (moved {:.3g})",
                    (x0 - start).lpNorm<Eigen::Infinity>());

  Context context;
  context.problem = &problem;
  context.options = &options;
  Tao tao = nullptr;
  Vec x = nullptr, lo = nullptr, hi = nullptr;
  Mat H = nullptr;
  struct Cleanup {
    Tao* tao;
    Vec* x;
    Vec* lo;
    Vec* hi;
    Mat* H;
    ~Cleanup() {
      if (*tao) TaoDestroy(tao);
      if (*x) VecDestroy(x);
      if (*lo) VecDestroy(lo);
      if (*hi) VecDestroy(hi);
      if (*H) MatDestroy(H);
    }
  } cleanup{&tao, &x, &lo, &hi, &H};

  const auto N = static_cast<PetscInt>(n);
  SFLSH_TAO(VecCreateSeq(PETSC_COMM_SELF, N, &x));
  SFLSH_TAO(VecDuplicate(x, &lo));
  SFLSH_TAO(VecDuplicate(x, &hi));
  from_eigen(x0, x);
  from_eigen(problem.lower, lo);
  from_eigen(problem.upper, hi);
  SFLSH_TAO(MatCreateSeqDense(PETSC_COMM_SELF, N, N, nullptr, &H));
  SFLSH_TAO(TaoCreate(PETSC_COMM_SELF, &tao));
  SFLSH_TAO(TaoSetType(tao, TAOBNTR));
  SFLSH_TAO(TaoSetOptionsPrefix(tao, "fit_"));
  SFLSH_TAO(TaoSetSolution(tao, x));
  SFLSH_TAO(TaoSetVariableBounds(tao, lo, hi));
  SFLSH_TAO(TaoSetObjective(tao, objective, &context));
  SFLSH_TAO(TaoSetGradient(tao, nullptr, gradient, &context));
  SFLSH_TAO(TaoSetHessian(tao, H, H, hessian, &context));
  SFLSH_TAO(TaoSetMaximumIterations(tao, options.max_iterations));
  SFLSH_TAO(TaoSetTolerances(tao, options.gradient_atol, options.gradient_rtol, options.gradient_ttol));
  if (options.initial_radius > 0.0) SFLSH_TAO(TaoSetInitialTrustRegionRadius(tao, options.initial_radius));
  SFLSH_TAO(TaoSetMonitor(tao, monitor, &context, nullptr));
  SFLSH_TAO(TaoSetConvergenceTest(tao, convergence_test, &context));
  SFLSH_TAO(TaoSetFromOptions(tao));  // -fit_tao_* options override
  // A callback's exception comes back as a PETSc error code; keep PETSc from printing a traceback for it.
  PetscPushErrorHandler(PetscReturnErrorHandler, nullptr);
  const PetscErrorCode solved = TaoSolve(tao);
  PetscPopErrorHandler();
  if (!context.error.empty()) throw Error(context.error);
  require(solved == 0, "least squares: TAO failed (PETSc error {})", static_cast<int>(solved));

  LeastSquaresResult result;
  TaoConvergedReason reason;
  PetscInt it = 0;
  PetscReal f = 0, gnorm = 0, cnorm = 0, xdiff = 0;
  SFLSH_TAO(TaoGetSolutionStatus(tao, &it, &f, &gnorm, &cnorm, &xdiff, &reason));
  Vec solution;
  SFLSH_TAO(TaoGetSolution(tao, &solution));
  result.p = to_eigen(solution);
  result.residual = residual_at(context, result.p);
  result.loss = 0.5 * result.residual.squaredNorm();
  result.gradient_norm = gnorm;
  result.iterations = static_cast<int>(it);
  result.reason = TaoConvergedReasons[reason];
  result.stopped_by = stopping_test(reason, context.loss_test_met);
  result.converged = reason > 0 || reason == TAO_DIVERGED_TR_REDUCTION;
  result.residual_evaluations = context.residual_evaluations;
  result.jacobian_evaluations = context.jacobian_evaluations;
  require(reason > 0 || reason == TAO_DIVERGED_MAXITS || reason == TAO_DIVERGED_TR_REDUCTION ||
              reason == TAO_DIVERGED_LS_FAILURE,
          "least squares: TAO failed ({})", result.reason);
  return result;
}

}  // namespace sflsh::reduced
