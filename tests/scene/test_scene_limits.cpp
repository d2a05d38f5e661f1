// Bad scene input refused before anything runs: motion offsets beyond the bound (and a motion sampled for the
// frames asked only), shapes without their size, invalid .obj obstacles, runaway work estimates, shape models
// whose [basis] does not fit the crowd. Every message names the file and the field.
#include "error_of.hpp"
#include "scratch_dir.hpp"

#include <sflsh/body/motion.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/meshing/region.hpp>
#include <sflsh/reduced/shape_model_file.hpp>
#include <sflsh/scene/obstacle.hpp>
#include <sflsh/scene/scene_file.hpp>
#include <sflsh/scene/scene_runner.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <regex>

namespace sflsh::scene {
namespace {

using sflsh::testing::error_of;
using ::testing::HasSubstr;

std::filesystem::path write(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

constexpr const char* kHeader = "[scene]\nfps = 30\nframes = 2\n";

TEST(SceneLimits, MotionOffsetIsBoundedAndNamed) {
  const auto dir = testing::scratch_dir();
  const auto path =
      write(dir / "scene.toml",
            std::string(kHeader) + "[[body]]\nmotion = \"dance\"\nsolver = \"skinned\"\nmotion_offset = 1e9\n");
  const std::string message = error_of([&] { load_scene(path); });
  EXPECT_THAT(message, HasSubstr("scene.toml:7: motion_offset in body #0: 1e+09 s is outside [0, 3600] s")) << message;
  const auto crowd = write(dir / "crowd.toml", std::string(kHeader) + "[crowd]\ncount = 2\nmax_offset = -1.0\n");
  EXPECT_THAT(error_of([&] { load_scene(crowd); }),
              HasSubstr("crowd.toml:6: max_offset in [crowd]: -1 s is outside [0, 3600] s"));
}

TEST(SceneLimits, AProceduralWindowIsTheTailOfTheWholeMotionAndCostsOnlyItsFrames) {
  const body::Motion whole = body::make_procedural_motion("dance", 30.0, 105);
  const body::Motion tail = body::procedural_motion_window("dance", 30.0, 100, 5);
  ASSERT_EQ(tail.num_frames(), 5u);
  for (std::size_t f = 0; f < 5; ++f) {
    EXPECT_EQ(tail.poses[f], whole.poses[100 + f]) << f;  // sample for sample, bit for bit
    EXPECT_EQ(tail.trans[f], whole.trans[100 + f]) << f;
  }
  // An hour in (the bound of motion_offset) at 10000 fps: two frames, at once.
  const auto t0 = std::chrono::steady_clock::now();
  const body::Motion far = body::procedural_motion_window("running_on_spot", 10000.0, 3600LL * 10000, 2);
  EXPECT_EQ(far.num_frames(), 2u);
  EXPECT_LT(sflsh::seconds_since(t0), 1.0);
}

TEST(SceneLimits, EveryShapeNeedsItsSize) {
  const auto dir = testing::scratch_dir();
  const std::string body = "[[body]]\nmotion = \"rest\"\n";
  struct Case {
    std::string object;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"[[object]]\nshape = \"box\"\n", "scene.toml:6: half_extents in object #0: missing (a box needs it)"},
      {"[[object]]\nshape = \"capsule\"\nradius = 0.1\n",
       "scene.toml:6: length in object #0: missing (a capsule needs it)"},
      {"[[object]]\nshape = \"sphere\"\n", "scene.toml:6: radius in object #0: missing (a sphere needs it)"},
      {"[[object]]\nshape = \"plane\"\n", "scene.toml:6: normal in object #0: missing (a plane needs it)"},
  };
  for (const Case& c : cases) {
    const auto path = write(dir / "scene.toml", std::string(kHeader) + body + c.object);
    EXPECT_THAT(error_of([&] { load_scene(path); }), HasSubstr(c.expected)) << c.object;
  }
}

TEST(SceneLimits, ObjObstaclesWithBadIndicesOrNonFiniteVerticesAreRefused) {
  const auto dir = testing::scratch_dir();
  const std::string tet = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  EXPECT_NO_THROW(TriangleMesh::load(write(dir / "tet.obj", tet)));
  const std::string beyond = error_of([&] { TriangleMesh::load(write(dir / "beyond.obj", tet + "f 2 3 9\n")); });
  EXPECT_THAT(beyond, HasSubstr("beyond.obj:9: f: vertex index 9 is outside the file's 4 vertices")) << beyond;
  const std::string nan = error_of([&] { TriangleMesh::load(write(dir / "nan.obj", "v nan 0 0\n" + tet)); });
  EXPECT_THAT(nan, HasSubstr("nan.obj:1: v: coordinate 1 is 'nan', expected a finite number")) << nan;
  const std::string far = error_of([&] { TriangleMesh::load(write(dir / "far.obj", tet + "v 0 1e12 0\n")); });
  EXPECT_THAT(far, HasSubstr("far.obj:9: v: coordinate 2 is 1e12, expected a number in [-1e6, 1e6]")) << far;
  std::filesystem::create_directories(dir / "mesh_dir.obj");
  const auto scene = write(
      dir / "scene.toml",
      std::string(kHeader) + "[[body]]\nmotion = \"rest\"\n[[object]]\nshape = \"mesh\"\nfile = \"mesh_dir.obj\"\n");
  EXPECT_THAT(error_of([&] { load_scene(scene); }),
              HasSubstr("scene.toml:8: file in object #0: " + (dir / "mesh_dir.obj").string() + ": is a directory"));
}

TEST(SceneLimits, RunawayWorkIsRefusedBeforeAnythingIsBuilt) {
  const auto dir = testing::scratch_dir();
  const auto path = write(dir / "crowd.toml",
                          "[scene]\nfps = 30\nduration = 2.0\n[effects]\ninertia = true\n[crowd]\ncount = 100000\n");
  const Scene scene = load_scene(path);
  SceneRunOptions options;
  options.cache_dir = SFLSH_TEST_CACHE;
  const WorkEstimate e = estimate_scene_work(scene, options);
  EXPECT_EQ(e.bodies, 100000.0);
  EXPECT_EQ(e.steps, 100000.0 * 60.0);
  const auto t0 = std::chrono::steady_clock::now();
  const std::string message = error_of([&] { run_scene(scene, options); });
  EXPECT_LT(sflsh::seconds_since(t0), 1.0);
  EXPECT_THAT(message, HasSubstr("crowd.toml: [scene] duration")) << message;
  EXPECT_THAT(message, HasSubstr("([crowd] count at line 6)")) << message;
  EXPECT_THAT(message, HasSubstr("exceed the limit")) << message;
  EXPECT_THAT(message, HasSubstr("pass --allow-long to run it anyway")) << message;
  // The shipped scenes are all within the limits.
  for (const char* name : {"belly_press", "two_bodies_push", "crowd", "skinning_only"}) {
    const Scene shipped = load_scene(std::filesystem::path(SFLSH_DATA_DIR) / "scenes" / (std::string(name) + ".toml"));
    EXPECT_NO_THROW(check_work(estimate_scene_work(shipped, {}), WorkLimits{}, false, name)) << name;
  }
}

TEST(SceneLimits, ShapeModelBasisMustBeKnownAndFitTheCrowd) {
  const auto dir = testing::scratch_dir();
  std::ifstream in(std::filesystem::path(SFLSH_DATA_DIR) / "shape_models" / "default.toml");
  const std::string shipped((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const reduced::ShapeModelFile ok = reduced::load_shape_model_file(write(dir / "ok.toml", shipped));
  const std::string crowd_region = meshing::region_key(meshing::default_region_names());
  EXPECT_NO_THROW(reduced::check_layer_match(ok, crowd_region, "coarse", "the [crowd]"));

  const std::string ultra = error_of([&] {
    reduced::load_shape_model_file(
        write(dir / "ultra.toml", std::regex_replace(shipped, std::regex("mesh = 'coarse'"), "mesh = 'ultra'")));
  });
  EXPECT_THAT(ultra, HasSubstr("ultra.toml:"));
  EXPECT_THAT(ultra, HasSubstr(": mesh in [basis]: 'ultra' is not a mesh preset")) << ultra;
  const std::string belly = error_of([&] {
    reduced::load_shape_model_file(
        write(dir / "belly.toml", std::regex_replace(shipped, std::regex("region = '[a-z_+]*'"), "region = 'belly'")));
  });
  EXPECT_THAT(belly, HasSubstr(": region in [basis]: 'belly' is not a layer region")) << belly;

  const auto torso_path =
      write(dir / "torso.toml", std::regex_replace(shipped, std::regex("region = '[a-z_+]*'"), "region = 'torso'"));
  const reduced::ShapeModelFile torso = reduced::load_shape_model_file(torso_path);
  const std::string mismatch =
      error_of([&] { reduced::check_layer_match(torso, crowd_region, "coarse", "the [crowd]"); });
  EXPECT_THAT(mismatch, HasSubstr(torso_path.string() + ":")) << mismatch;
  EXPECT_THAT(
      mismatch,
      HasSubstr(
          "region in [basis]: the shape model was fitted on region 'torso', but the [crowd] uses layers of region "
          "'thighs+torso+upper_arms'"))
      << mismatch;
  EXPECT_THAT(
      error_of([&] { reduced::check_layer_match(ok, crowd_region, "fine", "the [crowd]"); }),
      HasSubstr(
          "mesh in [basis]: the shape model was fitted on the 'coarse' mesh, but the [crowd] uses the 'fine' mesh"));
}

}  // namespace
}  // namespace sflsh::scene
