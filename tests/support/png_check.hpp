#pragma once
// Pictures in tests: a headless process (no $DISPLAY, as on a cluster node or in CI) and a check that a PNG the
// CLI wrote is a real picture, decoded with VTK's PNG reader: the expected size, and enough distinct colours that
// it is not a blank or single-colour image; and that a colour bar of a given colour map is drawn in it.
#include <gtest/gtest.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#include <vtkPointData.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace sflsh::testing {

/// Unsets $DISPLAY for the scope (child processes inherit the environment), restoring it afterwards.
class NoDisplay {
 public:
  NoDisplay() {
    if (const char* d = std::getenv("DISPLAY")) saved_ = d;
    ::unsetenv("DISPLAY");
  }
  ~NoDisplay() {
    if (saved_) ::setenv("DISPLAY", saved_->c_str(), 1);
  }
  NoDisplay(const NoDisplay&) = delete;
  NoDisplay& operator=(const NoDisplay&) = delete;

 private:
  std::optional<std::string> saved_;
};

struct PngInfo {
  int width = 0;
  int height = 0;
  std::size_t distinct_colors = 0;  ///< distinct RGB triples (counted up to 4096)
};

/// Decodes the PNG at `path` (fails the test when it is missing or not a PNG) and counts its colours.
inline PngInfo read_png_info(const std::filesystem::path& path) {
  PngInfo info;
  EXPECT_TRUE(std::filesystem::exists(path)) << path;
  if (!std::filesystem::exists(path)) return info;
  vtkNew<vtkPNGReader> reader;
  EXPECT_TRUE(reader->CanReadFile(path.c_str())) << path << " is not a PNG";
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  int dims[3] = {0, 0, 0};
  image->GetDimensions(dims);
  info.width = dims[0];
  info.height = dims[1];
  vtkDataArray* scalars = image->GetPointData()->GetScalars();
  if (!scalars) return info;
  const int channels = scalars->GetNumberOfComponents();
  std::set<std::uint32_t> colors;
  for (vtkIdType i = 0; i < scalars->GetNumberOfTuples() && colors.size() < 4096; ++i) {
    std::uint32_t rgb = 0;
    for (int c = 0; c < std::min(channels, 3); ++c)
      rgb = (rgb << 8) | static_cast<std::uint32_t>(scalars->GetComponent(i, c));
    colors.insert(rgb);
  }
  info.distinct_colors = colors.size();
  return info;
}

/// A drawn picture: at least `min_width` × `min_height` pixels and more than `min_colors` distinct colours (a blank
/// image has one; antialiased text, axes and a coloured surface give hundreds).
inline void expect_drawn_png(const std::filesystem::path& path, int min_width, int min_height,
                             std::size_t min_colors = 16) {
  const PngInfo info = read_png_info(path);
  EXPECT_GE(info.width, min_width) << path;
  EXPECT_GE(info.height, min_height) << path;
  EXPECT_GT(info.distinct_colors, min_colors) << path << ": a blank or nearly blank image";
}

/// An RGB colour, 0–255 per channel.
using Rgb8 = std::array<int, 3>;

/// The first column of the PNG in which, going up, pixels within `tolerance` (per channel) of every colour of
/// `colors` appear in that order: a vertical colour bar drawn with those colours; −1 when there is none. Shaded
/// surfaces do not trace a map's colours in order along a column, an unlit colour bar does.
inline int color_strip_column(const std::filesystem::path& path, const std::vector<Rgb8>& colors, int tolerance = 6) {
  vtkNew<vtkPNGReader> reader;
  if (!reader->CanReadFile(path.c_str())) return -1;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  int dims[3] = {0, 0, 0};
  image->GetDimensions(dims);
  vtkDataArray* scalars = image->GetPointData()->GetScalars();
  if (!scalars || scalars->GetNumberOfComponents() < 3 || colors.empty()) return -1;
  for (int x = 0; x < dims[0]; ++x) {
    std::size_t next = 0;
    for (int y = 0; y < dims[1] && next < colors.size(); ++y) {  // VTK's image rows go up from the bottom
      const vtkIdType pixel = static_cast<vtkIdType>(y) * dims[0] + x;
      bool close = true;
      for (int c = 0; c < 3; ++c)
        close = close && std::abs(static_cast<int>(scalars->GetComponent(pixel, c)) - colors[next][c]) <= tolerance;
      if (close) ++next;
    }
    if (next == colors.size()) return x;
  }
  return -1;
}

}  // namespace sflsh::testing
