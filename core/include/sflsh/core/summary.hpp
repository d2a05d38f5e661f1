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

/// The project version string (from CMake).
std::string version();

}  // namespace sflsh
