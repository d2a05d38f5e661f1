#pragma once
// The outputs of `sflsh compare` that do not depend on the solvers: the trade-off table (CSV, Markdown),
// the error-against-time chart, and the names of the per-configuration fields of compare.vtp.
#include <filesystem>
#include <string>
#include <vector>

namespace sflsh::app::compare {

/// One line of tradeoff.csv: the full-space reference or one reduced configuration.
struct TradeoffRow {
  bool reduced = false;
  int handles = 0;      ///< point handles (reduced)
  int cubature = 0;     ///< cubature tets requested (reduced; every tet for exact cubature)
  int coordinates = 0;  ///< reduced coordinates 3S
  double seconds_per_frame = 0.0;
  double frames_per_second = 0.0;
  double sigma_mean_mm = 0.0;       ///< mean σ over the region's vertices
  double recovered_fraction = 0.0;  ///< mean σ / mean σ_full
  double rms_error_mm = 0.0;        ///< RMS of |u − u_full| over region vertices and frames
  double relative_rms_error = 0.0;  ///< rms_error / RMS of u_full
  bool valid = true;                ///< every full-space tet stayed within the material's range
  double sigma_correlation = 0.0;   ///< Pearson correlation of σ and σ_full over the region's vertices
  double trajectory_rms_mm = 0.0;   ///< RMS of |p − p_full| (posed body surface) over region vertices and frames 1..F
  double trajectory_max_mm = 0.0;   ///< largest |p − p_full| over region vertices and frames 1..F
};

/// The exact CSV header of tradeoff.csv.
inline constexpr const char* kTradeoffHeader =
    "model,handles,cubature,coordinates,seconds_per_frame,frames_per_second,sigma_mean_mm,recovered_fraction,"
    "rms_error_mm,relative_rms_error,sigma_correlation,trajectory_rms_mm,trajectory_max_mm";

/// "h<H>_k<K>": the suffix of a configuration's field names (K: cubature tets used).
std::string config_suffix(int handles, int cubature);

void write_tradeoff_csv(const std::filesystem::path& path, const std::vector<TradeoffRow>& rows);

/// Extra per-frame timings of a reduced configuration for the Markdown report.
struct ReducedTimings {
  int handles = 0, cubature = 0;
  double elastic_seconds_per_frame = 0.0, inertia_seconds_per_frame = 0.0, solve_seconds_per_frame = 0.0;
  double newton_per_frame = 0.0;
};

/// tradeoff.md: a title line, `context` lines (subject, motion, …), the trade-off table and the reduced
/// timing breakdown.
void write_tradeoff_markdown(const std::filesystem::path& path, const std::string& title,
                             const std::vector<std::string>& context, const std::vector<TradeoffRow>& rows,
                             const std::vector<ReducedTimings>& timings);

/// tradeoff.png: relative RMS error against seconds per frame (log–log), one labelled point per reduced
/// configuration and the full-space time as a dashed vertical line. Throws sflsh::Error without a display.
void write_tradeoff_png(const std::filesystem::path& path, const std::string& title,
                        const std::vector<TradeoffRow>& rows);

}  // namespace sflsh::app::compare
