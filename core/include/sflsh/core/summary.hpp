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

/// Sets summary.json's run time [s] under its one name, timings.total_seconds (docs/output.md), keeping the other
/// entries of "timings". `legacy_wall_time_key` also writes `wall_time_s`, the name the summaries of `motion export`,
/// `material`, `material show` and `shapefit` used for it, kept as an alias for one release.
void set_total_seconds(nlohmann::json& summary, double seconds, bool legacy_wall_time_key = false);

/// The project version string (from CMake).
std::string version();

}  // namespace sflsh
