// The reduced solver on the model's robustness ladder (model/step_ladder.hpp, reduced_solver.hpp): the whole state
// saved at a step's start and put back before the step is tried again with a projected Hessian or smaller
// substeps, coupled systems included. The substep itself is in reduced_solver.cpp.
#include <sflsh/core/error.hpp>
#include <sflsh/model/step_ladder.hpp>
#include <sflsh/reduced/reduced_solver.hpp>

namespace sflsh::reduced {

/// One substep per attempt from the current state; the ladder saves and restores the whole state, the posed
/// history and the recorded substeps included. A substep advances the history only when it converges, so a failed
/// single-substep rung leaves it as saved: the history (several vectors per inertia node) is copied only before the
/// first substep of a split rung, not on every step.
class ReducedSolver::Ladder final : public model::LadderSolver {
 public:
  Ladder(ReducedSolver& solver, double h) : solver_(solver), h_(h) {}
  double time() const override { return solver_.t_; }
  void save() override {
    solver_.save_state(saved_, false);
    history_saved_ = false;
    solver_.substeps_.clear();
    if (solver_.options_.coupled) solver_.options_.coupled->save();
  }
  void restore() override {
    solver_.restore_state(saved_, history_saved_);
    if (solver_.options_.coupled) solver_.options_.coupled->restore();
  }
  bool attempt(double dt, material::HessianProjection hessian, model::StepStats& stats, std::string& reason) override {
    if (!history_saved_ && solver_.t_ == saved_.t && dt < 0.75 * h_) {  // the first substep of a split rung
      saved_.history = solver_.history_;
      saved_.carried_history = solver_.carried_history_;
      history_saved_ = true;
    }
    int startup = 0;
    const bool ok = solver_.solve_substep(solver_.t_, dt, hessian, stats, reason, startup);
    stats.startup_steps += startup;
    return ok;
  }

 private:
  ReducedSolver& solver_;
  double h_;
  StepState saved_;
  bool history_saved_ = false;
};

model::StepStats ReducedSolver::step(double h) {
  require(h > 0.0 && std::isfinite(h), "reduced: step must be positive, got {}", h);
  require(history_.p.size() == 3 * static_cast<Eigen::Index>(inertia_.inertia_nodes().size()),
          "reduced: the solver has no state; call initialize() before step()");
  model::LadderOptions ladder_options;
  ladder_options.exact_hessian_first = options_.exact_hessian_first && !options_.quasi_static;
  ladder_options.projection = problem_.projection == material::HessianProjection::kNone
                                  ? material::HessianProjection::kStressDerivative
                                  : problem_.projection;
  ladder_options.max_halvings = options_.max_halvings;
  Ladder ladder(*this, h);
  return model::step_with_ladder(ladder, h, ladder_options, "reduced model");
}

}  // namespace sflsh::reduced
