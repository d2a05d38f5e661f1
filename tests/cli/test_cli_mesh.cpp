// `sflsh mesh`: the layer-mesh contract (files, fields, summary) and its one-line errors.
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "self_described.hpp"

#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>

#include <fmt/format.h>
#include <gmock/gmock.h>

#include <algorithm>
#include <fstream>

namespace sflsh {

using sflsh::testing::count_entries;
using sflsh::testing::run_sflsh;
using ::testing::HasSubstr;

namespace {

// The coarse gmsh layer of the open body, cached in the build tree (shared with the meshing tests).
std::string gmsh_coarse_args() { return fmt::format("--mesher gmsh --mesh coarse --cache {}", SFLSH_TEST_CACHE); }

}  // namespace

TEST(CliMesh, WritesTheLayerSurfacesAndSummary) {
  const auto dir = sflsh::testing::scratch_dir();
  const auto out = dir / "layer";
  const auto result = run_sflsh(
      fmt::format("-q mesh --subject OPEN_TRAIN_2 --thickness 0.4 {} --out {}", gmsh_coarse_args(), out.string()), dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  for (const char* file : {"layer.vtu", "outer.vtp", "inner.vtp", "summary.json"})
    EXPECT_TRUE(std::filesystem::exists(out / file)) << file;
  const auto names = sflsh::vtk::read_point_array_names(out / "layer.vtu");
  for (const char* field : {"node_kind", "part", "thickness_fraction", "local_thickness"})
    EXPECT_THAT(names, ::testing::Contains(std::string(field)));
  const auto h = sflsh::vtk::read_point_array(out / "layer.vtu", "thickness_fraction");
  EXPECT_NEAR(h.minCoeff(), 0.4, 1e-9);
  EXPECT_NEAR(h.maxCoeff(), 0.4, 1e-9);
  const auto summary = read_json(out / "summary.json");
  EXPECT_EQ(summary["subject"], "OPEN_TRAIN_2");
  EXPECT_EQ(summary["mesher"], "gmsh");
  EXPECT_EQ(summary["skin_mapping"], "nodes");
  EXPECT_EQ(summary["quality"]["inverted"], 0);
  EXPECT_GT(summary["quality"]["tets"].get<long>(), 1000);
  EXPECT_TRUE(summary["quality_template"].contains("min_dihedral_deg"));
  EXPECT_GT(summary["quality"]["thickness_max_m"].get<double>(), summary["quality"]["thickness_min_m"].get<double>());
  EXPECT_TRUE(summary["timings_s"].contains("retarget"));
  // The run time under its one name and under mesh's older one (an alias for one release, docs/output.md).
  EXPECT_EQ(summary.at("timings").at("total_seconds"), summary.at("timings_s").at("total"));
  // The outer surface has one point per skin vertex of the region.
  EXPECT_EQ(sflsh::vtk::read_points(out / "outer.vtp").rows(), summary["skin_vertices"].get<long>());
  // Every array says its unit; part and node_kind come with the names of their values.
  for (const char* file : {"layer.vtu", "outer.vtp", "inner.vtp"}) sflsh::testing::expect_self_described(out / file);
  sflsh::testing::expect_labels_named(out / "layer.vtu", sflsh::vtk::read_point_array(out / "layer.vtu", "part"),
                                      "part_names");
  sflsh::testing::expect_labels_named(out / "layer.vtu", sflsh::vtk::read_cell_array(out / "layer.vtu", "part"),
                                      "part_names");
  sflsh::testing::expect_labels_named(out / "layer.vtu", sflsh::vtk::read_point_array(out / "layer.vtu", "node_kind"),
                                      "node_kind_names");
  sflsh::testing::expect_labels_named(out / "outer.vtp", sflsh::vtk::read_point_array(out / "outer.vtp", "part"),
                                      "part_names");
  EXPECT_EQ(sflsh::vtk::read_field_strings(out / "layer.vtu", "part_names").size(), 5u);
  EXPECT_THAT(sflsh::vtk::read_field_strings(out / "layer.vtu", "node_kind_names"),
              ::testing::ElementsAre("interior", "outer", "inner", "side"));
}

TEST(CliMesh, BadInputGivesOneLineAndWritesNothing) {
  const auto dir = sflsh::testing::scratch_dir();
  const auto out = dir / "layer";
  struct Case {
    std::string args;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"--thickness 1.5", "--thickness 1.5: expected a fraction 0 < h < 1"},
      {"--thickness 0", "expected a fraction 0 < h < 1"},
      {"--region torso,tail", "unknown name 'tail'"},
      {"--subject NOBODY", "NOBODY"},
  };
  for (const auto& c : cases) {
    const auto result = run_sflsh(fmt::format("mesh {} {} --out {}", gmsh_coarse_args(), c.args, out.string()), dir);
    EXPECT_NE(result.exit_code, 0) << c.args;
    EXPECT_THAT(result.err, HasSubstr(c.message)) << c.args;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_EQ(count_entries(out), 0u) << c.args;
  }
}

TEST(CliMesh, CorruptCacheIsReportedWithTheFile) {
  const auto dir = sflsh::testing::scratch_dir();
  const auto cache = dir / "cache";
  std::filesystem::create_directories(cache);
  // Find the file name the command uses by building once, then corrupt it.
  // --size is the older spelling of --mesh and still names the preset.
  auto result = run_sflsh(fmt::format("-q mesh --region left_thigh --mesher layered --size coarse --cache {} --out {}",
                                      cache.string(), (dir / "a").string()),
                          dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const std::string path = read_json(dir / "a" / "summary.json")["cache"]["path"];
  { std::ofstream(path) << "garbage"; }
  result = run_sflsh(fmt::format("mesh --region left_thigh --mesher layered --size coarse --cache {} --out {}",
                                 cache.string(), (dir / "b").string()),
                     dir);
  EXPECT_NE(result.exit_code, 0);
  EXPECT_THAT(result.err, HasSubstr(path));
  EXPECT_THAT(result.err, HasSubstr("--rebuild-cache"));
  result = run_sflsh(
      fmt::format("-q mesh --region left_thigh --mesher layered --size coarse --cache {} --rebuild-cache --out {}",
                  cache.string(), (dir / "c").string()),
      dir);
  EXPECT_EQ(result.exit_code, 0) << result.err;
}

}  // namespace sflsh

namespace sflsh {

// Where the template inverts tets at a subject's shape and thickness, the subject's own layer is meshed (cached per
// subject and thickness) and the run succeeds: TEST_3 at h = 0.1 inverts 1519 tets of the gmsh coarse template and
// meshes on its own body in about a second (smallest dihedral angle 8.7°).
TEST(CliMesh, SubjectTheTemplateCannotReachIsMeshedOnItsOwn) {
  const auto dir = sflsh::testing::scratch_dir();
  const auto cache = dir / "cache";
  for (const char* run : {"first", "cached"}) {
    SCOPED_TRACE(run);
    const auto out = dir / run;
    const auto r = run_sflsh(
        fmt::format("-q mesh --subject TEST_3 --thickness 0.1 --mesher gmsh --mesh coarse --cache {} --out {}",
                    cache.string(), out.string()),
        dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json summary = read_json(out / "summary.json");
    EXPECT_TRUE(summary["remeshed"].get<bool>());
    EXPECT_THAT(summary["template_failure"].get<std::string>(), HasSubstr("inverts"));
    EXPECT_EQ(summary["quality"]["inverted"].get<long>(), 0);
    EXPECT_EQ(summary["quality"]["degenerate"].get<long>(), 0);
    const auto h = sflsh::vtk::read_point_array(out / "layer.vtu", "thickness_fraction");
    EXPECT_NEAR(h.minCoeff(), 0.1, 1e-9);
    EXPECT_NEAR(h.maxCoeff(), 0.1, 1e-9);
  }
  // The template's entry and the subject's own, side by side in the cache.
  EXPECT_EQ(count_entries(cache), 2u);
  // The layered coarse mesher at h = 0.7: its one prism layer twists at the crotch (on the template and on the
  // subject alike: 0.34°), so the layered mesh with two prism layers takes over, named in the summary.
  const auto thick = run_sflsh(fmt::format("-q mesh --subject OPEN_TEST_3 --thickness 0.7 --mesher layered --mesh "
                                           "coarse --cache {} --out {}",
                                           cache.string(), (dir / "thick").string()),
                               dir);
  ASSERT_EQ(thick.exit_code, 0) << thick.err;
  const nlohmann::json summary = read_json(dir / "thick" / "summary.json");
  EXPECT_TRUE(summary["remeshed"].get<bool>());
  EXPECT_THAT(summary["template_failure"].get<std::string>(), HasSubstr("inverts"));
  EXPECT_THAT(summary["fallback"].get<std::string>(), HasSubstr("2 prism layers"));
  EXPECT_EQ(summary["mesher"].get<std::string>(), "layered");
  EXPECT_GE(summary["quality"]["min_dihedral_deg"].get<double>(), 0.5);
}

}  // namespace sflsh
