// Rigid motions: keyframe interpolation (holds, keys, C¹ Catmull–Rom) and a free object under gravity.
#include <sflsh/core/error.hpp>
#include <sflsh/scene/rigid_motion.hpp>

#include <gtest/gtest.h>

#include <numbers>

namespace sflsh::scene {
namespace {

std::vector<Keyframe> three_keys() {
  Keyframe a, b, c;
  a.t = 0.0;
  a.position = {0.0, 0.0, 0.0};
  b.t = 0.5;
  b.position = {0.1, 0.2, 0.0};
  b.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * std::numbers::pi, Eigen::Vector3d::UnitZ()));
  c.t = 1.5;
  c.position = {0.3, 0.0, -0.1};
  c.rotation = b.rotation;
  return {a, b, c};
}

TEST(KeyframeMotion, PassesThroughKeysAndHoldsOutside) {
  for (auto interpolation : {KeyframeInterpolation::linear, KeyframeInterpolation::catmull_rom}) {
    const KeyframeMotion motion(three_keys(), interpolation);
    for (const Keyframe& k : motion.keys()) {
      EXPECT_LT((motion.pose(k.t).translation - k.position).norm(), 1e-14);
      EXPECT_LT((motion.pose(k.t).rotation - k.rotation.toRotationMatrix()).norm(), 1e-14);
    }
    EXPECT_LT((motion.pose(-3.0).translation - motion.keys().front().position).norm(), 1e-15);
    EXPECT_LT((motion.pose(9.0).translation - motion.keys().back().position).norm(), 1e-15);
    EXPECT_EQ(motion.velocity(-1.0).norm(), 0.0);
    EXPECT_EQ(motion.velocity(2.0).norm(), 0.0);
    // Half way between keys 1 and 2 the rotation is the same (equal keys): slerp keeps it.
    EXPECT_LT((motion.pose(1.0).rotation - motion.keys()[1].rotation.toRotationMatrix()).norm(), 1e-12);
  }
  const KeyframeMotion linear(three_keys(), KeyframeInterpolation::linear);
  EXPECT_LT((linear.pose(0.25).translation - Eigen::Vector3d(0.05, 0.1, 0.0)).norm(), 1e-15);
}

// Catmull–Rom: velocity() is the derivative of the position (central differences, h = 1e-6 s: error
// ~ h²|x'''| ≲ 1e-10 m/s), continuous at the inner key and zero at the ends (C¹ into the holds).
TEST(KeyframeMotion, CatmullRomIsC1) {
  const KeyframeMotion motion(three_keys(), KeyframeInterpolation::catmull_rom);
  const double h = 1e-6;
  for (double t : {0.1, 0.3, 0.7, 1.2}) {
    const Eigen::Vector3d fd = (motion.pose(t + h).translation - motion.pose(t - h).translation) / (2 * h);
    EXPECT_LT((motion.velocity(t) - fd).norm(), 1e-7) << t;
  }
  EXPECT_LT((motion.velocity(0.5 - 1e-9) - motion.velocity(0.5 + 1e-9)).norm(), 1e-6);
  EXPECT_LT(motion.velocity(1e-9).norm(), 1e-6);
  EXPECT_LT(motion.velocity(1.5 - 1e-9).norm(), 1e-6);
  // The inner tangent is (x2 − x0)/(t2 − t0).
  EXPECT_LT((motion.velocity(0.5) - Eigen::Vector3d(0.2, 0.0, -0.0666666666666667)).norm(), 1e-9);
}

TEST(KeyframeMotion, BadKeysThrow) {
  EXPECT_THROW(KeyframeMotion(std::vector<Keyframe>{}), Error);
  auto keys = three_keys();
  keys[2].t = 0.5;
  EXPECT_THROW(KeyframeMotion{keys}, Error);
}

// Symplectic Euler in free fall: x_n = x0 + v0 t + g dt² n(n+1)/2 exactly, and the pose asked for the
// end of a substep is the one commit() then reaches (so a refined substep sees the same object).
TEST(FreeMotion, FallsUnderGravityAndReactsToTheCommittedForce) {
  const Eigen::Vector3d g(0.0, 0.0, -9.81);
  Pose start;
  start.translation = {0.0, 0.0, 1.0};
  FreeMotion motion(2.0, g, start, Eigen::Vector3d(0.1, 0.0, 0.0));
  const double dt = 0.01;
  for (int n = 1; n <= 10; ++n) {
    const Pose predicted = motion.pose(n * dt);
    EXPECT_LT((motion.pose(n * dt).translation - predicted.translation).norm(), 0.0 + 1e-15);
    motion.commit(n * dt, Eigen::Vector3d::Zero());
    EXPECT_LT((motion.position() - predicted.translation).norm(), 1e-15);
  }
  const Eigen::Vector3d expected = start.translation + Eigen::Vector3d(0.1, 0.0, 0.0) * 0.1 + g * dt * dt * 55.0;
  EXPECT_LT((motion.position() - expected).norm(), 1e-12);
  // A committed upward force of m|g| stops the acceleration from the next step on.
  motion.commit(0.1, Eigen::Vector3d(0.0, 0.0, 2.0 * 9.81));
  const Eigen::Vector3d v = motion.velocity();
  motion.commit(0.11, Eigen::Vector3d(0.0, 0.0, 2.0 * 9.81));
  EXPECT_LT((motion.velocity() - v).norm(), 1e-12);
  EXPECT_THROW(FreeMotion(0.0, g, start, Eigen::Vector3d::Zero()), Error);
}

}  // namespace
}  // namespace sflsh::scene
