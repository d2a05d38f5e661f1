// Bodies that cannot touch each other step in parallel: a scene with body contact where two bodies push
// together and a third dances far away gives, grouped and on two threads, exactly the frames of one
// step of all bodies as one group on one thread.
#include "scratch_dir.hpp"

#include <sflsh/core/vtk_io.hpp>
#include <sflsh/scene/scene_file.hpp>
#include <sflsh/scene/scene_runner.hpp>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fstream>

namespace sflsh::scene {
namespace {

TEST(SceneParallel, UncoupledGroupsInParallelEqualTheSerialSweep) {
  const auto dir = testing::scratch_dir();
  const auto path = dir / "scene.toml";
  std::ofstream(path) << R"([scene]
fps = 30
frames = 8
[effects]
inertia = true
body_contact = true
[[body]]
name = "standing"
motion = "rest"
mesh = "coarse"
handles = 30
[[body]]
name = "dancer"
motion = "shake_hips"
mesh = "coarse"
handles = 30
placement = { position = [3.0, 0.0, 0.0] }
[[body]]
name = "pushing"
motion = "rest"
mesh = "coarse"
handles = 30
placement = { position = [0.0, 0.0, -0.30], yaw = 180.0 }
approach = [{ t = 0.0, position = [0.0, 0.0, 0.0] }, { t = 0.2, position = [0.0, 0.0, -0.10] }]
)";
  const Scene scene = load_scene(path);
  auto run = [&](const std::string& name, bool grouped, int threads) {
    SceneRunOptions options;
    options.cache_dir = SFLSH_TEST_CACHE;
    options.out = dir / name;
    options.threads = threads;
    options.group_bodies = grouped;
    return run_scene(scene, options);
  };
  const nlohmann::json serial = run("serial", false, 1);
  const nlohmann::json parallel = run("parallel", true, 2);
  EXPECT_DOUBLE_EQ(serial["body_groups_per_step"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(parallel["body_groups_per_step"].get<double>(), 2.0);  // {standing, pushing}, {dancer}
  for (std::size_t b = 0; b < 3; ++b) {
    const std::string name = serial["bodies"][b]["name"];
    SCOPED_TRACE(name);
    EXPECT_EQ(serial["bodies"][b]["newton_iterations"], parallel["bodies"][b]["newton_iterations"]);
    EXPECT_EQ(serial["bodies"][b]["contact"]["bodies"]["narrow_phase_evaluations"],
              parallel["bodies"][b]["contact"]["bodies"]["narrow_phase_evaluations"]);
    EXPECT_EQ(serial["bodies"][b]["dynamics"]["sigma_max_mm"], parallel["bodies"][b]["dynamics"]["sigma_max_mm"]);
    for (int f = 0; f < 8; ++f) {
      const std::string file = fmt::format("{}_{:06d}.vtp", name, f);
      EXPECT_EQ(vtk::read_points(dir / "serial" / file), vtk::read_points(dir / "parallel" / file)) << file;
      EXPECT_EQ(vtk::read_point_array(dir / "serial" / file, "elastic_displacement"),
                vtk::read_point_array(dir / "parallel" / file, "elastic_displacement"))
          << file;
    }
  }
  // The pair did touch, and the dancer moved on its own.
  EXPECT_GT(serial["bodies"][0]["contact"]["bodies"]["narrow_phase_evaluations"].get<long>(), 0);
  EXPECT_GT(serial["bodies"][1]["dynamics"]["sigma_max_mm"].get<double>(), 0.1);
}

}  // namespace
}  // namespace sflsh::scene
