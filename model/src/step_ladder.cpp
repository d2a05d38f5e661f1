#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/model/step_ladder.hpp>

#include <chrono>
#include <cmath>
#include <vector>

namespace sflsh::model {

StepStats step_with_ladder(LadderSolver& solver, double h, const LadderOptions& options, std::string_view name) {
  require(std::isfinite(h) && h > 0.0, "{}: step must be positive, got {}", name, h);
  require(options.max_halvings >= 0, "{}: max_halvings must be ≥ 0", name);
  const auto start = std::chrono::steady_clock::now();
  StepStats stats;
  const double t0 = solver.time();
  solver.save();
  struct Rung {
    int halvings;
    material::HessianProjection hessian;
  };
  const material::HessianProjection projected = options.projection;
  std::vector<Rung> rungs;
  if (options.exact_hessian_first) rungs.push_back({0, material::HessianProjection::kNone});
  for (int k = 0; k <= options.max_halvings; ++k) rungs.push_back({k, projected});

  std::string reason;
  for (std::size_t r = 0; r < rungs.size(); ++r) {
    const int substeps = 1 << rungs[r].halvings;
    const int startup_before = stats.startup_steps;  // counted for the accepted rung only
    bool ok = true;
    for (int k = 0; k < substeps && ok; ++k) {
      // Substep ends land exactly on t0 + h at the last one.
      const double t_end = k + 1 == substeps ? t0 + h : t0 + (k + 1) * (h / substeps);
      ok = solver.attempt(t_end - solver.time(), rungs[r].hessian, stats, reason);
    }
    if (ok) {
      stats.substeps = substeps;
      stats.converged_reason = reason;
      stats.seconds = seconds_since(start);
      if (stats.failed_attempts > 0)
        logger()->debug("{}: t = {:.6g} s recovered with {} substep(s) after {} failed attempt(s)", name, t0 + h,
                        substeps, stats.failed_attempts);
      return stats;
    }
    solver.restore();
    stats.startup_steps = startup_before;
    if (rungs[r].hessian == material::HessianProjection::kNone) {
      ++stats.projected_retries;
    } else {
      ++stats.failed_attempts;
    }
    logger()->debug("{}: step from t = {:.6g} s failed as {} substep(s): {}", name, t0, substeps, reason);
  }
  throw_error(
      "{} failed at t = {:.6g} s (the step from t = {:.6f} s): no convergence even with {} substeps of {:.3g} s ({})",
      name, t0 + h, t0, 1 << options.max_halvings, h / (1 << options.max_halvings), reason);
}

}  // namespace sflsh::model
