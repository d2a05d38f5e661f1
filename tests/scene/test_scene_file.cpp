// Scene files: the shipped examples parse, bad input is one error naming the file and line.
#include "scene_files.hpp"
#include "scratch_dir.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/scene/scene_file.hpp>

#include <gtest/gtest.h>

#include <fstream>

namespace sflsh::scene {
namespace {

using sflsh::testing::load_error;
using sflsh::testing::write_scene;

constexpr const char* kBody = "[[body]]\nname = \"a\"\nmotion = \"rest\"\n";

TEST(SceneFile, ShippedScenesParse) {
  for (const char* name :
       {"belly_press", "thigh_press", "arm_press", "two_bodies_push", "crowd", "skinning_only", "push_sway"}) {
    SCOPED_TRACE(name);
    const Scene scene = load_scene(std::filesystem::path(SFLSH_DATA_DIR) / "scenes" / (std::string(name) + ".toml"));
    EXPECT_EQ(scene.name, name);
    EXPECT_GT(scene.num_frames(), 1);
  }
  const Scene belly = load_scene(std::filesystem::path(SFLSH_DATA_DIR) / "scenes" / "belly_press.toml");
  EXPECT_TRUE(belly.effects.inertia && belly.effects.object_contact && !belly.effects.gravity &&
              !belly.effects.body_contact);
  ASSERT_EQ(belly.objects.size(), 1u);
  EXPECT_EQ(belly.objects[0].shape, ShapeKind::sphere);
  EXPECT_EQ(belly.objects[0].motion, ObjectMotionKind::prescribed);
  EXPECT_EQ(belly.objects[0].keyframes.size(), 4u);
  EXPECT_EQ(belly.num_frames(), 61);
  const Scene skin = load_scene(std::filesystem::path(SFLSH_DATA_DIR) / "scenes" / "skinning_only.toml");
  EXPECT_FALSE(skin.effects.elastic());
  EXPECT_DOUBLE_EQ(skin.bodies[1].placement.yaw_degrees, -30.0);
  const Scene crowd = load_scene(std::filesystem::path(SFLSH_DATA_DIR) / "scenes" / "crowd.toml");
  ASSERT_TRUE(crowd.crowd.has_value());
  EXPECT_EQ(crowd.crowd->count, 25);
  // Touching bodies exchange surfaces by default; the one-sweep coupling stays available by name.
  const Scene push = load_scene(std::filesystem::path(SFLSH_DATA_DIR) / "scenes" / "two_bodies_push.toml");
  EXPECT_TRUE(push.contact.body_exchange);
  const auto sweep = write_scene(testing::scratch_dir(),
                                 "[scene]\n[effects]\nbody_contact = true\n[contact]\nbody_exchange = false\n" +
                                     std::string(kBody) + "[[body]]\nname = \"b\"\nmotion = \"rest\"\n");
  EXPECT_FALSE(load_scene(sweep).contact.body_exchange);
}

TEST(SceneFile, BadInputNamesFileAndLine) {
  const auto dir = testing::scratch_dir();
  struct Case {
    std::string text;
    std::string expected;  // a part of the message
  };
  const std::vector<Case> cases = {
      {"[scene]\nfps = 60\n[effects]\ninertia = true\nwobble = true\n" + std::string(kBody),
       "scene.toml:5: unknown key 'wobble'"},
      {"[scene]\nfps = -1\n" + std::string(kBody), "scene.toml:2: 'fps' in [scene] = -1 must be positive"},
      {"[scene]\n[effects]\nobject_contact = true\n" + std::string(kBody),
       "'object_contact' is on but the scene has no [[object]]"},
      {"[scene]\n[effects]\nbody_contact = true\n" + std::string(kBody), "fewer than two bodies"},
      {"[scene]\n[effects]\nself_contact = true\n" + std::string(kBody),
       "scene.toml:3: 'self_contact' = true is not available"},
      {"[scene]\n" + std::string(kBody) + "solver = \"fast\"\n",
       "scene.toml:5: 'solver' in body #0 = 'fast' is not one of full | reduced | skinned"},
      {"[scene]\n" + std::string(kBody) + "material = \"nope.toml\"\n",
       "nope.toml: not found, expected a material TOML file"},
      {"[scene]\n" + std::string(kBody) + "integrator = \"rk4\"\n",
       "scene.toml:5: 'integrator' in body #0 = 'rk4' is not one of backward_euler | bdf2 | newmark"},
      {"[scene]\n" + std::string(kBody) + "mass = \"diagonal\"\n",
       "scene.toml:5: 'mass' in body #0 = 'diagonal' is not one of lumped | consistent"},
      {"[scene]\n" + std::string(kBody) + "[[object]]\nshape = \"sphere\"\nradius = -0.1\n",
       "scene.toml:7: 'radius' in object #0 = -0.1 must be in [0.0001, 100] m"},
      // Plausibility before solving: sizes, positions and speeds within their ranges (docs/scenes.md).
      {"[scene]\n" + std::string(kBody) + "[[object]]\nshape = \"sphere\"\nradius = 1e9\n",
       "scene.toml:7: 'radius' in object #0 = 1000000000 must be in [0.0001, 100] m"},
      {"[scene]\n" + std::string(kBody) + "[[object]]\nshape = \"box\"\nhalf_extents = [0.1, 0.1, 500.0]\n",
       "scene.toml:7: 'half_extents' in object #0 = [0.1, 0.1, 500] must have components in [0.0001, 100] m"},
      {"[scene]\n" + std::string(kBody) + "[[object]]\nshape = \"sphere\"\nradius = 0.1\nposition = [0, 1e12, 0]\n",
       "scene.toml:8: 'position' in object #0 = [0, 1000000000000, 0] must have components in [-1000, 1000] m"},
      {"[scene]\n" + std::string(kBody) +
           "[[object]]\nshape = \"sphere\"\nradius = 0.1\nmotion = \"free\"\nvelocity = [0, 0, -3e8]\n",
       "scene.toml:9: 'velocity' in object #0 = [0, 0, -300000000] must have components in [-100, 100] m/s"},
      {"[scene]\n" + std::string(kBody) +
           "[[object]]\nshape = \"sphere\"\nradius = 0.1\nmotion = \"free\"\nmass = 1e9\n",
       "scene.toml:9: 'mass' in object #0 = 1000000000 must be in [1e-06, 10000] kg"},
      {"[scene]\n" + std::string(kBody) + "[[object]]\nshape = \"box\"\nradius = 0.1\n",
       "'radius' in object #0 does not apply to a box"},
      {"[scene]\n" + std::string(kBody) +
           "[[object]]\nshape = \"sphere\"\nradius = 0.1\nmotion = \"prescribed\"\nkeyframes = [{ t = 0.5, position = "
           "[0, 0, 0] }, { t = 0.2, position = [0, 0, 1] }]\n",
       "keyframe times in 'keyframes' in object #0 must increase"},
      {"[scene]\n" + std::string(kBody) + "[[object]]\nshape = \"sphere\"\nradius = 0.1\nmotion = \"prescribed\"\n",
       "a prescribed object needs 'keyframes'"},
      {"[scene]\n[effects]\nobject_contact = true\n[crowd]\ncount = 4\n[[object]]\nshape = \"sphere\"\nradius = 0.1\n",
       "a [crowd] runs without contact"},
      {"[scene]\n" + std::string(kBody) + "[[body]]\nname = \"a\"\n", "the name 'a' is used twice"},
      {"[scene]\nfps = \n", "scene.toml:2:"},
      {"[effects]\n" + std::string(kBody), "missing key 'scene'"},
      {"[scene]\n[effects]\ninertia = true\n" + std::string(kBody) + "skeleton = \"loose\"\n",
       "scene.toml:7: 'skeleton' in body #0 = 'loose' is not one of prescribed | tracking"},
      {"[scene]\n[effects]\ninertia = true\n" + std::string(kBody) + "skeleton = \"tracking\"\nsolver = \"full\"\n",
       "scene.toml:7: skeleton = \"tracking\" in body #0 needs solver = \"reduced\" (the full-space solver keeps "
       "prescribed bones)"},
      {"[scene]\n[effects]\ninertia = true\n" + std::string(kBody) + "tracking_stiffness = 500.0\n",
       "scene.toml:7: 'tracking_stiffness' in body #0 needs skeleton = \"tracking\""},
      {"[scene]\n[effects]\ninertia = true\n" + std::string(kBody) + "skeleton = \"tracking\"\nroot = \"loose\"\n",
       "scene.toml:8: 'root' in body #0 = 'loose' is not one of tracked | free"},
      {"[scene]\n[effects]\ninertia = true\n" + std::string(kBody) +
           "skeleton = \"tracking\"\ntracking_stiffness = -1.0\n",
       "scene.toml:8: tracking_stiffness in body #0: -1 N/m is outside"},
      {"[scene]\n[effects]\ninertia = true\n" + std::string(kBody) +
           "skeleton = \"tracking\"\nintegrator = \"newmark\"\n",
       "needs integrator = \"backward_euler\""},
      {"[scene]\n" + std::string(kBody) + "skeleton = \"tracking\"\n",
       "body 'a' has skeleton = \"tracking\", which needs [effects] inertia = true"},
      {"[scene]\n[effects]\ninertia = true\n" + std::string(kBody) + "tracked_joints = \"all\"\n",
       "scene.toml:7: 'tracked_joints' in body #0 needs skeleton = \"tracking\""},
      {"[scene]\n[effects]\ninertia = true\n" + std::string(kBody) +
           "skeleton = \"tracking\"\ntracked_joints = \"some\"\n",
       "scene.toml:8: 'tracked_joints' in body #0 = 'some' is not one of all | root"},
      {"[scene]\n[effects]\ninertia = true\n" + std::string(kBody) +
           "skeleton = \"tracking\"\ntracked_joints = [\"spine1\", \"tail\"]\n",
       "scene.toml:8: 'tracked_joints' in body #0: 'tail' is not a joint below the root"},
      {"[scene]\n[effects]\ninertia = true\n" + std::string(kBody) +
           "skeleton = \"tracking\"\ntracked_joints = [\"pelvis\"]\n",
       "'pelvis' is not a joint below the root"},
      {"[scene]\n[effects]\ninertia = true\n" + std::string(kBody) +
           "skeleton = \"tracking\"\njoint_stiffness = { left_knee = 10.0, nose = 5.0 }\n",
       "scene.toml:8: 'joint_stiffness' in body #0: 'nose' is not a joint below the root"},
      {"[scene]\n[effects]\ninertia = true\n" + std::string(kBody) + "skeleton = \"tracking\"\njoint_damping = 5.0\n",
       "scene.toml:8: 'joint_damping' in body #0 must be a table { joint_name = value, … }"},
      {"[scene]\n[effects]\ninertia = true\n" + std::string(kBody) +
           "skeleton = \"tracking\"\njoint_limits = { spine1 = 4.0 }\n",
       "joint_limits in body #0: 4 rad is outside"},
      {"[scene]\n[effects]\ninertia = true\n" + std::string(kBody) + "skeleton = \"tracking\"\njoint_frequency = 0\n",
       "joint_frequency in body #0: 0 Hz is outside"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    const std::string message = load_error(write_scene(dir, c.text));
    EXPECT_NE(message.find(c.expected), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "one line: " << message;
  }
  EXPECT_NE(load_error(dir / "missing.toml").find("missing.toml: not found, expected a scene TOML file"),
            std::string::npos);
}

// Every key of docs/scenes.md's [contact] table is read (local_max_nodes was documented but refused as unknown).
TEST(SceneFile, TheLocalContactKeysAreRead) {
  const auto scene = load_scene(write_scene(testing::scratch_dir(),
                                            "[scene]\n[effects]\ninertia = true\n[contact]\nlocal_resolution = false\n"
                                            "local_spacing = 0.015\nlocal_depth = 0.03\nlocal_reach = 0.004\n"
                                            "local_free_objects = true\nlocal_max_nodes = 250\n" +
                                                std::string(kBody)));
  EXPECT_FALSE(scene.contact.local_resolution);
  EXPECT_DOUBLE_EQ(scene.contact.local_spacing, 0.015);
  EXPECT_DOUBLE_EQ(scene.contact.local_depth, 0.03);
  EXPECT_DOUBLE_EQ(scene.contact.local_reach, 0.004);
  EXPECT_TRUE(scene.contact.local_free_objects);
  EXPECT_EQ(scene.contact.local_max_nodes, 250);
}

TEST(SceneFile, TrackedJointsAndTheirSprings) {
  const auto dir = testing::scratch_dir();
  const auto all = load_scene(
      write_scene(dir, "[scene]\n[effects]\ninertia = true\n" + std::string(kBody) + "skeleton = \"tracking\"\n"));
  EXPECT_TRUE(all.bodies[0].all_joints);  // the default: every joint carrying the layer
  EXPECT_DOUBLE_EQ(all.bodies[0].joint_frequency, 2.0);
  const auto root = load_scene(write_scene(dir, "[scene]\n[effects]\ninertia = true\n" + std::string(kBody) +
                                                    "skeleton = \"tracking\"\ntracked_joints = \"root\"\n"));
  EXPECT_FALSE(root.bodies[0].all_joints);
  EXPECT_TRUE(root.bodies[0].tracked_joints.empty());
  const auto named = load_scene(write_scene(
      dir, "[scene]\n[effects]\ninertia = true\n" + std::string(kBody) +
               "skeleton = \"tracking\"\ntracked_joints = [\"spine1\", \"left_hip\"]\njoint_frequency = 3.0\n"
               "joint_damping_ratio = 0.5\njoint_limit = 0.3\njoint_stiffness = { spine1 = 80.0 }\n"
               "joint_damping = { left_hip = 4.0 }\njoint_limits = { spine1 = 0.2 }\n"));
  const BodySpec& b = named.bodies[0];
  EXPECT_FALSE(b.all_joints);
  EXPECT_EQ(b.tracked_joints, (std::vector<std::string>{"spine1", "left_hip"}));
  EXPECT_DOUBLE_EQ(b.joint_frequency, 3.0);
  EXPECT_DOUBLE_EQ(b.joint_damping_ratio, 0.5);
  EXPECT_DOUBLE_EQ(b.joint_limit, 0.3);
  EXPECT_DOUBLE_EQ(b.joint_stiffness.at("spine1"), 80.0);
  EXPECT_DOUBLE_EQ(b.joint_damping.at("left_hip"), 4.0);
  EXPECT_DOUBLE_EQ(b.joint_limits.at("spine1"), 0.2);
}

TEST(SceneFile, IntegratorAndMassPerBodyAndCrowd) {
  const auto dir = testing::scratch_dir();
  const Scene scene = load_scene(write_scene(
      dir, "[scene]\n" + std::string(kBody) +
               "integrator = \"newmark\"\nmass = \"consistent\"\n[[body]]\nname = \"b\"\nmotion = \"rest\"\n"));
  ASSERT_EQ(scene.bodies.size(), 2u);
  EXPECT_EQ(scene.bodies[0].integrator, model::Integrator::newmark);
  EXPECT_EQ(scene.bodies[0].mass, model::MassKind::consistent);
  EXPECT_EQ(scene.bodies[1].integrator, model::Integrator::bdf2);  // the defaults (model::kDefaultIntegrator)
  EXPECT_EQ(scene.bodies[1].mass, model::MassKind::consistent);
  // A tracking skeleton is solved with the paper's pair only: a body naming neither takes it.
  const Scene tracking = load_scene(write_scene(dir, "[scene]\n[effects]\ninertia = true\n" + std::string(kBody) +
                                                         "solver = \"reduced\"\nskeleton = \"tracking\"\n"));
  EXPECT_EQ(tracking.bodies[0].integrator, model::Integrator::backward_euler);
  EXPECT_EQ(tracking.bodies[0].mass, model::MassKind::lumped);
  const Scene crowd =
      load_scene(write_scene(dir, "[scene]\n[crowd]\ncount = 2\nintegrator = \"bdf2\"\nmass = \"consistent\"\n"));
  ASSERT_TRUE(crowd.crowd.has_value());
  EXPECT_EQ(crowd.crowd->integrator, model::Integrator::bdf2);
  EXPECT_EQ(crowd.crowd->mass, model::MassKind::consistent);
}

TEST(SceneFile, RelativePathsAreTakenFromTheSceneFolder) {
  const auto dir = testing::scratch_dir();
  std::filesystem::create_directories(dir / "meshes");
  std::ofstream(dir / "meshes" / "ball.obj") << "v 0 0 0\n";
  const Scene scene = load_scene(write_scene(
      dir, "[scene]\n" + std::string(kBody) + "[[object]]\nshape = \"mesh\"\nfile = \"meshes/ball.obj\"\n"));
  EXPECT_EQ(std::filesystem::path(scene.objects[0].mesh_path), (dir / "meshes" / "ball.obj").lexically_normal());
}

}  // namespace
}  // namespace sflsh::scene
