#include "sweep_report.hpp"

#include <sflsh/core/atomic_file.hpp>

#include <fmt/format.h>

#include <algorithm>

namespace sflsh::app::sweep {

namespace {

std::vector<std::string> meshes_in_order(const std::vector<SweepRun>& runs) {
  std::vector<std::string> meshes;
  for (const SweepRun& r : runs)
    if (std::find(meshes.begin(), meshes.end(), r.mesh) == meshes.end()) meshes.push_back(r.mesh);
  return meshes;
}

/// A Markdown table cell: no line breaks, no column separators.
std::string md_cell(const std::string& text) {
  std::string out;
  for (char c : one_line(text)) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

}  // namespace

std::string one_line(const std::string& text) {
  std::string out = text;
  std::replace(out.begin(), out.end(), '\n', ' ');
  std::replace(out.begin(), out.end(), '\r', ' ');
  const auto first = out.find_first_not_of(" \t"), last = out.find_last_not_of(" \t");
  return first == std::string::npos ? std::string() : out.substr(first, last - first + 1);
}

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

void write_sweep_csv(const std::filesystem::path& path, const std::vector<SweepRun>& runs) {
  std::string text = std::string(kSweepHeader) + "\n";
  for (const SweepRun& r : runs) {
    // A failed run has no σ, iteration counts or solve time: those cells stay empty (its wall time is known).
    const std::string measured =
        r.ok ? fmt::format("{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{},{}", r.sigma_mm, r.newton_per_frame, r.seconds,
                           r.fps, r.sigma_max_mm, r.solve_seconds, r.failed_attempts, r.factorizations)
             : fmt::format(",,{:.6g},,,,,", r.seconds);
    const std::string sizes = r.coordinates > 0 ? fmt::format("{},{},{}", r.tets, r.coordinates, r.cubature_tets)
                                                : (r.tets > 0 ? fmt::format("{},,", r.tets) : std::string(",,"));
    text += fmt::format("{},{},{},{},{},{},{},{}\n", csv_field(r.mesh), csv_field(r.subject), csv_field(r.motion),
                        r.ok ? "ok" : "failed", csv_field(one_line(r.error)), r.frames, measured, sizes);
  }
  write_text_atomically(path, text);
}

nlohmann::json counts_per_mesh(const std::vector<SweepRun>& runs) {
  nlohmann::json counts = nlohmann::json::object();
  for (const std::string& mesh : meshes_in_order(runs)) {
    const auto total = std::count_if(runs.begin(), runs.end(), [&](const SweepRun& r) { return r.mesh == mesh; });
    const auto ok = std::count_if(runs.begin(), runs.end(), [&](const SweepRun& r) { return r.mesh == mesh && r.ok; });
    counts[mesh] = {{"runs", total}, {"ok", ok}, {"failures", total - ok}};
  }
  return counts;
}

nlohmann::json failures_json(const std::vector<SweepRun>& runs) {
  nlohmann::json failures = nlohmann::json::array();
  for (const SweepRun& r : runs)
    if (!r.ok)
      failures.push_back({{"mesh", r.mesh},
                          {"subject", r.subject},
                          {"motion", r.motion},
                          {"frames", r.frames},
                          {"error", one_line(r.error)}});
  return failures;
}

void write_sweep_markdown(const std::filesystem::path& path, const std::string& title,
                          const std::vector<std::string>& context, const std::vector<SweepRun>& runs) {
  std::string text = fmt::format("# {}\n\n", title);
  for (const std::string& line : context) text += fmt::format("- {}\n", line);
  text += "\n| mesh | runs | ok | failed |\n|---|---:|---:|---:|\n";
  const nlohmann::json counts = counts_per_mesh(runs);
  for (const auto& [mesh, c] : counts.items())
    text += fmt::format("| {} | {} | {} | {} |\n", mesh, c["runs"].get<long>(), c["ok"].get<long>(),
                        c["failures"].get<long>());

  text +=
      "\n| mesh | subject | motion | status | frames | mean σ [mm] | max σ [mm] | Newton/frame | retried attempts | "
      "cubature tets | run [s] | frames/s |\n|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const SweepRun& r : runs) {
    const std::string cubature = r.cubature_tets > 0 ? fmt::format("{}", r.cubature_tets) : std::string("–");
    if (r.ok)
      text += fmt::format("| {} | {} | {} | ok | {} | {:.3f} | {:.3f} | {:.2f} | {} | {} | {:.2f} | {:.1f} |\n", r.mesh,
                          r.subject, r.motion, r.frames, r.sigma_mm, r.sigma_max_mm, r.newton_per_frame,
                          r.failed_attempts, cubature, r.seconds, r.fps);
    else
      text += fmt::format("| {} | {} | {} | **failed** | {} of {} | – | – | – | – | {} | {:.2f} | – |\n", r.mesh,
                          r.subject, r.motion, r.frames, r.frames_requested, cubature, r.seconds);
  }
  const nlohmann::json failures = failures_json(runs);
  if (failures.empty()) {
    text += "\nNo run failed.\n";
  } else {
    text += fmt::format("\n## Failures ({})\n\n", failures.size());
    for (const auto& f : failures)
      text += fmt::format("- {} · {} · {} (after {} frames): {}\n", f["mesh"].get<std::string>(),
                          f["subject"].get<std::string>(), f["motion"].get<std::string>(), f["frames"].get<int>(),
                          md_cell(f["error"].get<std::string>()));
  }
  write_text_atomically(path, text);
}

}  // namespace sflsh::app::sweep
