#include "compare_report.hpp"

#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/chart.hpp>
#include <sflsh/core/error.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <iterator>

namespace sflsh::app::compare {

namespace {

/// Index of `value` among the distinct values of `all` in ascending order.
std::size_t rank_of(std::vector<int> all, int value) {
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  return static_cast<std::size_t>(std::lower_bound(all.begin(), all.end(), value) - all.begin());
}

}  // namespace

std::string config_suffix(int handles, int cubature) { return fmt::format("h{}_k{}", handles, cubature); }

void write_tradeoff_csv(const std::filesystem::path& path, const std::vector<TradeoffRow>& rows) {
  std::string text = std::string(kTradeoffHeader) + "\n";
  for (const TradeoffRow& r : rows) {
    const std::string sizes = r.reduced ? fmt::format("{},{},{}", r.handles, r.cubature, r.coordinates) : ",,";
    text += fmt::format("{},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g}\n",
                        r.reduced ? "reduced" : "full", sizes, r.seconds_per_frame, r.frames_per_second,
                        r.sigma_mean_mm, r.recovered_fraction, r.rms_error_mm, r.relative_rms_error,
                        r.sigma_correlation, r.trajectory_rms_mm, r.trajectory_max_mm);
  }
  write_text_atomically(path, text);
}

void write_tradeoff_markdown(const std::filesystem::path& path, const std::string& title,
                             const std::vector<std::string>& context, const std::vector<TradeoffRow>& rows,
                             const std::vector<ReducedTimings>& timings) {
  std::string text = fmt::format("# {}\n\n", title);
  for (const std::string& line : context) text += fmt::format("- {}\n", line);
  text +=
      "\n| model | handles | cubature | coordinates | s/frame | frames/s | mean σ [mm] | recovered | RMS error [mm] | "
      "relative RMS error | σ correlation | trajectory RMS [mm] | trajectory max [mm] |\n"
      "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const TradeoffRow& r : rows) {
    const std::string sizes =
        r.reduced ? fmt::format("{} | {} | {}", r.handles, r.cubature, r.coordinates) : std::string("– | – | –");
    text +=
        fmt::format("| {} | {} | {:.4g} | {:.4g} | {:.3f} | {:.0f}% | {:.3f} | {:.3f}{} | {:.3f} | {:.3f} | {:.3f} |\n",
                    r.reduced ? "reduced" : "full", sizes, r.seconds_per_frame, r.frames_per_second, r.sigma_mean_mm,
                    100.0 * r.recovered_fraction, r.rms_error_mm, r.relative_rms_error, r.valid ? "" : " (*)",
                    r.sigma_correlation, r.trajectory_rms_mm, r.trajectory_max_mm);
  }
  if (std::any_of(rows.begin(), rows.end(), [](const TradeoffRow& r) { return !r.valid; }))
    text +=
        "\n(*) the reduced state left the material's range in tets outside the cubature (summary.json: out_of_range): "
        "too few cubature tets for the subspace.\n";
  if (!timings.empty()) {
    text +=
        "\nReduced model, per frame: cubature elastic terms, inertia terms, dense Cholesky solves, Newton "
        "iterations.\n\n"
        "| handles | cubature | elastic [ms] | inertia [ms] | solve [ms] | Newton |\n|---:|---:|---:|---:|---:|---:|\n";
    for (const ReducedTimings& t : timings)
      text += fmt::format("| {} | {} | {:.3f} | {:.3f} | {:.3f} | {:.2f} |\n", t.handles, t.cubature,
                          1e3 * t.elastic_seconds_per_frame, 1e3 * t.inertia_seconds_per_frame,
                          1e3 * t.solve_seconds_per_frame, t.newton_per_frame);
  }
  write_text_atomically(path, text);
}

void write_tradeoff_png(const std::filesystem::path& path, const std::string& title,
                        const std::vector<TradeoffRow>& rows) {
  chart::Chart c;
  c.title = title;
  c.x_label = "seconds per frame";
  c.y_label = "relative RMS error of the displacement";
  c.log_x = c.log_y = true;
  c.width = 1000;
  c.height = 650;
  std::vector<int> handles, cubatures;
  for (const TradeoffRow& r : rows)
    if (r.reduced) {
      handles.push_back(r.handles);
      cubatures.push_back(r.cubature);
    }
  // Colour by handle count, marker by cubature size: each configuration is its own legend entry.
  const chart::Marker markers[] = {chart::Marker::circle, chart::Marker::square, chart::Marker::diamond,
                                   chart::Marker::cross, chart::Marker::plus};
  double y_lo = 0.0, y_hi = 0.0;
  for (const TradeoffRow& r : rows) {
    if (!r.reduced) continue;
    require(r.seconds_per_frame > 0.0 && r.relative_rms_error > 0.0,
            "plot: configuration {} has no positive time and error", config_suffix(r.handles, r.cubature));
    chart::Series s;
    s.label = fmt::format("{} handles, {} cubature tets{}", r.handles, r.cubature, r.valid ? "" : " (out of range)");
    s.x = {r.seconds_per_frame};
    s.y = {r.relative_rms_error};
    s.color = chart::palette(rank_of(handles, r.handles));
    s.marker = markers[rank_of(cubatures, r.cubature) % std::size(markers)];
    s.marker_size = 12.0f;
    y_lo = y_lo == 0.0 ? r.relative_rms_error : std::min(y_lo, r.relative_rms_error);
    y_hi = std::max(y_hi, r.relative_rms_error);
    c.series.push_back(std::move(s));
  }
  require(!c.series.empty(), "plot: no reduced configuration to draw");
  for (const TradeoffRow& r : rows) {
    if (r.reduced || r.seconds_per_frame <= 0.0) continue;
    // The reference has no error: its cost is a vertical line.
    c.series.push_back(chart::vertical_line(fmt::format("full space (reference): {:.3g} s/frame", r.seconds_per_frame),
                                            r.seconds_per_frame, 0.7 * y_lo, 1.4 * y_hi, {60, 60, 60}));
  }
  chart::write_chart_png(path, c);
}

}  // namespace sflsh::app::compare
