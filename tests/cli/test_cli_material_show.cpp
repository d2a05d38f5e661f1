// `sflsh material show`: the material-field files and their errors.
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "self_described.hpp"

#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>

#include <fmt/format.h>
#include <gmock/gmock.h>

#include <fstream>

namespace sflsh {

using sflsh::testing::count_entries;
using sflsh::testing::run_sflsh;
using ::testing::HasSubstr;

namespace {
std::string layered_coarse_args() { return fmt::format("--mesher layered --mesh coarse --cache {}", SFLSH_TEST_CACHE); }
}  // namespace

TEST(CliMaterialShow, WritesFieldsControlPointsAndARoundTrippableMaterialFile) {
  const auto dir = sflsh::testing::scratch_dir();
  const auto out = dir / "show";
  auto result = run_sflsh(fmt::format("-q material show --subject OPEN_TEST_1 --control-points 12 --phi {} --out {}",
                                      layered_coarse_args(), out.string()),
                          dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  for (const char* file : {"surface.vtp", "layer.vtu", "control_points.vtp", "material.toml", "summary.json"})
    EXPECT_TRUE(std::filesystem::exists(out / file)) << file;
  const auto names = sflsh::vtk::read_point_array_names(out / "surface.vtp");
  for (const char* field : {"thickness", "young_tangent", "young_normal", "phi_00", "phi_11"})
    EXPECT_THAT(names, ::testing::Contains(std::string(field)));
  EXPECT_EQ(sflsh::vtk::read_points(out / "control_points.vtp").rows(), 12);
  for (const char* file : {"surface.vtp", "layer.vtu", "control_points.vtp"})
    sflsh::testing::expect_self_described(out / file);
  EXPECT_EQ(sflsh::vtk::read_point_array(out / "surface.vtp", "thickness_fraction"),
            sflsh::vtk::read_point_array(out / "surface.vtp", "thickness"));
  // The written material file is accepted back as --material.
  const auto again = dir / "again";
  result = run_sflsh(fmt::format("-q material show --subject OPEN_TEST_1 --material {} {} --out {}",
                                 (out / "material.toml").string(), layered_coarse_args(), again.string()),
                     dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(read_json(again / "summary.json")["control_points"], 12);
}

TEST(CliMaterialShow, BadMaterialFileGivesOneLineAndWritesNothing) {
  const auto dir = sflsh::testing::scratch_dir();
  const auto bad = dir / "bad.toml";
  { std::ofstream(bad) << "body = 'open_body'\nsubject = 'x'\n[[control_point]]\nvertex = 'seven'\n"; }
  const auto out = dir / "show";
  const auto result = run_sflsh(
      fmt::format("material show --material {} {} --out {}", bad.string(), layered_coarse_args(), out.string()), dir);
  EXPECT_NE(result.exit_code, 0);
  EXPECT_THAT(result.err, HasSubstr(bad.string()));
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  EXPECT_EQ(count_entries(out), 0u);
}

// --shape-model: the material of a subject's shape from the shipped shape model (SFLSH eq. 1). The fields vary
// over the body (more than one control point, each with its own κ) and between subjects of different shape.
TEST(CliMaterialShow, ShapeModelGivesAShapeDependentMaterial) {
  const auto dir = sflsh::testing::scratch_dir();
  const std::string model = std::string(SFLSH_DATA_DIR) + "/shape_models/default.toml";
  Eigen::VectorXd mean_young(2);
  int i = 0;
  for (const char* subject : {"OPEN_TRAIN_1", "OPEN_TEST_3"}) {
    const auto out = dir / subject;
    const auto result = run_sflsh(fmt::format("-q material show --subject {} --shape-model {} {} --out {}", subject,
                                              model, layered_coarse_args(), out.string()),
                                  dir);
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const nlohmann::json summary = read_json(out / "summary.json");
    EXPECT_EQ(summary["material_source"], "shape model");
    const Eigen::MatrixXd young = sflsh::vtk::read_point_array(out / "surface.vtp", "young_tangent");
    const Eigen::MatrixXd thickness = sflsh::vtk::read_point_array(out / "surface.vtp", "thickness");
    // Heterogeneous: the shipped model's four control points differ by more than 5 % (a uniform material would
    // give max/min = 1 up to round-off, as the defaults did).
    const double lo = young.col(0).minCoeff(), hi = young.col(0).maxCoeff();
    EXPECT_GT(lo, 0.0);
    EXPECT_GT(hi / lo, 1.05) << subject;
    EXPECT_GT(thickness.col(0).maxCoeff() - thickness.col(0).minCoeff(), 1e-3) << subject;
    mean_young(i++) = young.col(0).mean();
  }
  // Shape-dependent: two subjects of different shape get different materials.
  EXPECT_GT(std::abs(mean_young(0) - mean_young(1)), 1e-3 * mean_young(0));
  // --material and --shape-model exclude each other: one line, nothing written.
  const auto out = dir / "both";
  const auto both = run_sflsh(fmt::format("material show --material x.toml --shape-model {} {} --out {}", model,
                                          layered_coarse_args(), out.string()),
                              dir);
  EXPECT_EQ(both.exit_code, 2);
  EXPECT_THAT(both.err, HasSubstr("--shape-model"));
  EXPECT_EQ(count_entries(out), 0u);
}

}  // namespace sflsh
