// `sflsh material curve` as users' scripts see it: the CSV/summary contract, the PNG with and without a
// display, and one-line errors that name the option and write nothing.
#include "png_check.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "text_lines.hpp"

#include <sflsh/core/summary.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <optional>

using sflsh::testing::count_entries;
using sflsh::testing::NoDisplay;
using sflsh::testing::run_sflsh;
using ::testing::HasSubstr;

namespace {

std::size_t count_lines(const std::string& text) {
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

using sflsh::testing::lines_of;

}  // namespace

/// A PNG file that holds a picture: the signature, and more bytes than a blank image of its size compresses to.
void expect_png_with_content(const std::filesystem::path& path, std::uintmax_t min_bytes) {
  ASSERT_TRUE(std::filesystem::exists(path)) << path;
  std::ifstream png(path, std::ios::binary);
  char magic[8] = {};
  png.read(magic, 8);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");
  EXPECT_GT(std::filesystem::file_size(path), min_bytes);
}

TEST(CliMaterial, CurveWritesCsvSummaryAndThePngWithoutDisplay) {
  const auto dir = sflsh::testing::scratch_dir();
  const auto out = dir / "curves";
  const NoDisplay no_display;  // a headless machine: sflsh starts its own virtual display
  const auto r = run_sflsh("material curve --young-tangent 5000 --young-normal 2000 --out " + out.string(), dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  expect_png_with_content(out / "curves.png", 5000u);  // a 900×600 chart with three curves, not an empty image
  sflsh::testing::expect_drawn_png(out / "curves.png", 900, 600);
  EXPECT_EQ(count_entries(out), 3u);  // curves.csv + curves.png + summary.json, no staging leftovers

  const auto lines = lines_of(out / "curves.csv");
  ASSERT_EQ(lines.size(), 1u + 81u + 81u + 51u);
  EXPECT_EQ(lines[0], "test,strain,stress");
  EXPECT_THAT(lines[1], ::testing::StartsWith("uniaxial_tangent,-0.3"));
  EXPECT_THAT(lines[82], ::testing::StartsWith("uniaxial_normal,-0.3"));
  EXPECT_THAT(lines[163], ::testing::StartsWith("shear,0,"));
  EXPECT_THAT(lines.back(), ::testing::StartsWith("shear,0.5,"));

  const nlohmann::json summary = sflsh::read_json(out / "summary.json");
  EXPECT_EQ(summary["command"], "material curve");
  EXPECT_EQ(summary["material"]["young_tangent_pa"], 5000.0);
  EXPECT_EQ(summary["material"]["poisson"], 0.2);
  EXPECT_EQ(summary["material"]["saturation"], 4.0);
  EXPECT_EQ(summary["material"]["febio_fung_ortho_compressible"]["E3"], 2000.0);
  EXPECT_EQ(summary["material"]["febio_fung_ortho_compressible"]["c"], 1250.0);
  EXPECT_EQ(summary["plot"], "curves.png");
  ASSERT_EQ(summary["tests"].size(), 3u);
  EXPECT_EQ(summary["tests"][2]["test"], "shear");
  EXPECT_EQ(summary["tests"][2]["samples"], 51);
  // The last CSV row and the summary report the same stress.
  const std::string last = lines.back();
  EXPECT_EQ(std::stod(last.substr(last.rfind(',') + 1)), summary["tests"][2]["stress_at_strain_max_pa"].get<double>());
}

TEST(CliMaterial, CurveDrawsThePngUnderXvfb) {
  if (std::system("command -v xvfb-run >/dev/null 2>&1") != 0) GTEST_SKIP() << "xvfb-run is not installed";
  const auto dir = sflsh::testing::scratch_dir();
  const auto out = dir / "curves";
  const NoDisplay no_display;  // xvfb-run provides its own
  const std::string command = "xvfb-run -a " + std::string(SFLSH_CLI) +
                              " --quiet material curve --young-tangent 5000 --young-normal 2000 --saturation 8 --out " +
                              out.string() + " 2>" + (dir / "err.txt").string();
  ASSERT_EQ(std::system(command.c_str()), 0) << lines_of(dir / "err.txt").size() << " lines of stderr";
  ASSERT_TRUE(std::filesystem::exists(out / "curves.png"));
  std::ifstream png(out / "curves.png", std::ios::binary);
  char magic[8] = {};
  png.read(magic, 8);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");
  EXPECT_GT(std::filesystem::file_size(out / "curves.png"), 5000u);  // a 900×600 chart, not an empty image
  EXPECT_EQ(sflsh::read_json(out / "summary.json")["plot"], "curves.png");
}

TEST(CliMaterial, BadInputIsOneLineNamingTheOptionAndWritesNothing) {
  const auto dir = sflsh::testing::scratch_dir();
  const auto out = dir / "never";
  const std::string base = "material curve --out " + out.string() + " ";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--young-tangent=-1 --young-normal 2000", "--young-tangent"},
      {"--young-tangent -1 --young-normal 2000", "--young-tangent"},
      {"--young-tangent 5000 --young-normal 0", "--young-normal"},
      {"--young-tangent 5000 --young-normal 2000 --poisson 0.5", "--poisson"},
      {"--young-tangent 5000 --young-normal 2000 --poisson=-1", "--poisson"},
      {"--young-tangent 5000 --young-normal 2000 --saturation 0", "--saturation"},
      {"--young-tangent nan --young-normal 2000", "--young-tangent"},
  };
  for (const auto& [args, option] : cases) {
    const auto r = run_sflsh(base + args, dir);
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_THAT(r.err, HasSubstr(option)) << args;
    EXPECT_EQ(count_lines(r.err), 1u) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out)) << args;
  }
  const auto missing = run_sflsh("material curve --young-tangent 5000 --out " + out.string(), dir);
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_THAT(missing.err, HasSubstr("--young-normal"));
  EXPECT_FALSE(std::filesystem::exists(out));
}
