#pragma once
// Small 2-D charts (points and lines, optional log axes) written as PNG with VTK's charts (vtkChartXY in an
// offscreen vtkContextView), the approach of the material curves plot. Debian's VTK renders through X: on a
// machine without a display a virtual one is started (virtual_display.hpp); when that is impossible
// write_chart_png throws sflsh::Error, so callers treat the picture as optional.
//
// Link note: the implementation needs VTK's ChartsCore, ViewsContext2D, RenderingContext2D and
// RenderingContextOpenGL2 modules, which sflsh::core does not link itself; a target that calls it must link
// them (the sflsh executable gets them through sflsh::material).
#include <array>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace sflsh::chart {

enum class Marker { none, cross, plus, square, circle, diamond };
enum class Line { none, solid, dashed };

struct Series {
  std::string label;         ///< legend entry (empty: not in the legend)
  std::vector<double> x, y;  ///< same length
  Marker marker = Marker::circle;
  Line line = Line::none;
  std::array<unsigned char, 3> color = {40, 90, 200};
  float marker_size = 10.0f;
  float line_width = 2.0f;
};

struct Chart {
  std::string title;
  std::string x_label, y_label;
  bool log_x = false, log_y = false;  ///< every value on a log axis must be positive
  int width = 900, height = 600;
  std::vector<Series> series;
};

/// A dashed vertical line at x from y_lo to y_hi without markers: a value without a y, such as a reference's cost on
/// an error–time chart.
inline Series vertical_line(std::string label, double x, double y_lo, double y_hi, std::array<unsigned char, 3> color) {
  Series s;
  s.label = std::move(label);
  s.x = {x, x};
  s.y = {y_lo, y_hi};
  s.line = Line::dashed;
  s.marker = Marker::none;
  s.color = color;
  return s;
}

/// A distinguishable colour for index i (cycles through 8).
std::array<unsigned char, 3> palette(std::size_t i);

/// Draws the chart and writes it atomically as PNG. Throws sflsh::Error without an X display, for an empty
/// chart, series of unequal length or a non-positive value on a log axis.
void write_chart_png(const std::filesystem::path& path, const Chart& chart);

}  // namespace sflsh::chart
