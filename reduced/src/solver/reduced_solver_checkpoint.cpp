// Saving and restoring the reduced solver's state at the start of a step (reduced_solver.hpp).
#include <sflsh/reduced/reduced_solver.hpp>

namespace sflsh::reduced {

ReducedSolver::Checkpoint ReducedSolver::checkpoint() const {
  Checkpoint c;
  c.t = t_;
  c.q = q_;
  c.rate = q_rate_;
  c.rate_previous = q_rate_previous_;
  c.rate_dt = rate_dt_;
  c.rate_steps = rate_steps_;
  c.history = history_;
  c.factor_valid = factor_valid_;
  if (factor_valid_) c.factor = factor_;
  c.factor_h = factor_h_;
  c.factor_projection = factor_projection_;
  return c;
}

void ReducedSolver::restore(const Checkpoint& c) {
  t_ = c.t;
  q_ = c.q;
  q_rate_ = c.rate;
  q_rate_previous_ = c.rate_previous;
  rate_dt_ = c.rate_dt;
  rate_steps_ = c.rate_steps;
  history_ = c.history;
  factor_valid_ = c.factor_valid;
  if (c.factor_valid) factor_ = c.factor;
  factor_h_ = c.factor_h;
  factor_projection_ = c.factor_projection;
  substeps_.clear();
}

}  // namespace sflsh::reduced
