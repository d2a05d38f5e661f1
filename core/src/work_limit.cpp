// Work estimates and their limits (work_limit.hpp).
#include <sflsh/core/error.hpp>
#include <sflsh/core/work_limit.hpp>

#include <cmath>

namespace sflsh {

namespace {

std::string bytes_text(double bytes) {
  if (bytes >= 1e9) return fmt::format("{:.3g} GB", bytes / 1e9);
  if (bytes >= 1e6) return fmt::format("{:.3g} MB", bytes / 1e6);
  return fmt::format("{:.3g} kB", bytes / 1e3);
}

}  // namespace

std::string describe(const WorkEstimate& e) {
  return fmt::format("{:.3g} steps, {:.3g} bod{}, {:.3g} body-frames, {} of per-frame data", e.steps, e.bodies,
                     e.bodies == 1.0 ? "y" : "ies", e.body_frames, bytes_text(e.bytes));
}

void check_work(const WorkEstimate& e, const WorkLimits& limits, bool allow_long, std::string_view where) {
  if (allow_long) return;
  auto check = [&](double value, double limit, std::string_view quantity, const std::string& shown) {
    // NaN or infinite counts (an overflowing product) are above every limit.
    if (std::isfinite(value) && value <= limit) return;
    throw_error("{}: {} {} exceed the limit of {} (estimate: {}); pass --allow-long to run it anyway", where, shown,
                quantity, quantity == "of memory" ? bytes_text(limit) : fmt::format("{:.3g}", limit), describe(e));
  };
  check(e.bodies, limits.bodies, "bodies", fmt::format("{:.3g}", e.bodies));
  check(e.steps, limits.steps, "solver steps", fmt::format("{:.3g}", e.steps));
  check(e.body_frames, limits.body_frames, "body-frames", fmt::format("{:.3g}", e.body_frames));
  check(e.bytes, limits.bytes, "of memory", bytes_text(e.bytes));
}

}  // namespace sflsh
