// The dance showcase motion (validity, periodicity, C¹ smoothness, joint ranges, planted feet) and
// time-offset motions (offset_motion, make_procedural_motion / load_motion with a time offset).
#include "../../body/src/motion/rig.hpp"
#include "angles.hpp"

#include <sflsh/body/body_model.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/body/skinning.hpp>
#include <sflsh/core/error.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace sflsh::body {
namespace {

namespace md = motion_detail;
using sflsh::testing::kDeg;

double max_abs_difference(const Motion& a, std::size_t fa, const Motion& b, std::size_t fb) {
  return std::max((a.poses[fa] - b.poses[fb]).cwiseAbs().maxCoeff(), (a.trans[fa] - b.trans[fb]).cwiseAbs().maxCoeff());
}

/// Rest joints [m] whose legs are the nominal leg of the procedural motions (as test_motion.cpp's
/// synthetic skeleton), so that planted feet can be checked exactly.
JointPositions nominal_skeleton() {
  JointPositions j = JointPositions::Zero();
  const double hx = md::NominalLeg::hip_offset_x;
  j.row(md::kPelvis) << 0, 1.0, 0;
  j.row(md::kLeftHip) << hx, 0.91, 0;
  j.row(md::kRightHip) << -hx, 0.91, 0;
  j.row(md::kLeftKnee) << hx, 0.49, 0;
  j.row(md::kRightKnee) << -hx, 0.49, 0;
  j.row(md::kLeftAnkle) << hx, 0.07, 0;
  j.row(md::kRightAnkle) << -hx, 0.07, 0;
  j.row(md::kLeftFoot) << hx, 0.0, 0.14;
  j.row(md::kRightFoot) << -hx, 0.0, 0.14;
  j.row(md::kSpine1) << 0, 1.11, -0.01;
  j.row(md::kSpine2) << 0, 1.24, 0;
  j.row(md::kSpine3) << 0, 1.30, 0.01;
  j.row(md::kNeck) << 0, 1.50, -0.01;
  j.row(md::kHead) << 0, 1.60, 0.03;
  for (const double s : {1.0, -1.0}) {
    const int o = s > 0 ? 0 : 1;
    j.row(md::kLeftCollar + o) << s * 0.07, 1.42, -0.01;
    j.row(md::kLeftShoulder + o) << s * 0.18, 1.40, -0.02;
    j.row(md::kLeftElbow + o) << s * 0.44, 1.40, -0.03;
    j.row(md::kLeftWrist + o) << s * 0.69, 1.40, -0.02;
    j.row(md::kLeftHand + o) << s * 0.77, 1.39, -0.02;
  }
  return j;
}

TEST(DanceMotion, ShowcaseBesideTheDynaMotions) {
  const std::vector<std::string> dyna = {"one_leg_jump", "running_on_spot", "shake_hips", "jiggle_on_toes",
                                         "shake_shoulders"};
  EXPECT_EQ(procedural_motion_names(), dyna);  // presets and tests rely on this list and its order
  EXPECT_EQ(showcase_motion_names(), std::vector<std::string>{"dance"});
  EXPECT_FALSE(procedural_motion_description("dance").empty());
  EXPECT_DOUBLE_EQ(procedural_motion_period("dance"), 2.0);
  EXPECT_EQ(procedural_motion_period("shake_hips"), 0.0);
  const Motion m = load_motion("dance", 30.0, 12);
  EXPECT_EQ(m.num_frames(), 12u);
  EXPECT_EQ(m.source, "procedural");
  EXPECT_EQ(make_procedural_motion("dance", 60.0).num_frames(), 270u);  // default 4.5 s
}

TEST(DanceMotion, ValidPeriodicSmoothAndWithinJointRanges) {
  const double fps = 120.0;
  const Motion m = make_procedural_motion("dance", fps, 600);  // 5 s: ease-in + 2 bars
  ASSERT_NO_THROW(m.validate());
  EXPECT_EQ(m.poses[0].cwiseAbs().maxCoeff(), 0.0);  // starts at the rest pose
  const auto period = static_cast<std::size_t>(std::lround(2.0 * fps));
  const auto steady = static_cast<std::size_t>(std::lround(0.5 * fps));  // after the ease-in
  for (std::size_t f = steady; f + period < m.num_frames(); ++f)
    ASSERT_LT(max_abs_difference(m, f, m, f + period), 1e-12) << "frame " << f;

  // C¹: the acceleration estimate (second difference / h²) stays bounded and does not grow when h
  // halves; a jump in velocity would double it (it grows like 1/h), a jump in an axis-angle channel
  // would make the first difference O(1).
  const Motion fine = make_procedural_motion("dance", 2.0 * fps, 1200);
  auto max_acceleration = [](const Motion& x) {
    double acc = 0.0;
    for (std::size_t f = 1; f + 1 < x.num_frames(); ++f) {
      acc = std::max(acc, (x.poses[f + 1] - 2.0 * x.poses[f] + x.poses[f - 1]).cwiseAbs().maxCoeff());
      acc = std::max(acc, (x.trans[f + 1] - 2.0 * x.trans[f] + x.trans[f - 1]).cwiseAbs().maxCoeff());
    }
    return acc * x.fps * x.fps;
  };
  double step = 0.0;
  for (std::size_t f = 1; f < m.num_frames(); ++f)
    step = std::max(step, (m.poses[f] - m.poses[f - 1]).cwiseAbs().maxCoeff());
  const double acc = max_acceleration(m), acc_fine = max_acceleration(fine);
  RecordProperty("max_acceleration", std::to_string(acc));
  // < 3° per 1/120 s (≤ 6.3 rad/s; the arm swing peaks near 5 rad/s) on every channel; an axis-angle
  // flip would be of order π.
  EXPECT_LT(step, 3.0 * kDeg);
  EXPECT_LT(acc, 60.0);  // [rad/s², m/s²]: a dance, not an impact
  EXPECT_LT(acc_fine, 1.05 * acc + 1e-6);

  // Plausible ranges: knees bent 15°–60°, pelvis within 12°, every joint within 90°; feet planted.
  const BodyModel model;  // forward kinematics only needs the parents
  const JointPositions rest = nominal_skeleton();
  double knee_min = 1e9, knee_max = 0.0, pelvis = 0.0, any = 0.0, foot = 0.0;
  for (std::size_t f = steady; f < m.num_frames(); f += 3) {
    for (const int k : {md::kLeftKnee, md::kRightKnee}) {
      knee_min = std::min(knee_min, m.poses[f].segment<3>(3 * k).norm());
      knee_max = std::max(knee_max, m.poses[f].segment<3>(3 * k).norm());
    }
    pelvis = std::max(pelvis, m.poses[f].segment<3>(0).norm());
    for (int k = 0; k < kNumJoints; ++k) any = std::max(any, m.poses[f].segment<3>(3 * k).norm());
    const JointPositions p = forward_kinematics(model, rest, m.poses[f], m.trans[f]).joints_posed;
    for (const int k : {md::kLeftAnkle, md::kRightAnkle, md::kLeftFoot, md::kRightFoot})
      foot = std::max(foot, (p.row(k) - rest.row(k)).norm());
  }
  RecordProperty("knee_range_deg", std::to_string(knee_min / kDeg) + ".." + std::to_string(knee_max / kDeg));
  EXPECT_GT(knee_min, 15.0 * kDeg);
  EXPECT_LT(knee_max, 60.0 * kDeg);
  EXPECT_LT(pelvis, 12.0 * kDeg);
  EXPECT_LT(any, 90.0 * kDeg);
  EXPECT_LT(foot, 1e-9);  // IK on the nominal leg, which this skeleton has exactly
}

TEST(OffsetMotion, PeriodicMotionShiftsItsPhaseAndStartsAtRest) {
  const double fps = 60.0;
  const Motion m = make_procedural_motion("dance", fps, 300);
  const std::size_t k = 25, steady = 30;  // offset of 25 frames; ease-in over the first 30
  const Motion shifted = offset_motion(m, static_cast<double>(k) / fps);
  ASSERT_EQ(shifted.num_frames(), m.num_frames());
  EXPECT_EQ(shifted.poses[0].cwiseAbs().maxCoeff(), 0.0);  // every avatar leaves the rest pose
  const Motion longer = make_procedural_motion("dance", fps, 300 + static_cast<int>(k));
  for (std::size_t f = steady; f < shifted.num_frames(); ++f)
    ASSERT_LT(max_abs_difference(shifted, f, longer, f + k), 1e-12) << "frame " << f;
  const Motion bar = offset_motion(m, 2.0);  // one period: the same motion
  for (std::size_t f = 0; f < m.num_frames(); ++f) ASSERT_LT(max_abs_difference(bar, f, m, f), 1e-12) << f;
  // Offsets compose, and the load option is the same thing.
  const Motion twice = offset_motion(offset_motion(m, 0.3), 0.4), once = offset_motion(m, 0.7);
  const Motion loaded = load_motion("dance", fps, 300, 0.7);
  for (std::size_t f = 0; f < m.num_frames(); f += 7) {
    EXPECT_LT(max_abs_difference(twice, f, once, f), 1e-12) << f;
    EXPECT_EQ(max_abs_difference(loaded, f, once, f), 0.0) << f;
  }
}

TEST(OffsetMotion, OtherMotionsStartLaterAndDataClamps) {
  const double fps = 60.0;
  const Motion jiggle = make_procedural_motion("jiggle_on_toes", fps, 120);
  const Motion later = offset_motion(jiggle, 0.25);  // a DYNA motion from t = 0.25 s on
  const Motion longer = make_procedural_motion("jiggle_on_toes", fps, 135);
  for (std::size_t f = 0; f < later.num_frames(); ++f)
    ASSERT_LT(max_abs_difference(later, f, longer, f + 15), 1e-12) << f;

  Motion data = jiggle;  // the same frames as a data motion: resampled from its frames, clamped at the end
  data.source = "clip.npz";
  const Motion whole = offset_motion(data, 10.0 / fps);
  for (std::size_t f = 0; f + 10 < data.num_frames(); ++f)
    ASSERT_EQ(max_abs_difference(whole, f, data, f + 10), 0.0) << f;
  for (std::size_t f = data.num_frames() - 10; f < data.num_frames(); ++f)
    ASSERT_EQ(max_abs_difference(whole, f, data, data.num_frames() - 1), 0.0) << f;
  const Motion half = offset_motion(data, 2.5 / fps);
  for (std::size_t f = 0; f + 3 < data.num_frames(); f += 5) {
    EXPECT_LT((half.poses[f] - slerp_pose(data.poses[f + 2], data.poses[f + 3], 0.5)).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((half.trans[f] - 0.5 * (data.trans[f + 2] + data.trans[f + 3])).cwiseAbs().maxCoeff(), 1e-12);
  }
  const Motion earlier = offset_motion(data, -5.0 / fps);  // before the first frame: held at frame 0
  for (std::size_t f = 0; f <= 5; ++f) ASSERT_EQ(max_abs_difference(earlier, f, data, 0), 0.0) << f;
  ASSERT_EQ(max_abs_difference(earlier, 20, data, 15), 0.0);
  EXPECT_THROW(offset_motion(data, std::nan("")), Error);
}

}  // namespace
}  // namespace sflsh::body
