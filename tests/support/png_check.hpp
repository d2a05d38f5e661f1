#pragma once
// Pictures in tests: a headless process (no $DISPLAY, as on a cluster node or in CI) and a check that a PNG the
// CLI wrote is a real picture, decoded with VTK's PNG reader: the expected size, and enough distinct colours that
// it is not a blank or single-colour image.
#include <gtest/gtest.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#include <vtkPointData.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <set>
#include <string>

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

}  // namespace sflsh::testing
