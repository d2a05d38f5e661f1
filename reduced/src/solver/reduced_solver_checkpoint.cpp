// Saving and restoring the reduced solver's state at the start of a step (reduced_solver.hpp): one StepState for the
// robustness ladder and the scene's checkpoints.
#include <sflsh/reduced/reduced_solver.hpp>

namespace sflsh::reduced {

void ReducedSolver::save_state(StepState& s, bool with_histories) const {
  s.t = t_;
  s.q = q_;
  s.rate = q_rate_;
  s.rate_previous = q_rate_previous_;
  s.rate_dt = rate_dt_;
  s.rate_steps = rate_steps_;
  s.deviation = deviation_;
  s.pose = pose_;
  if (with_histories) {
    s.history = history_;
    s.carried_history = carried_history_;
  }
}

void ReducedSolver::restore_state(const StepState& s, bool with_histories) {
  t_ = s.t;
  q_ = s.q;
  q_rate_ = s.rate;
  q_rate_previous_ = s.rate_previous;
  rate_dt_ = s.rate_dt;
  rate_steps_ = s.rate_steps;
  deviation_ = s.deviation;
  pose_ = s.pose;
  if (with_histories) {
    history_ = s.history;
    carried_history_ = s.carried_history;
  }
  substeps_.clear();
}

ReducedSolver::Checkpoint ReducedSolver::checkpoint() const {
  Checkpoint c;
  save_state(c.state, true);
  c.factor_valid = factor_valid_;
  if (factor_valid_) c.factor = factor_;
  c.factor_h = factor_h_;
  c.factor_projection = factor_projection_;
  return c;
}

void ReducedSolver::restore(const Checkpoint& c) {
  restore_state(c.state, true);
  factor_valid_ = c.factor_valid;
  if (c.factor_valid) factor_ = c.factor;
  factor_h_ = c.factor_h;
  factor_projection_ = c.factor_projection;
}

}  // namespace sflsh::reduced
