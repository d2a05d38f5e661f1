#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/summary.hpp>

#include <ctime>
#include <fstream>

#ifndef SFLSH_VERSION
#define SFLSH_VERSION "0.0.0"
#endif

namespace sflsh {

void write_json(const std::filesystem::path& path, const nlohmann::json& value) {
  write_text_atomically(path, value.dump(2) + "\n");
}

nlohmann::json read_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  require(static_cast<bool>(in), "{}: cannot open", path.string());
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw_error("{}: invalid JSON at byte {}: {}", path.string(), e.byte, e.what());
  }
}

void set_total_seconds(nlohmann::json& summary, double seconds, SummaryAliases aliases) {
  summary["timings"]["total_seconds"] = seconds;
  if (aliases.wall_time_s) summary["wall_time_s"] = seconds;
  if (aliases.seconds) summary["seconds"] = seconds;
  if (aliases.timings_s_total) summary["timings_s"]["total"] = seconds;
  if (aliases.timings_wall_seconds) summary["timings"]["wall_seconds"] = seconds;
}

void write_summary(RunFolder& run, nlohmann::json& summary, double total_seconds, SummaryAliases aliases) {
  set_total_seconds(summary, total_seconds, aliases);
  write_json(run.stage("summary.json"), summary);
}

nlohmann::json summary_header(const std::string& command, int argc, const char* const* argv) {
  nlohmann::json header;
  header["tool"] = "sflsh";
  header["version"] = version();
  header["command"] = command;
  std::vector<std::string> args;
  for (int i = 0; i < argc; ++i) args.emplace_back(argv[i]);
  header["argv"] = args;
  const std::time_t now = std::time(nullptr);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  header["started_utc"] = buffer;
  return header;
}

std::string version() { return SFLSH_VERSION; }

}  // namespace sflsh
