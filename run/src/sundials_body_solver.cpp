// The SUNDIALS reference as a body solver (sundials_body_solver.hpp).
#include <sflsh/run/sundials_body_solver.hpp>

#include <cmath>

namespace sflsh::run {

SundialsBodySolver::SundialsBodySolver(const model::Problem& problem, const fullspace::ReferenceOptions& options,
                                       const model::State& initial, double step_rate)
    : options_(options), integrator_(problem, options), state_(initial), step_rate_(step_rate) {
  integrator_.initialize(initial);
}

model::StepStats SundialsBodySolver::step(double h) {
  const fullspace::ReferenceStats before = integrator_.stats();
  double t_end = state_.t + h;
  if (step_rate_ > 0.0) t_end = std::round(t_end * step_rate_) / step_rate_;
  state_ = integrator_.advance_to(t_end);
  const fullspace::ReferenceStats& after = integrator_.stats();
  model::StepStats st;
  st.newton_iterations = static_cast<int>(after.nonlin_iters - before.nonlin_iters);
  st.factorizations = static_cast<int>(after.lin_setups - before.lin_setups);
  st.failed_attempts =
      static_cast<int>(after.error_test_fails - before.error_test_fails + after.conv_fails - before.conv_fails);
  st.substeps = static_cast<int>(after.steps - before.steps);
  st.seconds = after.seconds - before.seconds;
  st.converged_reason = "arkode";
  return st;
}

}  // namespace sflsh::run
