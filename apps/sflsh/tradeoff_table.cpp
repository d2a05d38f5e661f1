#include "tradeoff_table.hpp"

#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/chart.hpp>
#include <sflsh/core/error.hpp>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace sflsh::app::tradeoff {

namespace {

bool is_reference(const Row& r) { return r.model == "reference"; }

std::string step_text(const Row& r) {
  if (r.substeps == 0) return "adaptive";
  const double per_second = 1.0 / r.step;
  return std::abs(per_second - std::round(per_second)) < 1e-6 ? fmt::format("1/{:.0f} s", per_second)
                                                              : fmt::format("{:.4g} s", r.step);
}

}  // namespace

std::string Row::label() const {
  const std::string scheme =
      integrator == "backward_euler" && mass == "lumped" ? std::string() : fmt::format("{} {} ", integrator, mass);
  if (model == "reference")
    return substeps ? fmt::format("reference {} {} {}{}", integrator, mesh, mass == "lumped" ? "" : mass + " ",
                                  step_text(*this))
                    : fmt::format("reference {} {}{}", integrator, mesh, mass == "lumped" ? "" : " " + mass);
  if (model == "reduced")
    return fmt::format("reduced {} h{} k{} {}{}", mesh, handles, cubature, scheme, step_text(*this));
  return fmt::format("full {} {}{}", mesh, scheme, step_text(*this));
}

void mark_pareto_front(std::vector<Row>& rows) {
  for (Row& a : rows) {
    a.pareto = a.valid && std::isfinite(a.rms_error_mm);
    if (!a.pareto) continue;
    for (const Row& b : rows) {
      if (&a == &b || !b.valid || !std::isfinite(b.rms_error_mm)) continue;
      const bool no_worse = b.seconds_per_frame <= a.seconds_per_frame && b.rms_error_mm <= a.rms_error_mm;
      const bool better = b.seconds_per_frame < a.seconds_per_frame || b.rms_error_mm < a.rms_error_mm;
      if (no_worse && better) {
        a.pareto = false;
        break;
      }
    }
  }
}

bool Budget::admits(const Row& row) const {
  if (!row.valid || !std::isfinite(row.rms_error_mm)) return false;
  if (mm && !(row.rms_error_mm <= *mm)) return false;
  if (relative && !(row.relative_error <= *relative)) return false;
  return given();
}

std::string Budget::text() const {
  std::vector<std::string> parts;
  if (mm) parts.push_back(fmt::format("RMS error ≤ {:g} mm", *mm));
  if (relative) parts.push_back(fmt::format("relative error ≤ {:g}", *relative));
  return parts.empty() ? "no budget" : fmt::format("{}", fmt::join(parts, " and "));
}

std::optional<std::size_t> recommend(const std::vector<Row>& rows, const Budget& budget) {
  std::optional<std::size_t> pick;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (is_reference(rows[i]) || !budget.admits(rows[i])) continue;
    if (!pick || rows[i].seconds_per_frame < rows[*pick].seconds_per_frame) pick = i;
  }
  return pick;
}

std::string recommendation_text(const std::vector<Row>& rows, const Budget& budget,
                                const std::optional<std::size_t>& pick) {
  if (!budget.given()) return "No error budget given (--budget-mm X and/or --budget-relative R): no recommendation.";
  if (pick) {
    const Row& r = rows[*pick];
    return fmt::format(
        "Recommended for {}: {} — {:.4g} s per frame, RMS error {:.3g} mm (relative {:.3g}), σ ratio {:.3g}.",
        budget.text(), r.label(), r.seconds_per_frame, r.rms_error_mm, r.relative_error, r.sigma_ratio);
  }
  std::optional<std::size_t> best;
  for (std::size_t i = 0; i < rows.size(); ++i)
    if (!is_reference(rows[i]) && rows[i].valid && std::isfinite(rows[i].rms_error_mm) &&
        (!best || rows[i].rms_error_mm < rows[*best].rms_error_mm))
      best = i;
  if (!best)
    return fmt::format("No tested configuration meets {}: none ran within the material's range.", budget.text());
  return fmt::format(
      "No tested configuration meets {}; the most accurate is {} with RMS error {:.3g} mm (relative {:.3g}).",
      budget.text(), rows[*best].label(), rows[*best].rms_error_mm, rows[*best].relative_error);
}

