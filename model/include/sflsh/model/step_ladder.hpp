#pragma once
// The one robustness ladder of every solver (docs/integrators.md): a step of length h is tried as
//   1. one substep with the exact elastic Hessian (when the solver asks for it: dynamic steps),
//   2. one substep with dP/dF projected to PSD,
//   3. 2, 4, … 2^max_halvings substeps with the projected Hessian,
// and when even the last fails the state is restored and one sflsh::Error names the time, the solver and the
// reason of the last failure. Between rungs the solver's state is restored to the start of the step, so a
// step never leaves a half-updated state.
#include <sflsh/material/psd_projection.hpp>
#include <sflsh/model/step_stats.hpp>

#include <string>
#include <string_view>

namespace sflsh::model {

/// What a solver gives the ladder.
class LadderSolver {
 public:
  virtual ~LadderSolver() = default;
  /// The time at the start of the step [s].
  virtual double time() const = 0;
  /// Remembers the whole state (with the integrator's history), and puts it back.
  virtual void save() = 0;
  virtual void restore() = 0;
  /// One substep from the current state over dt with this Hessian; true when converged (the state then
  /// holds t + dt). On false, `reason` says why; the state is restored by the ladder.
  virtual bool attempt(double dt, material::HessianProjection hessian, StepStats& stats, std::string& reason) = 0;
};

struct LadderOptions {
  bool exact_hessian_first = true;  ///< rung 1 (skipped for quasi-static problems by the solvers)
  /// The Hessian of rungs 2–3 (kNone keeps the exact one: the ladder then only halves).
  material::HessianProjection projection = material::HessianProjection::kStressDerivative;
  int max_halvings = 6;
};

/// Advances `solver` by h through the ladder; fills stats.substeps, failed_attempts, projected_retries,
/// seconds and converged_reason. Throws sflsh::Error "<name> failed at t = … s: …" (state restored).
StepStats step_with_ladder(LadderSolver& solver, double h, const LadderOptions& options, std::string_view name);

}  // namespace sflsh::model
