#include <sflsh/core/error.hpp>
#include <sflsh/model/frame_loop.hpp>

#include <cmath>

namespace sflsh::model {

void accumulate(StepStats& total, const StepStats& step) {
  total.newton_iterations += step.newton_iterations;
  total.linear_iterations += step.linear_iterations;
  total.factorizations += step.factorizations;
  total.substeps = step.substeps;
  total.failed_attempts += step.failed_attempts;
  total.projected_retries += step.projected_retries;
  total.fallback_preconditioner += step.fallback_preconditioner;
  total.preconditioner_builds += step.preconditioner_builds;
  total.truncated_solves += step.truncated_solves;
  total.potential_refinements += step.potential_refinements;
  total.startup_steps += step.startup_steps;
  total.cubature_added += step.cubature_added;
  total.seconds += step.seconds;
  total.function_seconds += step.function_seconds;
  total.jacobian_seconds += step.jacobian_seconds;
  total.elastic_seconds += step.elastic_seconds;
  total.inertia_seconds += step.inertia_seconds;
  total.solve_seconds += step.solve_seconds;
  total.potential_seconds += step.potential_seconds;
  total.final_gradient = step.final_gradient;
  total.converged_reason = step.converged_reason;
}

StepStats run_frames(BodySolver& solver, const FrameLoopOptions& options,
                     const std::function<void(int frame, double t, const StepStats& stats)>& on_frame) {
  const bool fixed_step = options.step != 0.0;
  require(fixed_step || (options.fps > 0.0 && std::isfinite(options.fps)), "frame loop: fps must be positive, got {}",
          options.fps);
  require(!fixed_step || (options.step > 0.0 && std::isfinite(options.step)),
          "frame loop: the fixed step must be positive, got {} s", options.step);
  require(options.substeps >= 1, "frame loop: substeps must be ≥ 1, got {}", options.substeps);
  require(options.first_frame >= 1, "frame loop: the first frame solved is ≥ 1, got {}", options.first_frame);
  const double h = fixed_step ? options.step : 1.0 / (options.fps * options.substeps);
  StepStats total;
  for (int f = options.first_frame; f < options.frames; ++f) {
    StepStats frame;
    for (int k = 0; k < options.substeps; ++k) accumulate(frame, solver.step(h));
    accumulate(total, frame);
    if (on_frame) on_frame(f, fixed_step ? f * options.substeps * h : f / options.fps, frame);
  }
  return total;
}

}  // namespace sflsh::model
