// Scenes end to end: effects on demand (nothing built that is not asked for, idle bodies not solved, an
// inactive effect changes nothing), a ball pressed into the belly stops at the skin, two bodies pushed
// together do not interpenetrate. Coarse layers, 30 handles, short clips.
#include "scene_files.hpp"
#include "scratch_dir.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/skinning.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/scene/obstacle.hpp>
#include <sflsh/scene/scene_file.hpp>
#include <sflsh/scene/scene_runner.hpp>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fstream>

namespace sflsh::scene {
namespace {

nlohmann::json run(const std::filesystem::path& dir, const std::string& text, bool write = false) {
  return testing::run_scene_text(dir, text, write);
}

const nlohmann::json* effect(const nlohmann::json& summary, const std::string& name) {
  for (const auto& e : summary["effects"])
    if (e["name"] == name) return &e;
  return nullptr;
}

// The belly's front on the open body's mean shape is near (0, 0.064, 0.119) m.
std::string ball_scene(const std::string& solver, const std::string& effects, double press_to_z, int frames) {
  return fmt::format(R"([scene]
fps = 60
frames = {3}
[effects]
{1}
[[body]]
name = "b"
motion = "rest"
solver = "{0}"
mesh = "coarse"
handles = 30
[[object]]
name = "ball"
shape = "sphere"
radius = 0.06
motion = "prescribed"
smooth = false
keyframes = [{{ t = 0.0, position = [0.0, 0.064, 0.19] }}, {{ t = {4}, position = [0.0, 0.064, {2}] }}]
)",
                     solver, effects, press_to_z, frames, (frames - 1) / 60.0);
}

TEST(SceneRun, NothingIsBuiltForEffectsThatAreOff) {
  const auto dir = testing::scratch_dir();
  // No elastic effect: the body is only skinned (no layer), the object is only drawn.
  const nlohmann::json skinned = run(dir, ball_scene("reduced", "", 0.15, 4));
  EXPECT_EQ(skinned["built"]["soft_layers"], 0);
  EXPECT_EQ(skinned["built"]["contact_potentials"], 0);
  EXPECT_EQ(skinned["bodies"][0]["solver"], "skinned");
  ASSERT_EQ(skinned["effects"].size(), 1u);
  EXPECT_EQ(skinned["effects"][0]["name"], "skinning");
  // Inertia without contact: a soft layer, but no contact potential and no proximity query ever.
  const nlohmann::json dynamic = run(dir, ball_scene("reduced", "inertia = true", 0.15, 4));
  EXPECT_EQ(dynamic["built"]["soft_layers"], 1);
  EXPECT_EQ(dynamic["built"]["contact_potentials"], 0);
  EXPECT_EQ(dynamic["built"]["broad_phase_passes"], 0);
  EXPECT_EQ(dynamic["built"]["narrow_phase_evaluations"], 0);
  EXPECT_EQ(effect(dynamic, "object_contact"), nullptr);
  EXPECT_NE(effect(dynamic, "inertia"), nullptr);
  EXPECT_FALSE(dynamic.contains("contact"));
}

TEST(SceneRun, InactiveContactChangesNothingAndIdleBodiesAreNotSolved) {
  const auto dir = testing::scratch_dir();
  // The ball stays 7 cm in front of the belly: with object contact on, the broad phase finds no candidate.
  const std::string far = ball_scene("reduced", "inertia = true\nobject_contact = true", 0.19, 6);
  const std::string off = ball_scene("reduced", "inertia = true", 0.19, 6);
  const nlohmann::json with = run(dir / "with", far, true);
  const nlohmann::json without = run(dir / "without", off, true);
  EXPECT_EQ(with["built"]["contact_potentials"], 1);
  EXPECT_GT(with["built"]["broad_phase_passes"], 0);
  EXPECT_EQ(with["built"]["narrow_phase_evaluations"], 0);  // far away: never evaluated
  const auto a = vtk::read_points(dir / "with" / "out" / "b_000005.vtp");
  const auto b = vtk::read_points(dir / "without" / "out" / "b_000005.vtp");
  EXPECT_EQ((a - b).cwiseAbs().maxCoeff(), 0.0);  // the same arithmetic: no term was added
  // Quasi-static without gravity and no contact in reach: at rest, no solve, the skinned surface.
  const nlohmann::json idle = run(dir / "idle", ball_scene("reduced", "object_contact = true", 0.19, 6), true);
  EXPECT_EQ(idle["bodies"][0]["idle_steps"], 5);
  EXPECT_EQ(idle["bodies"][0]["newton_iterations"], 0);
  const nlohmann::json skin = run(dir / "skin", ball_scene("reduced", "", 0.19, 6), true);
  const auto c = vtk::read_points(dir / "idle" / "out" / "b_000005.vtp");
  const auto d = vtk::read_points(dir / "skin" / "out" / "b_000005.vtp");
  EXPECT_LT((c - d).cwiseAbs().maxCoeff(), 1e-9);  // posing through the layer equals plain skinning (rounding)
}

// The ball ends 2.4 cm inside the rest surface; the skin must stay within the 1 mm tolerance of it.
void check_press(const std::string& solver, int frames) {
  const auto dir = testing::scratch_dir();
  const nlohmann::json s = run(dir, ball_scene(solver, "inertia = true\nobject_contact = true", 0.155, frames));
  // Without the contact the ball would sit this deep in the skin: the test would see it.
  const body::BodyModel model = body::load_body(body::default_body_path());
  Sphere ball(0.06);
  ball.set_pose({Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.0, 0.064, 0.155)});
  double depth = 0.0;
  for (Eigen::Index v = 0; v < model.v_template.rows(); ++v)
    depth = std::max(depth, -ball.distance(model.v_template.row(v).transpose()));
  EXPECT_GT(depth, 0.02);
  // 1 mm is the scene's tolerance (the default): the potential re-solves a substep that ends deeper.
  EXPECT_LE(s["contact"]["measured_max_penetration_mm"].get<double>(), 1.0 + 1e-9);
  EXPECT_GT(s["bodies"][0]["contact"]["objects"]["narrow_phase_evaluations"].get<long>(), 0);
  // The tissue moved: a ≥ 1 cm dent somewhere.
  EXPECT_GT(s["bodies"][0]["dynamics"]["sigma_max_mm"].get<double>(), 3.0);
  EXPECT_NE(effect(s, "object_contact"), nullptr);
}

