// `sflsh render`: a picture of a simulation's result on a headless machine with its colour bar (viridis by
// default, rainbow on request), and its one-line errors.
#include "png_check.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"

#include <sflsh/core/colormap.hpp>
#include <sflsh/core/render.hpp>

#include <fmt/format.h>
#include <gmock/gmock.h>

#include <fstream>

using sflsh::testing::count_entries;
using sflsh::testing::run_sflsh;
using ::testing::HasSubstr;

namespace {

/// Nine colours of the map, from 10 % to 90 % of its range (the bar's ends meet its frame and labels).
std::vector<sflsh::testing::Rgb8> map_colors(const std::string& colormap) {
  std::vector<sflsh::testing::Rgb8> out;
  for (int k = 1; k <= 9; ++k) {
    const std::array<double, 3> c = sflsh::render::colormap_color(colormap, k / 10.0);
    out.push_back({static_cast<int>(std::lround(255 * c[0])), static_cast<int>(std::lround(255 * c[1])),
                   static_cast<int>(std::lround(255 * c[2]))});
  }
  return out;
}

/// The picture has a vertical colour bar of `colormap` in its right-hand `bar_width` pixels (of `width`).
void expect_color_bar(const std::filesystem::path& png, const std::string& colormap, int width, int bar_width) {
  const int column = sflsh::testing::color_strip_column(png, map_colors(colormap));
  EXPECT_GE(column, width - bar_width) << png << ": no " << colormap << " colour bar on the right";
}

}  // namespace

