// The two tet-meshing backends on a layer-like shell: watertight, positively oriented, good tets that
// fill the shell and sit on its surface; clear errors for bad input.
#include "shell_fixture.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/meshing/quality.hpp>
#include <sflsh/meshing/tet_backend.hpp>

#include <error_of.hpp>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>

namespace sflsh {

using meshing::Mesher;
using sflsh::testing::error_of;
using sflsh::testing::Shell;
using sflsh::testing::spherical_shell;
using ::testing::HasSubstr;

namespace {

// Hemispherical shell between 0.15 m and 0.10 m (5 cm thick, like a thick part of the layer), outer
// edges 2 cm; meshed at edge 1.8 cm: about 3 tets through the thickness and ~5k tets.
const Shell& test_shell() {
  static const Shell shell = spherical_shell(0.15, 0.10, 0.02);
  return shell;
}

meshing::SizeControl test_size() {
  meshing::SizeControl size;
  size.edge_length = 0.018;
  size.surface_distance = 0.0018;
  size.threads = 2;
  return size;
}

/// The tet mesh of the test shell per backend, meshed once per test process.
const meshing::TetMesh& shell_mesh(Mesher mesher) {
  static std::map<Mesher, meshing::TetMesh> meshes;
  auto it = meshes.find(mesher);
  if (it == meshes.end())
    it = meshes.emplace(mesher, meshing::tetrahedralize(test_shell().surface, mesher, test_size())).first;
  return it->second;
}

struct BoundarySurface {
  std::vector<std::array<int, 3>> faces;
  int faces_used_more_than_twice = 0;
};

// Faces of the tets used by exactly one tet.
BoundarySurface boundary_surface(const meshing::RowMatrixX4i& tets) {
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::map<std::array<int, 3>, std::pair<int, std::array<int, 3>>> faces;
  for (Eigen::Index e = 0; e < tets.rows(); ++e)
    for (const auto& f : kFace) {
      const std::array<int, 3> face{tets(e, f[0]), tets(e, f[1]), tets(e, f[2])};
      std::array<int, 3> key = face;
      std::sort(key.begin(), key.end());
      auto& entry = faces[key];
      ++entry.first;
      entry.second = face;
    }
  BoundarySurface out;
  for (const auto& [key, entry] : faces) {
    if (entry.first == 1) out.faces.push_back(entry.second);
    if (entry.first > 2) ++out.faces_used_more_than_twice;
  }
  return out;
}

class Backend : public ::testing::TestWithParam<Mesher> {};

std::string backend_name(const ::testing::TestParamInfo<Mesher>& info) { return meshing::mesher_name(info.param); }

}  // namespace

TEST(MesherNames, ParseAndNameRoundTrip) {
  EXPECT_EQ(meshing::parse_mesher("cgal"), Mesher::cgal);
  EXPECT_EQ(meshing::parse_mesher("gmsh"), Mesher::gmsh);
  EXPECT_STREQ(meshing::mesher_name(Mesher::cgal), "cgal");
  EXPECT_STREQ(meshing::mesher_name(Mesher::gmsh), "gmsh");
  EXPECT_THAT(error_of([] { meshing::parse_mesher("tetgen"); }), HasSubstr("'tetgen'"));
}

TEST(SizeForTargetTets, EdgeScalesWithTheCubeRootOfVolumePerTet) {
  const auto base = meshing::size_for_target_tets(0.04, 50'000, Mesher::cgal, 3);
  EXPECT_GT(base.edge_length, 0.0);
  EXPECT_NEAR(base.surface_distance, 0.1 * base.edge_length, 1e-15);
  EXPECT_EQ(base.threads, 3);
  EXPECT_NEAR(meshing::size_for_target_tets(0.04, 400'000, Mesher::cgal, 3).edge_length, base.edge_length / 2, 1e-12);
  EXPECT_NEAR(meshing::size_for_target_tets(0.32, 50'000, Mesher::cgal, 3).edge_length, base.edge_length * 2, 1e-12);
  EXPECT_THAT(error_of([] { meshing::size_for_target_tets(0.0, 10, Mesher::gmsh, 2); }), HasSubstr("volume"));
  EXPECT_THAT(error_of([] { meshing::size_for_target_tets(1.0, 0, Mesher::gmsh, 2); }), HasSubstr("tet count"));
}

TEST(ShellFixture, IsAClosedLayerWithTheAnalyticVolume) {
  const Shell& shell = test_shell();
  // Enclosed volume of the polyhedral shell: inscribed in the smooth one, so slightly smaller.
  double volume = 0.0;
  const auto& s = shell.surface;
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t)
    volume += s.vertices.row(s.triangles(t, 0))
                  .dot(s.vertices.row(s.triangles(t, 1)).cross(s.vertices.row(s.triangles(t, 2)))) /
              6.0;
  EXPECT_LT(volume, shell.volume);
  EXPECT_GT(volume, 0.98 * shell.volume);
  EXPECT_EQ(s.features.size(), 2u);
  EXPECT_EQ(s.patch.size(), static_cast<std::size_t>(s.triangles.rows()));
}

TEST_P(Backend, MeshIsWatertightWithTheBoundaryOfABall) {
  const meshing::TetMesh& mesh = shell_mesh(GetParam());
  const BoundarySurface boundary = boundary_surface(mesh.tets);
  EXPECT_EQ(boundary.faces_used_more_than_twice, 0);
  // Every boundary edge is shared by exactly two boundary faces, in opposite directions.
  std::map<std::pair<int, int>, int> directed;
  std::set<int> vertices;
  for (const auto& f : boundary.faces)
    for (int k = 0; k < 3; ++k) {
      ++directed[{f[k], f[(k + 1) % 3]}];
      vertices.insert(f[k]);
    }
  int unpaired = 0;
  for (const auto& [edge, uses] : directed)
    if (uses != 1 || directed.count({edge.second, edge.first}) != 1) ++unpaired;
  EXPECT_EQ(unpaired, 0);
  // Euler characteristic V − E + F = 2: one closed surface of genus 0 (the shell is a thick disc).
  const long edges = static_cast<long>(directed.size()) / 2;
  EXPECT_EQ(static_cast<long>(vertices.size()) - edges + static_cast<long>(boundary.faces.size()), 2);
}

TEST_P(Backend, TetsArePositiveAndWellShaped) {
  const meshing::TetMesh& mesh = shell_mesh(GetParam());
  const meshing::QualityReport q = meshing::quality_report(mesh.nodes, mesh.tets);
  RecordProperty("tets", std::to_string(q.tets));
  RecordProperty("min_dihedral_deg", std::to_string(q.min_dihedral_deg));
  RecordProperty("max_radius_edge", std::to_string(q.max_radius_edge));
  EXPECT_GT(q.tets, 2'000);
  EXPECT_LT(q.tets, 20'000);
  EXPECT_EQ(q.inverted, 0);
  EXPECT_EQ(q.degenerate, 0);
  EXPECT_GT(q.min_volume, 0.0);
  // Thresholds: after exudation (CGAL) or gmsh's optimizer, slivers are gone. Both measured here well
  // above 5° min dihedral; 5° leaves margin for platform rounding while still catching a
  // missing sliver removal step (without it, CGAL's min dihedral is below 1°). The median of a good
  // Delaunay mesh is near the regular tet's 70.5°.
  EXPECT_GT(q.min_dihedral_deg, 5.0);
  EXPECT_LT(q.max_dihedral_deg, 175.0);
  EXPECT_NEAR(q.median_dihedral_deg, 70.5, 8.0);
  EXPECT_LT(q.max_radius_edge, 10.0);
  // Every node is used by a tet.
  std::vector<char> used(static_cast<std::size_t>(mesh.nodes.rows()), 0);
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e)
    for (int k = 0; k < 4; ++k) used[static_cast<std::size_t>(mesh.tets(e, k))] = 1;
  EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0);
  EXPECT_EQ(mesh.input_vertex.size(), static_cast<std::size_t>(mesh.nodes.rows()));
}

TEST_P(Backend, TetsFillTheShell) {
  const meshing::TetMesh& mesh = shell_mesh(GetParam());
  const double volume = meshing::quality_report(mesh.nodes, mesh.tets).total_volume;
  // The input is a polyhedral approximation (inscribed, ~1% below the analytic volume); CGAL
  // resamples it within surface_distance.
  EXPECT_NEAR(volume / test_shell().volume, 1.0, 0.03);
}

TEST_P(Backend, BoundaryNodesLieOnTheInputSurface) {
  const meshing::TetMesh& mesh = shell_mesh(GetParam());
  const meshing::BoundaryLocation location = meshing::locate_boundary_nodes(mesh, test_shell().surface);
  ASSERT_EQ(location.triangle.size(), static_cast<std::size_t>(mesh.nodes.rows()));
  EXPECT_LE(location.max_distance, test_size().surface_distance);
  int boundary = 0, interior = 0;
  double worst = 0.0;
  const auto& s = test_shell().surface;
  for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i) {
    const int t = location.triangle[static_cast<std::size_t>(i)];
    if (t < 0) {
      ++interior;
      continue;
    }
    ++boundary;
    const Eigen::Vector3d& b = location.bary[static_cast<std::size_t>(i)];
    EXPECT_NEAR(b.sum(), 1.0, 1e-12);
    EXPECT_GE(b.minCoeff(), 0.0);
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) p += b(k) * s.vertices.row(s.triangles(t, k)).transpose();
    worst = std::max(worst, (p - mesh.nodes.row(i).transpose()).norm());
  }
  EXPECT_LE(worst, test_size().surface_distance);
  EXPECT_GT(boundary, 0);
  EXPECT_GT(interior, 0);
  // Interior nodes are strictly inside: a node on a boundary face of the mesh is never one.
  const BoundarySurface faces = boundary_surface(mesh.tets);
  for (const auto& f : faces.faces)
    for (int v : f) EXPECT_GE(location.triangle[static_cast<std::size_t>(v)], 0);
}

INSTANTIATE_TEST_SUITE_P(Meshers, Backend, ::testing::Values(Mesher::cgal, Mesher::gmsh), backend_name);

TEST(CgalBackend, ResamplesTheSurface) {
  const meshing::TetMesh& mesh = shell_mesh(Mesher::cgal);
  EXPECT_TRUE(std::all_of(mesh.input_vertex.begin(), mesh.input_vertex.end(), [](int v) { return v == -1; }));
}

TEST(GmshBackend, KeepsEveryInputVertexOnce) {
  const meshing::TetMesh& mesh = shell_mesh(Mesher::gmsh);
  const auto& s = test_shell().surface;
  std::vector<int> seen(static_cast<std::size_t>(s.vertices.rows()), 0);
  for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i) {
    const int v = mesh.input_vertex[static_cast<std::size_t>(i)];
    if (v < 0) continue;
    ASSERT_LT(v, s.vertices.rows());
    ++seen[static_cast<std::size_t>(v)];
    EXPECT_EQ(mesh.nodes.row(i), s.vertices.row(v)) << "node " << i << " of input vertex " << v;
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), s.vertices.rows());
}

// Disabled: a known defect. Two 1→4 subdivisions put 16 coplanar points on each input facet, and gmsh
// then leaves flat boundary slivers (3 of 2 770 tets, min dihedral 0°) that its optimizer does not remove;
// the backend reports them as an error instead of returning them. The body layer's fine preset (curved
// facets, one subdivision) meshes cleanly (bench_meshing: 112 k tets, min dihedral 2.9°).
TEST(GmshBackend, DISABLED_SubdividesACoarseInputAndStillKeepsItsVertices) {
  // Outer edges 4.5 cm for a requested edge of 1.5 cm: two 1→4 subdivisions bring the surface to the
  // volume's resolution; the original vertices keep their indices.
  const Shell coarse = spherical_shell(0.15, 0.10, 0.045, std::numbers::pi / 3, 2);
  meshing::SizeControl size;
  size.edge_length = 0.015;
  size.surface_distance = 0.0015;
  const meshing::TetMesh mesh = meshing::tetrahedralize(coarse.surface, Mesher::gmsh, size);
  const auto& s = coarse.surface;
  std::vector<int> seen(static_cast<std::size_t>(s.vertices.rows()), 0);
  int added = 0;
  for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i) {
    const int v = mesh.input_vertex[static_cast<std::size_t>(i)];
    if (v < 0) {
      ++added;
      continue;
    }
    ++seen[static_cast<std::size_t>(v)];
    EXPECT_EQ(mesh.nodes.row(i), s.vertices.row(v));
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), s.vertices.rows());
  // Boundary nodes: 16× the input triangles after two subdivisions ⇒ about 16× the input vertices.
  const meshing::BoundaryLocation location = meshing::locate_boundary_nodes(mesh, s);
  const auto boundary_nodes =
      std::count_if(location.triangle.begin(), location.triangle.end(), [](int t) { return t >= 0; });
  EXPECT_GT(boundary_nodes, 10 * s.vertices.rows());
  EXPECT_LE(location.max_distance, 1e-9);
  const meshing::QualityReport q = meshing::quality_report(mesh.nodes, mesh.tets);
  EXPECT_TRUE(q.valid());
  EXPECT_GT(q.min_dihedral_deg, 5.0);
}

