#pragma once
// The SUNDIALS reference (fullspace/reference_integrator.hpp) as a model::BodySolver: step(h) integrates to
// t + h with ARKODE's own adaptive steps, so the error-controlled reference runs through the same frame loop as
// the stepping solvers. Its step statistics report ARKODE's Newton iterations and wall time of that interval.
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/model/frame_loop.hpp>

namespace sflsh::run {

class SundialsBodySolver final : public model::BodySolver {
 public:
  /// The problem must outlive the solver (ReferenceIntegrator's rules); starts at `initial`. `step_rate` > 0 [1/s]
  /// (the frame loop's fps × substeps) snaps the end of every step to the grid k / step_rate, so that a run of steps
  /// ends exactly at the motion's frame times k / fps instead of at a sum of rounded steps.
  SundialsBodySolver(const model::Problem& problem, const fullspace::ReferenceOptions& options,
                     const model::State& initial, double step_rate = 0.0);
  /// Integrates from time() to time() + h [s]; throws sflsh::Error when ARKODE gives up.
  model::StepStats step(double h) override;
  model::State current_state() const override { return state_; }
  Eigen::VectorXd positions() const override { return state_.x; }
  double time() const { return state_.t; }
  const fullspace::ReferenceStats& stats() const { return integrator_.stats(); }
  const fullspace::ReferenceOptions& options() const { return options_; }

 private:
  fullspace::ReferenceOptions options_;
  fullspace::ReferenceIntegrator integrator_;
  model::State state_;
  double step_rate_ = 0.0;
};

}  // namespace sflsh::run
