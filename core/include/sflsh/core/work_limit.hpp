#pragma once
// A run's size estimated before it starts, and the limits above which it is refused unless the user
// asks for it (--allow-long): a mistyped duration, step or crowd count must not silently schedule years of
// work or exhaust memory. docs/scenes.md ("Input limits") gives the limits and why.
#include <string>
#include <string_view>

namespace sflsh {

/// What a run will do, counted before it starts.
struct WorkEstimate {
  double steps = 0.0;        ///< solver (or integrator) steps, summed over bodies, substeps included
  double bodies = 0.0;       ///< bodies built (layers meshed, models reduced)
  double body_frames = 0.0;  ///< output frames × bodies (posed, measured, maybe written)
  double bytes = 0.0;        ///< memory that grows with the request (per-frame and per-step records) [B]
};

/// The largest run started without --allow-long.
struct WorkLimits {
  double steps = 1e6;
  double bodies = 100.0;
  double body_frames = 1e6;
  double bytes = 4.0 * 1024.0 * 1024.0 * 1024.0;
};

/// "1.2e+11 steps, 1 body, 2 body-frames, 2.1 GB" — the estimate in one phrase.
std::string describe(const WorkEstimate& estimate);

/// Throws sflsh::Error unless every quantity of `estimate` is within `limits` (or `allow_long`): one line
/// "<where>: <quantity> exceeds the limit <limit> (estimate: …); pass --allow-long to run it anyway".
/// `where` names the file and the fields that set the size, e.g. "p.toml: time.duration / time.step".
void check_work(const WorkEstimate& estimate, const WorkLimits& limits, bool allow_long, std::string_view where);

}  // namespace sflsh