void write_csv(const std::filesystem::path& path, const std::vector<Row>& rows) {
  std::string text = std::string(kHeader) + "\n";
  for (const Row& r : rows) {
    const std::string sizes = r.model == "reduced" ? fmt::format("{},{}", r.handles, r.cubature) : ",";
    const std::string step = r.substeps ? fmt::format("{},{:.6g}", r.substeps, r.step) : ",";
    text += fmt::format("{},{},{},{},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{},{},{}\n", r.model, r.integrator, r.mesh,
                        sizes, step, r.setup_seconds, r.seconds_per_frame, r.rms_error_mm, r.relative_error,
                        r.sigma_ratio, r.valid ? "yes" : "no", r.pareto ? "yes" : "no", r.mass);
  }
  write_text_atomically(path, text);
}

void write_markdown(const std::filesystem::path& path, const std::string& title,
                    const std::vector<std::string>& context, const std::vector<Row>& rows,
                    const std::string& recommendation) {
  std::string text = fmt::format("# {}\n\n", title);
  for (const std::string& line : context) text += fmt::format("- {}\n", line);
  text +=
      "\n| model | integrator | mass | mesh | handles | cubature | step | setup [s] | s/frame | RMS error [mm] | "
      "relative error | "
      "σ ratio | Pareto |\n|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|\n";
  for (const Row& r : rows) {
    const std::string sizes =
        r.model == "reduced" ? fmt::format("{} | {}", r.handles, r.cubature) : std::string("– | –");
    text += fmt::format("| {} | {} | {} | {} | {} | {} | {:.3g} | {:.4g} | {:.4f} | {:.4f} | {:.3f} | {}{} |\n",
                        r.model, r.integrator, r.mass, r.mesh, sizes, step_text(r), r.setup_seconds,
                        r.seconds_per_frame, r.rms_error_mm, r.relative_error, r.sigma_ratio, r.pareto ? "yes" : "no",
                        r.valid ? "" : " (out of range)");
  }
  text += fmt::format("\n**{}**\n", recommendation);
  write_text_atomically(path, text);
}

void write_png(const std::filesystem::path& path, const std::string& title, const std::vector<Row>& rows) {
  chart::Chart c;
  c.title = title;
  c.x_label = "seconds per frame (solve)";
  c.y_label = "RMS error of the posed region surface [mm]";
  c.log_x = c.log_y = true;
  c.width = 1100;
  c.height = 700;
  const chart::Marker markers[] = {chart::Marker::circle, chart::Marker::square, chart::Marker::diamond};  // by mesh
  auto mesh_index = [](const std::string& mesh) { return mesh == "coarse" ? 0u : mesh == "default" ? 1u : 2u; };
  double y_lo = 0.0, y_hi = 0.0;
  std::vector<std::size_t> front;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    if (is_reference(r) || !(r.seconds_per_frame > 0.0) || !(r.rms_error_mm > 0.0) || !std::isfinite(r.rms_error_mm))
      continue;
    chart::Series s;
    s.label = r.label() + (r.valid ? "" : " (out of range)");
    s.x = {r.seconds_per_frame};
    s.y = {r.rms_error_mm};
    s.color = chart::palette(c.series.size());
    s.marker = r.model == "reduced" ? markers[mesh_index(r.mesh)] : chart::Marker::cross;
    s.marker_size = 12.0f;
    y_lo = y_lo == 0.0 ? r.rms_error_mm : std::min(y_lo, r.rms_error_mm);
    y_hi = std::max(y_hi, r.rms_error_mm);
    c.series.push_back(std::move(s));
    if (r.pareto) front.push_back(i);
  }
  require(!c.series.empty(), "plot: no tested configuration with a positive time and error");
  if (front.size() >= 2) {
    std::sort(front.begin(), front.end(),
              [&](std::size_t a, std::size_t b) { return rows[a].seconds_per_frame < rows[b].seconds_per_frame; });
    chart::Series s;
    s.label = "Pareto front";
    for (std::size_t i : front) {
      s.x.push_back(rows[i].seconds_per_frame);
      s.y.push_back(rows[i].rms_error_mm);
    }
    s.line = chart::Line::solid;
    s.marker = chart::Marker::none;
    s.color = {30, 30, 30};
    c.series.push_back(std::move(s));
  }
  for (const Row& r : rows) {
    if (!is_reference(r) || !(r.seconds_per_frame > 0.0)) continue;
    // The reference has no error: its cost is a vertical line.
    c.series.push_back(chart::vertical_line(fmt::format("{}: {:.3g} s/frame", r.label(), r.seconds_per_frame),
                                            r.seconds_per_frame, 0.7 * y_lo, 1.4 * y_hi, {90, 90, 90}));
  }
  chart::write_chart_png(path, c);
}

}  // namespace sflsh::app::tradeoff
