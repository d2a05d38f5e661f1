// `sflsh render`: a picture of a simulation's result on a headless machine, and its one-line errors.
#include "png_check.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"

#include <fmt/format.h>
#include <gmock/gmock.h>

using sflsh::testing::count_entries;
using sflsh::testing::run_sflsh;
using ::testing::HasSubstr;

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
  // under a rainbow map hundreds.
  sflsh::testing::expect_drawn_png(dir / "sigma.png", 900, 1000, 200);

  result =
      run_sflsh(fmt::format("-q render --run {} --color displacement --frame 6 --view front --width 400 --height 500 "
                            "--out {}",
                            run.string(), (dir / "frame6.png").string()),
                dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  sflsh::testing::expect_drawn_png(dir / "frame6.png", 400, 500, 50);
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