TEST_P(Backend, RejectsAnEmptySurface) {
  const std::string message = error_of([&] { meshing::tetrahedralize({}, GetParam(), test_size()); });
  EXPECT_THAT(message, HasSubstr(meshing::mesher_name(GetParam())));
  EXPECT_THAT(message, HasSubstr("empty"));
}

TEST_P(Backend, RejectsAnOpenSurface) {
  meshing::ClosedSurface open = test_shell().surface;
  open.triangles.conservativeResize(open.triangles.rows() - 1, 3);  // drop the last side triangle
  open.patch.pop_back();
  const std::string message = error_of([&] { meshing::tetrahedralize(open, GetParam(), test_size()); });
  EXPECT_THAT(message, HasSubstr(meshing::mesher_name(GetParam())));
  EXPECT_THAT(message, HasSubstr("open"));
}

TEST_P(Backend, RejectsAnInconsistentlyOrientedSurface) {
  meshing::ClosedSurface flipped = test_shell().surface;
  flipped.triangles.row(0) = flipped.triangles.row(0).reverse().eval();
  EXPECT_THAT(error_of([&] { meshing::tetrahedralize(flipped, GetParam(), test_size()); }), HasSubstr("oriented"));
}

// Calibration sweep behind size_for_target_tets (run with --gtest_also_run_disabled_tests): meshes
// body-like shells at the coarse/default/fine tet counts and prints time, quality and the calibration
// factor tets · a³ / (6√2 · volume) that would have hit the target exactly.
TEST(SizeCalibration, DISABLED_PresetsOnLayerLikeShells) {
  struct Shape {
    const char* name;
    double outer, inner, surface_edge;
  };
  const Shape shapes[] = {{"R0.30 t4cm e2.5cm", 0.30, 0.26, 0.025}, {"R0.15 t5cm e2cm", 0.15, 0.10, 0.02}};
  std::printf("%-20s %-5s %8s %7s %8s %8s %7s %6s %6s %6s %7s %7s %6s\n", "shape", "mesh", "target", "edge mm", "tets",
              "nodes", "time s", "min°", "med°", "max°", "max r/e", "vol err", "calib");
  const char* only = std::getenv("SWEEP");  // TEMP: "shape,mesher,target" filter while calibrating
  for (const Shape& shape : shapes)
    for (Mesher mesher : {Mesher::cgal, Mesher::gmsh})
      for (long target : {10'000L, 50'000L, 200'000L}) {
        if (only && std::string(only).find(std::string(shape.name).substr(0, 5) + "," + meshing::mesher_name(mesher) +
                                           "," + std::to_string(target)) == std::string::npos)
          continue;
        Shell shell = spherical_shell(shape.outer, shape.inner, shape.surface_edge);
        double volume = 0.0;
        const auto& s0 = shell.surface;
        for (Eigen::Index t = 0; t < s0.triangles.rows(); ++t)
          volume += s0.vertices.row(s0.triangles(t, 0))
                        .dot(s0.vertices.row(s0.triangles(t, 1)).cross(s0.vertices.row(s0.triangles(t, 2)))) /
                    6.0;
        const meshing::SizeControl size = meshing::size_for_target_tets(volume, target, mesher, 2);
        // Side rows as build_layer_surface chooses them: side edges about the target edge.
        const int side_layers = std::max(1, static_cast<int>(std::ceil(shell.thickness / size.edge_length - 0.25)));
        shell = spherical_shell(shape.outer, shape.inner, shape.surface_edge, std::numbers::pi / 2, side_layers);
        const auto start = std::chrono::steady_clock::now();
        meshing::TetMesh mesh;
        try {
          mesh = meshing::tetrahedralize(shell.surface, mesher, size);
        } catch (const Error& e) {
          std::printf("%-20s %-5s %8ld failed: %s\n", shape.name, meshing::mesher_name(mesher), target, e.what());
          continue;
        }
        const double seconds = sflsh::seconds_since(start);
        const meshing::QualityReport q = meshing::quality_report(mesh.nodes, mesh.tets);
        const double a = size.edge_length;
        double edge_sum = 0.0;
        for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e)
          for (int i = 0; i < 4; ++i)
            for (int j = i + 1; j < 4; ++j)
              edge_sum += (mesh.nodes.row(mesh.tets(e, i)) - mesh.nodes.row(mesh.tets(e, j))).norm();
        {  // TEMP diagnostic: boundary nodes of the worst tets
          const auto per = meshing::tet_quality(mesh.nodes, mesh.tets);
          const auto loc = meshing::locate_boundary_nodes(mesh, shell.surface);
          int hist[5] = {0, 0, 0, 0, 0};
          for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) {
            if (per.min_dihedral_deg(e) > 5.0) continue;
            int b = 0;
            for (int k = 0; k < 4; ++k) b += loc.triangle[static_cast<std::size_t>(mesh.tets(e, k))] >= 0;
            ++hist[b];
          }
          std::printf("  tets < 5deg by boundary nodes: %d %d %d %d %d\n", hist[0], hist[1], hist[2], hist[3], hist[4]);
        }
        std::printf("  mean tet edge / a = %.3f\n", edge_sum / (6.0 * static_cast<double>(mesh.tets.rows())) / a);
        std::printf("%-20s %-5s %8ld %7.1f %8ld %8ld %7.2f %6.2f %6.1f %6.1f %7.2f %6.2f%% %6.3f\n", shape.name,
                    meshing::mesher_name(mesher), target, 1e3 * a, q.tets, q.nodes, seconds, q.min_dihedral_deg,
                    q.median_dihedral_deg, q.max_dihedral_deg, q.max_radius_edge,
                    100.0 * (q.total_volume / volume - 1.0),
                    static_cast<double>(q.tets) * a * a * a / (6.0 * std::numbers::sqrt2 * volume));
        std::fflush(stdout);
      }
}

}  // namespace sflsh
