// Every mesher × named subject × thickness gives a valid layer (docs/meshing.md, "Every mesher at every thickness"):
// the coarse template retargeted or, where that inverts tets, the subject's own layer by the same mesher or the
// layered mesh with more prism layers (meshing/subject_layer.hpp).
// The whole sweep (3 meshers × 22 subjects × h = 0.1…0.9) is a long test that writes its table to the build tree
// (meshing-sweep/thickness.md); a slice runs in every CI run.
#include "layer_fixture.hpp"
#include "long_test.hpp"

#include <sflsh/body/subjects.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/meshing/subject_layer.hpp>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace sflsh::meshing {
namespace {

using sflsh::testing::coarse_layer;
using sflsh::testing::coarse_options;
using sflsh::testing::open_body;

struct Outcome {
  /// ok (template retargeted), remeshed (the subject's own layer by the same mesher), layered×L (the layered mesh
  /// with L prism layers) or failed
  std::string kind;
  double min_dihedral_deg = 0.0;
  std::string error;
};

Outcome layer_outcome(Mesher mesher, const body::Subject& subject, double thickness) {
  const LayerMesh& mesh = coarse_layer(mesher);
  try {
    const SubjectLayer layer = subject_layer(open_body(), mesh, subject.beta,
                                             Eigen::VectorXd::Constant(mesh.region_surface.num_vertices(), thickness),
                                             coarse_options(mesher), SFLSH_TEST_CACHE);
    EXPECT_TRUE(layer.layer.quality.valid()) << "a returned layer is always valid";
    std::string kind = layer.remeshed ? "remeshed" : "ok";
    if (layer.remeshed && layer.mesh->mesher == Mesher::layered)
      kind = fmt::format("layered×{}", layer.mesh->num_nodes() / layer.mesh->region_surface.num_vertices() - 1);
    return {kind, layer.layer.quality.min_dihedral_deg, ""};
  } catch (const Error& e) {
    return {"failed", 0.0, e.what()};
  }
}

// Runs the cases, fails the test for each failed one, and returns the table (one row per mesher and subject).
std::string sweep(const std::vector<Mesher>& meshers, const std::vector<std::string>& subjects,
                  const std::vector<double>& thicknesses) {
  const auto all = body::default_subjects();
  std::string table = "| mesher | subject |";
  for (double h : thicknesses) table += fmt::format(" {:.1f} |", h);
  table += "\n|---|---|";
  for (std::size_t k = 0; k < thicknesses.size(); ++k) table += "---|";
  table += "\n";
  for (Mesher mesher : meshers)
    for (const auto& name : subjects) {
      table += fmt::format("| {} | {} |", mesher_name(mesher), name);
      for (double h : thicknesses) {
        const Outcome outcome = layer_outcome(mesher, body::find_subject(all, name), h);
        EXPECT_NE(outcome.kind, "failed") << mesher_name(mesher) << " " << name << " h=" << h << ": " << outcome.error;
        table += outcome.kind == "failed" ? " failed |"
                                          : fmt::format(" {} {:.1f}° |", outcome.kind, outcome.min_dihedral_deg);
      }
      table += "\n";
    }
  return table;
}

const std::vector<Mesher> kMeshers = {Mesher::layered, Mesher::gmsh, Mesher::cgal};

TEST(ThicknessSweep, SliceOfEveryMesherGivesValidLayers) {
  // The hardest Table-1 shape and the hardest open test subject (docs/meshing.md §6) at a thin, the template's and a
  // thick layer; layered up to 0.9, where its single coarse prism layer twists at the crotch and the fallback takes
  // 2, 4, 8 layers (a second each); cgal at 0.1, where its thin layer over concave skin fails on the template and on
  // the subject alike and the layered mesh takes over (~20 s: the subject is meshed twice first).
  std::string table = sweep({Mesher::gmsh, Mesher::cgal}, {"TEST_3", "OPEN_TEST_3"}, {0.3, 0.5, 0.7});
  table += sweep({Mesher::layered}, {"TEST_3", "OPEN_TEST_3"}, {0.3, 0.5, 0.7, 0.8, 0.9});
  table += sweep({Mesher::cgal}, {"TEST_3"}, {0.1});
  RecordProperty("table", table);
}

TEST(ThicknessSweep, AFieldNoLayerTakesFailsNamingEveryTry) {
  // A thickness alternating between 0.02 and 0.98 from one skin vertex to the next folds the inner surface over
  // itself: no mesh of any layer count can follow it, so the error names the template's failure and every fallback.
  const LayerMesh& mesh = coarse_layer(Mesher::layered);
  Eigen::VectorXd h(mesh.region_surface.num_vertices());
  for (int v = 0; v < h.size(); ++v) h(v) = (v % 2) ? 0.98 : 0.02;
  std::string message;
  try {
    subject_layer(open_body(), mesh, body::Betas::Zero(), h, coarse_options(Mesher::layered), SFLSH_TEST_CACHE);
  } catch (const Error& e) {
    message = e.what();
  }
  EXPECT_THAT(message, ::testing::HasSubstr("inverts"));
  EXPECT_THAT(message, ::testing::HasSubstr("the subject's own layer failed as well"));
  for (int layers : {2, 4, 8, 16})
    EXPECT_THAT(message, ::testing::HasSubstr(fmt::format("the layered mesh with {} prism layers:", layers)));
  EXPECT_EQ(message.find('\n'), std::string::npos) << "one line";
}

TEST(ThicknessSweep, EveryMesherSubjectAndThicknessGivesAValidLayer) {
  SFLSH_LONG_TEST();
  std::vector<std::string> names;
  for (const auto& subject : body::default_subjects()) names.push_back(subject.name);
  const std::string table = sweep(kMeshers, names, {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9});
  const std::filesystem::path report =
      std::filesystem::path(SFLSH_TEST_CACHE).parent_path() / "meshing-sweep/thickness.md";
  std::filesystem::create_directories(report.parent_path());
  std::ofstream(report) << "# Mesher × subject × thickness (coarse): ok = template retargeted, remeshed = the "
                           "subject's own layer, layered×L = the layered mesh with L prism layers; smallest dihedral "
                           "angle\n\n"
                        << table;
  std::cout << table;
}

}  // namespace
}  // namespace sflsh::meshing