TEST(SceneRun, BallPressedIntoTheBellyStopsAtTheSkinReduced) { check_press("reduced", 13); }

TEST(SceneRun, BallPressedIntoTheBellyStopsAtTheSkinFullSpace) { check_press("full", 9); }

TEST(SceneRun, TwoBodiesPushedTogetherDoNotInterpenetrate) {
  const auto dir = testing::scratch_dir();
  // Back to back, 8 cm apart at rest, the second body moves 10 cm towards the first in 0.3 s.
  const nlohmann::json s = run(dir, R"([scene]
fps = 30
frames = 10
[effects]
inertia = true
body_contact = true
[[body]]
name = "standing"
motion = "rest"
mesh = "coarse"
handles = 30
[[body]]
name = "pushing"
motion = "rest"
mesh = "coarse"
handles = 30
placement = { position = [0.0, 0.0, -0.30], yaw = 180.0 }
approach = [{ t = 0.0, position = [0.0, 0.0, 0.0] }, { t = 0.3, position = [0.0, 0.0, -0.10] }]
)");
  EXPECT_EQ(s["built"]["contact_potentials"], 2);
  for (const auto& b : s["bodies"]) {
    SCOPED_TRACE(b["name"].get<std::string>());
    EXPECT_GT(b["contact"]["bodies"]["narrow_phase_evaluations"].get<long>(), 0);  // they did touch
    EXPECT_LE(b["contact"]["measured_max_penetration_mm"].get<double>(), 1.0 + 1e-9);
    EXPECT_GT(b["dynamics"]["sigma_max_mm"].get<double>(), 1.0);  // both soft layers gave way
  }
  EXPECT_EQ(s["contact"]["skeleton_response"], false);
}

}  // namespace
}  // namespace sflsh::scene
