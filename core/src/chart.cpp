#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/chart.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/virtual_display.hpp>
#include <sflsh/core/window_png.hpp>

#include <fmt/format.h>
#include <vtkAutoInit.h>
#include <vtkAxis.h>
#include <vtkChartLegend.h>
#include <vtkChartXY.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPen.h>
#include <vtkPlot.h>
#include <vtkPlotPoints.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkTable.h>
#include <vtkTextProperty.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

// The OpenGL device of the 2-D context: sflsh::core's VTK module set does not include it, so it is
// registered here, where it is used.
VTK_MODULE_INIT(vtkRenderingContextOpenGL2);

namespace sflsh::chart {

namespace {

int marker_style(Marker m) {
  switch (m) {
    case Marker::none:
      return vtkPlotPoints::NONE;
    case Marker::cross:
      return vtkPlotPoints::CROSS;
    case Marker::plus:
      return vtkPlotPoints::PLUS;
    case Marker::square:
      return vtkPlotPoints::SQUARE;
    case Marker::circle:
      return vtkPlotPoints::CIRCLE;
    case Marker::diamond:
      return vtkPlotPoints::DIAMOND;
  }
  return vtkPlotPoints::CIRCLE;
}

vtkSmartPointer<vtkTable> table_of(const Series& s, std::size_t index) {
  auto table = vtkSmartPointer<vtkTable>::New();
  vtkNew<vtkDoubleArray> x;
  x->SetName(fmt::format("x{}", index).c_str());
  vtkNew<vtkDoubleArray> y;
  y->SetName(s.label.empty() ? fmt::format("y{}", index).c_str() : s.label.c_str());
  table->AddColumn(x);
  table->AddColumn(y);
  table->SetNumberOfRows(static_cast<vtkIdType>(s.x.size()));
  for (std::size_t i = 0; i < s.x.size(); ++i) {
    table->SetValue(static_cast<vtkIdType>(i), 0, s.x[i]);
    table->SetValue(static_cast<vtkIdType>(i), 1, s.y[i]);
  }
  return table;
}

/// Axis range with a margin: a fraction of the span (linear) or of the decades (log).
void set_range(vtkAxis* axis, double lo, double hi, bool log) {
  if (log) {
    const double a = std::log10(lo), b = std::log10(hi);
    const double pad = std::max(0.08 * (b - a), 0.15);
    axis->SetUnscaledRange(std::pow(10.0, a - pad), std::pow(10.0, b + pad));
  } else {
    const double pad = hi > lo ? 0.08 * (hi - lo) : std::max(std::abs(lo) * 0.1, 1.0);
    axis->SetUnscaledRange(lo - pad, hi + pad);
  }
  axis->SetBehavior(vtkAxis::FIXED);
}

}  // namespace

std::array<unsigned char, 3> palette(std::size_t i) {
  static const std::array<std::array<unsigned char, 3>, 8> colors = {{{200, 60, 40},
                                                                      {40, 90, 200},
                                                                      {40, 150, 60},
                                                                      {150, 60, 170},
                                                                      {230, 140, 20},
                                                                      {20, 160, 170},
                                                                      {120, 90, 50},
                                                                      {90, 90, 90}}};
  return colors[i % colors.size()];
}

void write_chart_png(const std::filesystem::path& path, const Chart& chart) {
  require_display("plot");  // $DISPLAY, or a virtual display started for this process
  require(!chart.series.empty(), "plot: no series to draw");
  double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo, y_lo = x_lo, y_hi = -x_lo;
  for (const Series& s : chart.series) {
    require(s.x.size() == s.y.size() && !s.x.empty(), "plot: series '{}' has {} x and {} y values", s.label, s.x.size(),
            s.y.size());
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      require(std::isfinite(s.x[i]) && std::isfinite(s.y[i]), "plot: series '{}' has a non-finite value", s.label);
      require(!chart.log_x || s.x[i] > 0.0, "plot: series '{}' has x = {} on a log axis", s.label, s.x[i]);
      require(!chart.log_y || s.y[i] > 0.0, "plot: series '{}' has y = {} on a log axis", s.label, s.y[i]);
      x_lo = std::min(x_lo, s.x[i]);
      x_hi = std::max(x_hi, s.x[i]);
      y_lo = std::min(y_lo, s.y[i]);
      y_hi = std::max(y_hi, s.y[i]);
    }
  }

  vtkNew<vtkContextView> view;
  view->GetRenderer()->SetBackground(1.0, 1.0, 1.0);
  view->GetRenderWindow()->SetOffScreenRendering(1);
  view->GetRenderWindow()->SetSize(chart.width, chart.height);
  vtkNew<vtkChartXY> xy;
  view->GetScene()->AddItem(xy);
  xy->SetTitle(chart.title);
  xy->GetTitleProperties()->SetFontSize(16);
  xy->SetShowLegend(true);
  xy->GetLegend()->SetHorizontalAlignment(vtkChartLegend::RIGHT);
  xy->GetLegend()->SetVerticalAlignment(vtkChartLegend::TOP);
  vtkAxis* bottom = xy->GetAxis(vtkAxis::BOTTOM);
  vtkAxis* left = xy->GetAxis(vtkAxis::LEFT);
  bottom->SetTitle(chart.x_label);
  left->SetTitle(chart.y_label);
  bottom->SetLogScale(chart.log_x);
  left->SetLogScale(chart.log_y);
  set_range(bottom, x_lo, x_hi, chart.log_x);
  set_range(left, y_lo, y_hi, chart.log_y);

  std::vector<vtkSmartPointer<vtkTable>> tables;  // the plots reference their tables until rendering
  for (std::size_t k = 0; k < chart.series.size(); ++k) {
    const Series& s = chart.series[k];
    tables.push_back(table_of(s, k));
    vtkPlot* plot = xy->AddPlot(s.line == Line::none ? vtkChart::POINTS : vtkChart::LINE);
    plot->SetInputData(tables.back(), 0, 1);
    plot->SetColor(s.color[0], s.color[1], s.color[2], 255);
    plot->SetWidth(s.line == Line::none ? 1.5f : s.line_width);
    if (s.line == Line::dashed) plot->GetPen()->SetLineType(vtkPen::DASH_LINE);
    plot->SetLabel(s.label);
    if (s.label.empty()) plot->SetLegendVisibility(false);
    if (auto* points = vtkPlotPoints::SafeDownCast(plot)) {
      points->SetMarkerStyle(marker_style(s.marker));
      points->SetMarkerSize(s.marker_size);
    }
  }

  view->Render();
  write_window_png(*view->GetRenderWindow(), path);
}

}  // namespace sflsh::chart
