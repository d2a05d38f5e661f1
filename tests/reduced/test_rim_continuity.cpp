// No artifacts at the rim (issue 18): the soft-tissue displacement vanishes on the region's boundary curves
// (the skin's rim is attached like the side wall), and neither solver stretches the skin against the plainly
// posed body by more than the tissue itself does — at the rim and around every point handle, where a handle
// on a free rim or one the cubature did not see once produced a 61 mm, 4× kink at the right elbow.
#include "open_body.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/reduced/reduced_model.hpp>
#include <sflsh/reduced/reduced_solver.hpp>

#include <gtest/gtest.h>
#include <petscsys.h>

#include <filesystem>
#include <set>

namespace sflsh::reduced {
namespace {

using sflsh::testing::open_body;

model::BodyLayer coarse_layer(const body::Motion& motion) {
  model::BodyLayerOptions options;
  options.size = meshing::SizePreset::coarse;
  options.cache_dir = SFLSH_TEST_CACHE;
  return model::build_body_layer(open_body(), body::Betas::Zero(), motion, nullptr, 6, options);
}

/// Body-mesh edges (a < b) watched: those touching a rim vertex, and those within two rings of the skin
/// vertex over each point handle.
struct WatchedEdges {
  std::vector<int> rim_vertices;  ///< body vertex indices on the region's boundary curves
  std::vector<std::pair<int, int>> rim, handles;
};

WatchedEdges watched_edges(const model::BodyLayer& layer, const BodyHandles& handles) {
  const meshing::LayerMesh& mesh = *layer.mesh;
  const body::BodyModel& body = *layer.model;
  std::set<std::pair<int, int>> all;
  for (Eigen::Index f = 0; f < body.faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = body.faces(f, k), b = body.faces(f, (k + 1) % 3);
      all.emplace(std::min(a, b), std::max(a, b));
    }
  std::vector<std::vector<int>> neighbours(static_cast<std::size_t>(body.num_vertices()));
  for (const auto& [a, b] : all) {
    neighbours[static_cast<std::size_t>(a)].push_back(b);
    neighbours[static_cast<std::size_t>(b)].push_back(a);
  }
  WatchedEdges out;
  std::vector<char> on_rim(static_cast<std::size_t>(body.num_vertices()), 0);
  for (const auto& loop : mesh.region_surface.boundary_loops)
    for (int r : loop) {
      const int v = mesh.region_surface.vertices[static_cast<std::size_t>(r)];
      on_rim[static_cast<std::size_t>(v)] = 1;
      out.rim_vertices.push_back(v);
    }
  // Two rings around the skin vertex nearest each handle node (template positions).
  const meshing::RowMatrixX3d skin = mesh.skin_positions(mesh.nodes);
  std::vector<char> near_handle(static_cast<std::size_t>(body.num_vertices()), 0);
  for (int node : handles.point_nodes) {
    Eigen::Index nearest = 0;
    (skin.rowwise() - mesh.nodes.row(node)).rowwise().squaredNorm().minCoeff(&nearest);
    const int v = mesh.region_surface.vertices[static_cast<std::size_t>(nearest)];
    near_handle[static_cast<std::size_t>(v)] = 1;
    for (int w : neighbours[static_cast<std::size_t>(v)]) near_handle[static_cast<std::size_t>(w)] = 1;
  }
  for (const auto& edge : all) {
    if (on_rim[static_cast<std::size_t>(edge.first)] || on_rim[static_cast<std::size_t>(edge.second)])
      out.rim.push_back(edge);
    if (near_handle[static_cast<std::size_t>(edge.first)] || near_handle[static_cast<std::size_t>(edge.second)])
      out.handles.push_back(edge);
  }
  return out;
}

/// The worst over the frames seen: rim vertex distance to the plainly posed body, and edge stretch
/// s = |x_a − x_b| / |x̄_a − x̄_b| (x simulated, x̄ plainly posed) on the watched edges.
struct Worst {
  double rim_displacement = 0.0;
  double rim_low = 1.0, rim_high = 1.0, handle_low = 1.0, handle_high = 1.0;

