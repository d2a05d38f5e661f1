// `sflsh material show`: the material-field files and their errors.
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "self_described.hpp"

#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>

#include <fmt/format.h>
#include <gmock/gmock.h>

#include <fstream>

using namespace sflsh;
using sflsh::testing::count_entries;
using sflsh::testing::run_sflsh;
using ::testing::HasSubstr;

namespace {
std::string common_args() { return fmt::format("--mesher layered --mesh coarse --cache {}", SFLSH_TEST_CACHE); }
}  // namespace

TEST(CliMaterialShow, WritesFieldsControlPointsAndARoundTrippableMaterialFile) {
  const auto dir = sflsh::testing::scratch_dir();
  const auto out = dir / "show";
  auto result = run_sflsh(
      fmt::format("-q material show --subject OPEN_TEST_1 --control-points 12 --phi {} --out {}", common_args(), out.string()), dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  for (const char* file : {"surface.vtp", "layer.vtu", "control_points.vtp", "material.toml", "summary.json"})
    EXPECT_TRUE(std::filesystem::exists(out / file)) << file;
  const auto names = vtk::read_point_array_names(out / "surface.vtp");
  for (const char* field : {"thickness", "young_tangent", "young_normal", "phi_00", "phi_11"})
    EXPECT_THAT(names, ::testing::Contains(std::string(field)));
  EXPECT_EQ(vtk::read_points(out / "control_points.vtp").rows(), 12);
  for (const char* file : {"surface.vtp", "layer.vtu", "control_points.vtp"}) sflsh::testing::expect_self_described(out / file);
  EXPECT_EQ(vtk::read_point_array(out / "surface.vtp", "thickness_fraction"), vtk::read_point_array(out / "surface.vtp", "thickness"));
  // The written material file is accepted back as --material.
  const auto again = dir / "again";
  result = run_sflsh(fmt::format("-q material show --subject OPEN_TEST_1 --material {} {} --out {}",
                                 (out / "material.toml").string(), common_args(), again.string()),
                     dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(read_json(again / "summary.json")["control_points"], 12);
}

TEST(CliMaterialShow, BadMaterialFileGivesOneLineAndWritesNothing) {
  const auto dir = sflsh::testing::scratch_dir();
  const auto bad = dir / "bad.toml";
  { std::ofstream(bad) << "body = 'open_body'\nsubject = 'x'\n[[control_point]]\nvertex = 'seven'\n"; }
  const auto out = dir / "show";
  const auto result = run_sflsh(fmt::format("material show --material {} {} --out {}", bad.string(), common_args(), out.string()), dir);
  EXPECT_NE(result.exit_code, 0);
  EXPECT_THAT(result.err, HasSubstr(bad.string()));
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_EQ(count_entries(out), 0u);
}
