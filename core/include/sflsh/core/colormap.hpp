#pragma once
// Colour maps of the pictures (render, strips, σ maps): perceptually uniform viridis (default) and cividis
// (readable with colour-vision deficiency), or the older rainbow (blue to red) on request.
#include <array>
#include <string>
#include <vector>

namespace sflsh::render {

/// "viridis", "cividis", "rainbow".
const std::vector<std::string>& colormap_names();
/// Throws sflsh::Error "<what> <name>: expected viridis, cividis or rainbow" for another name.
void check_colormap(const std::string& name, const std::string& what);
/// The RGB colour (each in [0, 1]) of the map at `fraction` of its range (clamped to [0, 1]).
std::array<double, 3> colormap_color(const std::string& name, double fraction);

}  // namespace sflsh::render
