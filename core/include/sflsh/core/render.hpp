#pragma once
// Offscreen pictures of triangle surfaces with VTK (PNG). Debian's VTK renders through X; on a machine
// without a display a virtual one is started (virtual_display.hpp).
#include <sflsh/core/vtk_io.hpp>

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace sflsh::render {

struct Surface {
  vtk::Points points;
  vtk::Cells triangles;
  std::optional<Eigen::VectorXd> scalars;  ///< per-point values to colour by (else a skin tone)
  std::array<double, 3> color = {0.87, 0.72, 0.62};
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< translation applied when drawing (for line-ups)
  bool framed = true;  ///< strips: the camera frames this surface (false: drawn, but may be cut off, e.g. a floor)
};

/// One panel of a strip: its surfaces and the caption under it.
struct Panel {
  std::vector<Surface> surfaces;
  std::string caption;
};

struct View {
  std::string name = "front";  ///< front (+Z toward the camera), side (from +X), back, three_quarter, top
  int width = 800;
  int height = 1000;
  std::string title;  ///< drawn across the top when not empty (lines separated by '\n')
  std::optional<std::pair<double, double>> scalar_range;
  std::string colormap = "viridis";  ///< viridis | cividis | rainbow (colormap.hpp)
  /// The colour bar's title, the quantity and its unit (e.g. "sigma [mm]"). A colour bar is drawn on the right
  /// whenever a surface is coloured by scalars.
  std::string scalar_title;
};

/// Width [px] of the colour bar's column on the right of a picture.
constexpr int kColorBarWidth = 150;

/// Renders the surfaces into one PNG of view.width × view.height (atomic write), the colour bar inside it.
/// Throws sflsh::Error when no X display can be had.
void render_png(const std::filesystem::path& path, const std::vector<Surface>& surfaces, const View& view);

/// Renders the panels side by side into one PNG, each view.width × view.height (title across the top, each
/// panel's caption under it), with one colour scale and one camera over every panel, and the colour bar in a
/// column of kColorBarWidth on the right when there are scalars. Throws like render_png.
void render_strip_png(const std::filesystem::path& path, const std::vector<Panel>& panels, const View& view);

}  // namespace sflsh::render