  void add(const model::BodyLayer& layer, const WatchedEdges& edges, const Eigen::VectorXd& x, double t) {
    const model::RowMatrixX3d simulated = layer.posed_surface(x, t);
    const model::RowMatrixX3d plain = layer.posed_surface_from_displacement(
        model::RowMatrixX3d::Zero(layer.mesh->region_surface.num_vertices(), 3), t);
    for (int v : edges.rim_vertices)
      rim_displacement = std::max(rim_displacement, (simulated.row(v) - plain.row(v)).norm());
    const auto stretch = [&](const std::pair<int, int>& e) {
      return (simulated.row(e.first) - simulated.row(e.second)).norm() /
             (plain.row(e.first) - plain.row(e.second)).norm();
    };
    for (const auto& e : edges.rim) {
      rim_low = std::min(rim_low, stretch(e));
      rim_high = std::max(rim_high, stretch(e));
    }
    for (const auto& e : edges.handles) {
      handle_low = std::min(handle_low, stretch(e));
      handle_high = std::max(handle_high, stretch(e));
    }
  }
};

TEST(RimContinuity, TheSkinsRimIsAttachedOnEveryBoundaryCurve) {
  const body::Motion motion = body::make_procedural_motion("jiggle_on_toes", 60.0, 2);
  const model::BodyLayer layer = coarse_layer(motion);
  const meshing::LayerMesh& mesh = *layer.mesh;
  const std::vector<int> rim = mesh.rim_nodes();
  const std::vector<char> attached = layer.problem.dirichlet.mask(mesh.num_nodes());
  for (int i : rim) {
    EXPECT_EQ(mesh.kind[static_cast<std::size_t>(i)], meshing::NodeKind::outer);
    EXPECT_TRUE(attached[static_cast<std::size_t>(3 * i)] && attached[static_cast<std::size_t>(3 * i + 1)] &&
                attached[static_cast<std::size_t>(3 * i + 2)]);
  }
  // Every vertex of every boundary curve has a rim node at its skin position (the layered mesher keeps them).
  const meshing::RowMatrixX3d skin = mesh.skin_positions(mesh.nodes);
  std::size_t loop_vertices = 0;
  for (const auto& loop : mesh.region_surface.boundary_loops)
    for (int r : loop) {
      ++loop_vertices;
      double nearest = 1e9;
      for (int i : rim) nearest = std::min(nearest, (mesh.nodes.row(i) - skin.row(r)).norm());
      EXPECT_LT(nearest, 1e-9) << "boundary vertex " << r;
    }
  EXPECT_EQ(rim.size(), loop_vertices);
}

TEST(RimContinuity, ReducedCacheKeyFollowsTheAttachedNodes) {
  // Attaching more nodes changes the bone handles and where every basis function vanishes: a cached subspace
  // of the old attachment must not be loaded.
  const body::Motion motion = body::make_procedural_motion("jiggle_on_toes", 60.0, 2);
  model::BodyLayer layer = coarse_layer(motion);
  const std::filesystem::path dir = std::filesystem::path(SFLSH_TEST_CACHE) / "reduced-attachment-test";
  std::filesystem::remove_all(dir);
  ReducedModelOptions ro;
  ro.point_handles = 24;
  ro.cubature = 60;
  ro.cache_dir = dir;
  const ReducedModel first = build_reduced_model(layer, ro);
  EXPECT_EQ(first.cache_outcome, "built");
  EXPECT_EQ(build_reduced_model(layer, ro).cache_outcome, "hit");
  const std::vector<char> attached = layer.problem.dirichlet.mask(layer.problem.num_nodes());
  int free_node = 0;
  while (attached[static_cast<std::size_t>(3 * free_node)]) ++free_node;
  layer.problem.dirichlet.add(free_node, 0b111u);
  const ReducedModel second = build_reduced_model(layer, ro);
  EXPECT_EQ(second.cache_outcome, "built");
  EXPECT_NE(second.cache_key, first.cache_key);
  std::filesystem::remove_all(dir);
}

// Tolerances. The full-space reference stretches the skin near the rim by ≤ 3% on these frames (measured
// 0.97–1.03); a free rim gave 0.84–1.18 by frame 10 (a collar line at the neck, 0.42–1.54 later). The
// reduced model (86 handles, 200 cubature tets) is coarser: ≤ 10% at the rim and ≤ 25% anywhere on the layer
// over 2 s of this motion (measured); the artifacts were 0.31–4.2× at the right elbow. Bounds: 10% (full
// space), 35% (reduced); the rim itself must not move at all (round-off of the posing arithmetic, 1e-9 m).

TEST(RimContinuity, ReducedModelHasNoKinkAtTheRimOrAtAnyHandle) {
  const body::Motion motion = body::make_procedural_motion("jiggle_on_toes", 60.0, 24);
  const model::BodyLayer layer = coarse_layer(motion);
  ReducedModelOptions ro;
  ro.cache_dir = SFLSH_TEST_CACHE;
  const ReducedModel m = build_reduced_model(layer, ro);
  const WatchedEdges edges = watched_edges(layer, m.handles);
  ReducedSolver solver(layer.problem, m.subspace, m.cubature);
  solver.initialize(model::initial_state(layer.problem, 0.0));
  Worst worst;
  for (std::size_t f = 1; f < motion.num_frames(); ++f) {
    solver.step(1.0 / 60.0);
    worst.add(layer, edges, solver.full_state().x, motion.time(f));
  }
  EXPECT_LT(worst.rim_displacement, 1e-9);
  EXPECT_GT(worst.rim_low, 0.65);
  EXPECT_LT(worst.rim_high, 1.35);
  EXPECT_GT(worst.handle_low, 0.65);
  EXPECT_LT(worst.handle_high, 1.35);
  std::printf("reduced: rim %.2e m, rim stretch [%.3f, %.3f], handle stretch [%.3f, %.3f]\n", worst.rim_displacement,
              worst.rim_low, worst.rim_high, worst.handle_low, worst.handle_high);
}

TEST(RimContinuity, FullSpaceHasNoCollarAtTheRim) {
  const body::Motion motion = body::make_procedural_motion("jiggle_on_toes", 60.0, 11);
  const model::BodyLayer layer = coarse_layer(motion);
  const WatchedEdges edges = watched_edges(layer, place_body_handles(layer, 86));
  fullspace::FullSpaceSolver solver(layer.problem, PETSC_COMM_WORLD);
  solver.initialize(model::initial_state(layer.problem, 0.0));
  Worst worst;
  for (std::size_t f = 1; f < motion.num_frames(); ++f) {
    solver.step(1.0 / 60.0);
    worst.add(layer, edges, solver.state().x, motion.time(f));
  }
  EXPECT_LT(worst.rim_displacement, 1e-9);
  EXPECT_GT(worst.rim_low, 0.90);
  EXPECT_LT(worst.rim_high, 1.10);
  EXPECT_GT(worst.handle_low, 0.90);
  EXPECT_LT(worst.handle_high, 1.10);
  std::printf("full space: rim %.2e m, rim stretch [%.3f, %.3f], handle stretch [%.3f, %.3f]\n", worst.rim_displacement,
              worst.rim_low, worst.rim_high, worst.handle_low, worst.handle_high);
}

}  // namespace
}  // namespace sflsh::reduced
