#pragma once
// The one frame loop of every body simulation (simulate, compare, tradeoff, ground truth, the fit and its
// sensitivities, verify): frames 1 … F−1 of a motion at `fps`, each as `substeps` solver steps, the step statistics
// summed per frame, and a callback per finished frame (which writes, measures or records what its command needs).
// A run of a problem's own fixed step (verify, the sensitivity runs) passes `step` instead of fps. Scenes step all
// their bodies together per frame (scene/src/runner/scene_runner.cpp) with the same body solvers.
#include <sflsh/model/problem.hpp>
#include <sflsh/model/step_stats.hpp>

#include <functional>

namespace sflsh::model {

/// A body solver as the frame loop sees it (the full-space solver and the reduced model).
class BodySolver {
 public:
  virtual ~BodySolver() = default;
  /// Advances by h [s] through the robustness ladder (step_ladder.hpp); throws sflsh::Error when it fails.
  virtual StepStats step(double h) = 0;
  /// The current full-space state (x, w at every node).
  virtual State current_state() const = 0;
  /// The unposed elastic positions x alone (3N) [m]: what σ and the skin's output need; solvers that can give them
  /// without the velocities and the motion's node maps of current_state() override it.
  virtual Eigen::VectorXd positions() const { return current_state().x; }
};

/// Adds the counts and timings of `step` into `total` (substeps and the reason: the last step's).
void accumulate(StepStats& total, const StepStats& step);

struct FrameLoopOptions {
  int frames = 0;       ///< frames of the motion, frame 0 included (the loop solves frames 1 … frames − 1)
  double fps = 60.0;    ///< [1/s]
  int substeps = 1;     ///< solver steps per frame
  int first_frame = 1;  ///< resume from here (the solver holds frame first_frame − 1)
  /// A fixed solver step h [s] instead of 1/(fps · substeps) (fps is then unused); frame f ends at f · substeps · h.
  double step = 0.0;
};

/// Runs the frames; `on_frame(frame, t, stats)` after each (t [s] = frame / fps, or frame · substeps · step; stats
/// summed over its steps).
/// Returns the statistics summed over every frame.
StepStats run_frames(BodySolver& solver, const FrameLoopOptions& options,
                     const std::function<void(int frame, double t, const StepStats& stats)>& on_frame);

}  // namespace sflsh::model
