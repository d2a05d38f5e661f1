// The pictures' colour maps: viridis and cividis as matplotlib draws them, rainbow as VTK's blue-to-red table, and a
// one-line error for another name.
#include <sflsh/core/colormap.hpp>
#include <sflsh/core/error.hpp>

#include <gmock/gmock.h>

#include <cmath>

namespace sflsh {
namespace {

void expect_rgb(const std::array<double, 3>& got, double r, double g, double b, double tolerance) {
  EXPECT_NEAR(got[0], r, tolerance);
  EXPECT_NEAR(got[1], g, tolerance);
  EXPECT_NEAR(got[2], b, tolerance);
}

TEST(Colormap, ViridisAndCividisMatchMatplotlib) {
  // matplotlib 3.6: viridis(0) = #440154, viridis(0.5) = #21918c, viridis(1) = #fde725; cividis(0) = #00224e,
  // cividis(1) = #fee838 (within the interpolation's 5/255).
  const double tolerance = 5.0 / 255.0;
  expect_rgb(render::colormap_color("viridis", 0.0), 0x44 / 255.0, 0x01 / 255.0, 0x54 / 255.0, tolerance);
  expect_rgb(render::colormap_color("viridis", 0.5), 0x21 / 255.0, 0x91 / 255.0, 0x8c / 255.0, tolerance);
  expect_rgb(render::colormap_color("viridis", 1.0), 0xfd / 255.0, 0xe7 / 255.0, 0x25 / 255.0, tolerance);
  expect_rgb(render::colormap_color("cividis", 0.0), 0x00 / 255.0, 0x22 / 255.0, 0x4e / 255.0, tolerance);
  expect_rgb(render::colormap_color("cividis", 1.0), 0xfe / 255.0, 0xe8 / 255.0, 0x38 / 255.0, tolerance);
  // Perceptually uniform maps grow in lightness; out-of-range and non-finite fractions clamp.
  double previous = -1.0;
  for (int k = 0; k <= 20; ++k) {
    const std::array<double, 3> c = render::colormap_color("viridis", k / 20.0);
    const double luma = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    EXPECT_GT(luma, previous) << k;
    previous = luma;
  }
  EXPECT_EQ(render::colormap_color("viridis", 2.0), render::colormap_color("viridis", 1.0));
  EXPECT_EQ(render::colormap_color("viridis", std::nan("")), render::colormap_color("viridis", 0.0));
}

TEST(Colormap, RainbowRunsFromBlueToRedAndOtherNamesAreRefused) {
  expect_rgb(render::colormap_color("rainbow", 0.0), 0.0, 0.0, 1.0, 0.01);
  expect_rgb(render::colormap_color("rainbow", 1.0), 1.0, 0.0, 0.0, 1e-12);
  expect_rgb(render::colormap_color("rainbow", 0.5), 0.0, 1.0, 0.0, 0.01);  // hue ≈ 0.33: green
  try {
    render::colormap_color("jet", 0.5);
    ADD_FAILURE() << "jet accepted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "colour map jet: expected viridis, cividis or rainbow");
  }
}

}  // namespace
}  // namespace sflsh
