#pragma once
// Run folders: every command that writes one also writes summary.json describing what it did.
#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <string>

namespace sflsh {

/// Writes `value` as indented JSON to `path` atomically.
void write_json(const std::filesystem::path& path, const nlohmann::json& value);

/// Reads a JSON file; errors name the file and the parse position.
nlohmann::json read_json(const std::filesystem::path& path);

/// The common header of summary.json: tool version, command line, start time (UTC, ISO 8601).
nlohmann::json summary_header(const std::string& command, int argc, const char* const* argv);

class RunFolder;

/// The older names of a summary's run time, written beside timings.total_seconds with the same value. Each is kept
/// as an alias for one release (docs/output.md, "summary.json"); new summaries name the run time only
/// timings.total_seconds.
struct SummaryAliases {
  bool wall_time_s = false;      ///< top-level `wall_time_s` (motion export, material curve, material show, shapefit)
  bool seconds = false;          ///< top-level `seconds` (verify, validate, groundtruth)
  bool timings_s_total = false;  ///< `timings_s.total` (mesh)
  bool timings_wall_seconds = false;  ///< `timings.wall_seconds` (sweep)
};

/// Sets summary.json's run time [s] under its one name, timings.total_seconds, keeping the other entries of
/// "timings" (and of "timings_s"), and under the older names `aliases` asks for.
void set_total_seconds(nlohmann::json& summary, double seconds, SummaryAliases aliases = {});

/// Writes a run folder's summary: sets the run time (set_total_seconds) in `summary` and stages it as summary.json,
/// which appears with the run's other files at run.commit(). Every command's summary.json is written here; the
/// caller keeps the completed summary (the one written).
void write_summary(RunFolder& run, nlohmann::json& summary, double total_seconds, SummaryAliases aliases = {});

/// The project version string (from CMake).
std::string version();

}  // namespace sflsh