TEST(CliRender, DrawsTheRunsPosedBodyColouredBySigmaWithoutADisplay) {
  const auto dir = sflsh::testing::scratch_dir();
  const auto run = dir / "run";
  auto result = run_sflsh(fmt::format("-q simulate --solver reduced --mesh coarse --subject OPEN_TRAIN_1 --motion "
                                      "jiggle_on_toes --frames 13 --cache {} --out {}",
                                      SFLSH_TEST_CACHE, run.string()),
                          dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;

  const sflsh::testing::NoDisplay no_display;  // sflsh starts its own virtual display
  result = run_sflsh(fmt::format("-q render --run {} --out {}", run.string(), (dir / "sigma.png").string()), dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  // A 900×1000 picture of a coloured body: a blank or one-colour image has a handful of colours, a shaded body
  // under a colour map hundreds; its colour bar (viridis) on the right, and no rainbow in it.
  sflsh::testing::expect_drawn_png(dir / "sigma.png", 900, 1000, 200);
  expect_color_bar(dir / "sigma.png", "viridis", 900, sflsh::render::kColorBarWidth);
  EXPECT_EQ(sflsh::testing::color_strip_column(dir / "sigma.png", map_colors("rainbow")), -1);

  result =
      run_sflsh(fmt::format("-q render --run {} --color displacement --frame 6 --view front --width 400 --height 500 "
                            "--colormap rainbow --out {}",
                            run.string(), (dir / "frame6.png").string()),
                dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  sflsh::testing::expect_drawn_png(dir / "frame6.png", 400, 500, 50);
  expect_color_bar(dir / "frame6.png", "rainbow", 400, sflsh::render::kColorBarWidth);  // on request
  EXPECT_EQ(sflsh::testing::color_strip_column(dir / "frame6.png", map_colors("viridis")), -1);

  // Point arrays of one surface side by side (validate's σ maps use this on its dynamics.vtp).
  const auto dynamics = run / "dynamics.vtp";
  result = run_sflsh(fmt::format("-q render --map {} --fields sigma,sigma_normal,sigma_tangent --view front --out {}",
                                 dynamics.string(), (dir / "maps.png").string()),
                     dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  sflsh::testing::expect_drawn_png(dir / "maps.png", 3 * 360, 560, 200);
  // The colour bar in its own column right of the panels.
  expect_color_bar(dir / "maps.png", "viridis", 3 * 360 + sflsh::render::kColorBarWidth, sflsh::render::kColorBarWidth);
  // An array the file lacks: one line naming it and what the file has, nothing written.
  result = run_sflsh(
      fmt::format("render --map {} --fields sigma,nope --out {}", dynamics.string(), (dir / "none.png").string()), dir);
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_THAT(result.err, HasSubstr("nope"));
  EXPECT_THAT(result.err, HasSubstr("sigma_normal"));
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "none.png"));
  // A run written with --format vtk (one .vtp per frame) draws the same way.
  const auto vtk_run = dir / "vtk_run";
  result = run_sflsh(fmt::format("-q simulate --solver reduced --mesh coarse --subject OPEN_TRAIN_1 --motion "
                                 "jiggle_on_toes --frames 5 --format vtk --cache {} --out {}",
                                 SFLSH_TEST_CACHE, vtk_run.string()),
                     dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  result = run_sflsh(
      fmt::format("-q render --run {} --color displacement --out {}", vtk_run.string(), (dir / "vtk.png").string()),
      dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  sflsh::testing::expect_drawn_png(dir / "vtk.png", 900, 1000, 200);
  // --run and --map together are refused.
  result = run_sflsh(fmt::format("render --run {} --map {} --fields sigma --out {}", run.string(), dynamics.string(),
                                 (dir / "none.png").string()),
                     dir);
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_THAT(result.err, HasSubstr("--map"));
}

TEST(CliRender, BadRunOrFrameGivesOneLineAndWritesNothing) {
  const auto dir = sflsh::testing::scratch_dir();
  const auto png = dir / "out.png";
  auto result = run_sflsh(fmt::format("render --run {} --out {}", (dir / "missing").string(), png.string()), dir);
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_THAT(result.err, HasSubstr("--run"));
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  std::filesystem::create_directories(dir / "empty");
  result = run_sflsh(fmt::format("render --run {} --out {}", (dir / "empty").string(), png.string()), dir);
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_THAT(result.err, HasSubstr("body_NNNNNN.vtp"));
  result = run_sflsh(fmt::format("render --run {} --frame nine --out {}", (dir / "empty").string(), png.string()), dir);
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_FALSE(std::filesystem::exists(png));
}

TEST(CliRender, DrawsAStripOfASceneRunWithoutADisplay) {
  const auto dir = sflsh::testing::scratch_dir();
  // A ball pressed into the belly of a soft body beside a skinned one: bodies and objects in every panel.
  std::ofstream(dir / "scene.toml") << R"([scene]
fps = 30
frames = 7
[effects]
inertia = true
object_contact = true
[[body]]
name = "soft"
motion = "rest"
solver = "reduced"
mesh = "coarse"
handles = 30
[[body]]
name = "skinned"
motion = "shake_hips"
solver = "skinned"
placement = { position = [1.7, 0.0, 0.0] }
[[object]]
name = "ball"
shape = "sphere"
radius = 0.06
motion = "prescribed"
keyframes = [{ t = 0.0, position = [0.0, 0.064, 0.19] }, { t = 0.2, position = [0.0, 0.064, 0.16] }]
)";
  const auto run = dir / "run";
  auto result = run_sflsh(fmt::format("-q simulate --scene {} --cache {} --out {}", (dir / "scene.toml").string(),
                                      SFLSH_TEST_CACHE, run.string()),
                          dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;

  const sflsh::testing::NoDisplay no_display;  // sflsh starts its own virtual display
  result = run_sflsh(fmt::format("-q render --run {} --strip 3 --view front --colormap cividis --out {}", run.string(),
                                 (dir / "strip.png").string()),
                     dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  // Three 360×560 panels side by side; shaded bodies under a colour map, a grey ball and text give hundreds of
  // colours, a blank picture one. The colour bar (cividis, asked for) in its column right of the panels.
  sflsh::testing::expect_drawn_png(dir / "strip.png", 3 * 360, 560, 200);
  expect_color_bar(dir / "strip.png", "cividis", 3 * 360 + sflsh::render::kColorBarWidth,
                   sflsh::render::kColorBarWidth);

  // A single-body run has no scene.pvd: one line, nothing written.
  result = run_sflsh(fmt::format("render --run {} --strip 3 --out {}", (dir / "scene.toml").parent_path().string(),
                                 (dir / "none.png").string()),
                     dir);
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_THAT(result.err, HasSubstr("scene.pvd"));
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "none.png"));
  // --strip draws displacement at evenly spaced frames: --frame is refused with it.
  result = run_sflsh(
      fmt::format("render --run {} --strip 3 --frame 2 --out {}", run.string(), (dir / "none.png").string()), dir);
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_THAT(result.err, HasSubstr("--frame"));
}
