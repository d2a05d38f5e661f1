// The on-disk cache of template layers: hit, stale detection, forced rebuild, corrupt files.
#include "error_of.hpp"
#include "layer_fixture.hpp"
#include "scratch_dir.hpp"

#include <sflsh/core/npz.hpp>

#include <gmock/gmock.h>

#include <fstream>

namespace sflsh {

using sflsh::testing::error_of;
using sflsh::testing::open_body;
using ::testing::HasSubstr;

namespace {

meshing::LayerMeshOptions thigh_options() {
  meshing::LayerMeshOptions options;
  options.region_names = {"left_thigh"};  // a small region and the extruded mesh keep these tests quick
  options.mesher = meshing::Mesher::layered;
  options.size = meshing::SizePreset::coarse;
  return options;
}

}  // namespace

TEST(LayerCache, BuildsOnceThenHitsWithIdenticalArrays) {
  const auto dir = sflsh::testing::scratch_dir();
  meshing::CacheOutcome outcome{};
  const auto built = meshing::cached_layer_mesh(open_body(), thigh_options(), dir, false, &outcome);
  EXPECT_EQ(outcome, meshing::CacheOutcome::built);
  const auto loaded = meshing::cached_layer_mesh(open_body(), thigh_options(), dir, false, &outcome);
  EXPECT_EQ(outcome, meshing::CacheOutcome::hit);
  EXPECT_EQ(loaded.nodes, built.nodes);
  EXPECT_EQ(loaded.tets, built.tets);
  EXPECT_EQ(loaded.kind, built.kind);
  EXPECT_EQ(loaded.skin.node, built.skin.node);
  EXPECT_EQ(loaded.region_surface.boundary_loops, built.region_surface.boundary_loops);
  EXPECT_EQ(loaded.correspondence.joint_weights.toDense(), built.correspondence.joint_weights.toDense());
  for (std::size_t i = 0; i < built.anchor.size(); ++i) {
    EXPECT_EQ(loaded.anchor[i].vertex, built.anchor[i].vertex);
    EXPECT_EQ(loaded.anchor[i].depth, built.anchor[i].depth);
  }
  meshing::cached_layer_mesh(open_body(), thigh_options(), dir, true, &outcome);
  EXPECT_EQ(outcome, meshing::CacheOutcome::rebuilt_forced);
}

TEST(LayerCache, ChangedBodyModelMakesTheEntryStale) {
  const auto dir = sflsh::testing::scratch_dir();
  meshing::cached_layer_mesh(open_body(), thigh_options(), dir);
  body::BodyModel changed = open_body();  // same name, same file name in the cache, new content
  changed.v_template *= 1.01;
  EXPECT_NE(meshing::body_fingerprint(changed), meshing::body_fingerprint(open_body()));
  meshing::CacheOutcome outcome{};
  const auto mesh = meshing::cached_layer_mesh(changed, thigh_options(), dir, false, &outcome);
  EXPECT_EQ(outcome, meshing::CacheOutcome::rebuilt_stale);
  std::string key;
  meshing::load_layer_mesh(meshing::layer_cache_path(dir, changed, thigh_options()), &key);
  EXPECT_EQ(key, meshing::layer_cache_key(changed, thigh_options()));
  EXPECT_EQ(mesh.num_nodes(), mesh.nodes.rows());
}

TEST(LayerCache, CorruptEntriesGiveAClearError) {
  const auto dir = sflsh::testing::scratch_dir();
  const auto path = meshing::layer_cache_path(dir, open_body(), thigh_options());
  std::filesystem::create_directories(dir);
  { std::ofstream(path) << "not a zip archive"; }
  const std::string garbage = error_of([&] { meshing::cached_layer_mesh(open_body(), thigh_options(), dir); });
  EXPECT_THAT(garbage, HasSubstr(path.string()));
  EXPECT_THAT(garbage, HasSubstr("--rebuild-cache"));

  // A valid archive that lacks an array names the array.
  npz::write(path, {{"key", npz::make_string(meshing::layer_cache_key(open_body(), thigh_options()))},
                    {"body_name", npz::make_string("x")}});
  EXPECT_THAT(error_of([&] { meshing::cached_layer_mesh(open_body(), thigh_options(), dir); }), HasSubstr("'region'"));

  // --rebuild-cache replaces the corrupt entry.
  meshing::CacheOutcome outcome{};
  meshing::cached_layer_mesh(open_body(), thigh_options(), dir, true, &outcome);
  EXPECT_EQ(outcome, meshing::CacheOutcome::rebuilt_forced);
  EXPECT_NO_THROW(meshing::load_layer_mesh(path));
}

TEST(LayerCache, KeyNamesEverythingTheMeshDependsOn) {
  auto options = thigh_options();
  const std::string key = meshing::layer_cache_key(open_body(), options);
  options.mesher = meshing::Mesher::gmsh;
  EXPECT_NE(meshing::layer_cache_key(open_body(), options), key);
  options = thigh_options();
  options.size = meshing::SizePreset::fine;
  EXPECT_NE(meshing::layer_cache_key(open_body(), options), key);
  options = thigh_options();
  options.region_names = {"torso"};
  EXPECT_NE(meshing::layer_cache_key(open_body(), options), key);
  options = thigh_options();
  options.template_thickness = 0.4;
  EXPECT_NE(meshing::layer_cache_key(open_body(), options), key);
}

}  // namespace sflsh
