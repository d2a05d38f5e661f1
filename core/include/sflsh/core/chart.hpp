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

/// A distinguishable colour for index i (cycles through 8).
std::array<unsigned char, 3> palette(std::size_t i);

/// Draws the chart and writes it atomically as PNG. Throws sflsh::Error without an X display, for an empty
/// chart, series of unequal length or a non-positive value on a log axis.
void write_chart_png(const std::filesystem::path& path, const Chart& chart);

}  // namespace sflsh::chart
