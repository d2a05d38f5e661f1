// Procedural DYNA-like motions: counts, smoothness, advertised kinematics, and sign conventions
// checked with forward kinematics on a synthetic skeleton. File I/O is in test_motion_io.cpp.
#include <sflsh/body/body_model.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/body/skinning.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/npz.hpp>

// White-box: the private curve and rig helpers of the procedural motions.
#include "../../body/src/motion/curves.hpp"
#include "../../body/src/motion/rig.hpp"
#include "angles.hpp"
#include "error_of.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

namespace sflsh::body {
namespace {

namespace md = motion_detail;
constexpr double kG = 9.81;
using sflsh::testing::kDeg;

// ---------------------------------------------------------------------------------------------
// Helpers

/// A synthetic SMPL-like rest skeleton [m] (ground at y = 0, facing +Z, left = +X) whose legs match
/// the nominal leg of the procedural motions exactly (thigh = shank = 0.42, ankle 0.07 above the
/// ground, ball of the foot 0.14 ahead of the ankle), so foot planting can be checked exactly.
JointPositions synthetic_skeleton() {
  JointPositions j;
  const double hx = md::NominalLeg::hip_offset_x;
  j << 0, 1.0, 0,                             // 0 pelvis
      hx, 0.91, 0, -hx, 0.91, 0,              // 1, 2 hips
      0, 1.11, -0.01,                         // 3 spine1
      hx, 0.49, 0, -hx, 0.49, 0,              // 4, 5 knees
      0, 1.24, 0,                             // 6 spine2
      hx, 0.07, 0, -hx, 0.07, 0,              // 7, 8 ankles
      0, 1.30, 0.01,                          // 9 spine3
      hx, 0.0, 0.14, -hx, 0.0, 0.14,          // 10, 11 feet (balls of the feet)
      0, 1.50, -0.01,                         // 12 neck
      0.07, 1.42, -0.01, -0.07, 1.42, -0.01,  // 13, 14 collars
      0, 1.60, 0.03,                          // 15 head
      0.18, 1.40, -0.02, -0.18, 1.40, -0.02,  // 16, 17 shoulders
      0.44, 1.40, -0.03, -0.44, 1.40, -0.03,  // 18, 19 elbows
      0.69, 1.40, -0.02, -0.69, 1.40, -0.02,  // 20, 21 wrists
      0.77, 1.39, -0.02, -0.77, 1.39, -0.02;  // 22, 23 hands
  return j;
}

/// Posed joint positions of frame `f` on the synthetic skeleton (world_from_body applied).
JointPositions pose_joints(const Motion& m, std::size_t f) {
  const BodyModel model;  // only the parents are used by forward kinematics
  JointPositions p = forward_kinematics(model, synthetic_skeleton(), m.poses[f], m.trans[f]).joints_posed;
  for (int k = 0; k < kNumJoints; ++k) p.row(k) = (m.world_from_body * p.row(k).transpose()).transpose();
  return p;
}

/// One scalar per frame.
std::vector<double> series(const Motion& m, const std::function<double(std::size_t)>& f) {
  std::vector<double> out(m.num_frames());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = f(i);
  return out;
}

/// Frames of the steady part (after the ease-in plus a margin), [first, end).
std::size_t steady_start(const Motion& m) { return static_cast<std::size_t>(std::ceil(0.8 * m.fps)); }

double max_in(const std::vector<double>& v, std::size_t first) {
  return *std::max_element(v.begin() + static_cast<std::ptrdiff_t>(first), v.end());
}
double min_in(const std::vector<double>& v, std::size_t first) {
  return *std::min_element(v.begin() + static_cast<std::ptrdiff_t>(first), v.end());
}

/// Strict local maxima in [first, end) that rise at least `prominence` above the series' minimum.
std::vector<std::size_t> peaks(const std::vector<double>& v, std::size_t first, double prominence) {
  const double floor_value = min_in(v, first);
  std::vector<std::size_t> out;
  for (std::size_t i = std::max<std::size_t>(first, 1); i + 1 < v.size(); ++i)
    if (v[i] > v[i - 1] && v[i] >= v[i + 1] && v[i] - floor_value > prominence) out.push_back(i);
  return out;
}

/// Mean frequency [Hz] from the spacing of successive peaks.
double peak_frequency(const std::vector<std::size_t>& p, double fps) {
  if (p.size() < 2) return 0.0;
  return static_cast<double>(p.size() - 1) * fps / static_cast<double>(p.back() - p.front());
}

double correlation(const std::vector<double>& a, const std::vector<double>& b, std::size_t first) {
  const auto n = static_cast<double>(a.size() - first);
  double ma = 0, mb = 0;
  for (std::size_t i = first; i < a.size(); ++i) ma += a[i] / n, mb += b[i] / n;
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = first; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return sab / std::sqrt(saa * sbb);
}

/// Rotation angle of joint k's local rotation [rad].
double joint_angle(const Motion& m, std::size_t f, int k) { return m.poses[f].segment<3>(3 * k).norm(); }

/// Second difference / h² (acceleration) and third difference / h³ (jerk) of a series.
double max_second_difference(const std::vector<double>& v, double fps) {
  double out = 0;
  for (std::size_t i = 1; i + 1 < v.size(); ++i) out = std::max(out, std::abs(v[i + 1] - 2 * v[i] + v[i - 1]));
  return out * fps * fps;
}
double max_third_difference(const std::vector<double>& v, double fps) {
  double out = 0;
  for (std::size_t i = 0; i + 3 < v.size(); ++i)
    out = std::max(out, std::abs(v[i + 3] - 3 * v[i + 2] + 3 * v[i + 1] - v[i]));
  return out * fps * fps * fps;
}

/// All 72 pose components and 3 translation components as series.
std::vector<std::vector<double>> all_channels(const Motion& m) {
  std::vector<std::vector<double>> out;
  for (int c = 0; c < 3 * kNumJoints; ++c) out.push_back(series(m, [&](std::size_t f) { return m.poses[f](c); }));
  for (int c = 0; c < 3; ++c) out.push_back(series(m, [&](std::size_t f) { return m.trans[f](c); }));
  return out;
}

using sflsh::testing::error_of;

// ---------------------------------------------------------------------------------------------
// Registry

TEST(ProceduralMotion, NamesInDynaOrderWithDescriptions) {
  const std::vector<std::string> expected = {"one_leg_jump", "running_on_spot", "shake_hips", "jiggle_on_toes",
                                             "shake_shoulders"};
  EXPECT_EQ(procedural_motion_names(), expected);
  for (const auto& name : expected) {
    const std::string d = procedural_motion_description(name);
    EXPECT_FALSE(d.empty());
    EXPECT_EQ(d.find('\n'), std::string::npos);
  }
  const std::string msg = error_of([] { make_procedural_motion("moonwalk"); });
  EXPECT_NE(msg.find("moonwalk"), std::string::npos) << msg;
  EXPECT_NE(msg.find("shake_shoulders"), std::string::npos) << msg;
  EXPECT_THROW(procedural_motion_description("moonwalk"), Error);
  EXPECT_THROW(make_procedural_motion("shake_hips", 0.0), Error);
  EXPECT_THROW(make_procedural_motion("shake_hips", -60.0), Error);
}

// ---------------------------------------------------------------------------------------------
// Every procedural motion

class ProceduralMotionTest : public ::testing::TestWithParam<std::string> {};

TEST_P(ProceduralMotionTest, FrameCountsAndValidity) {
  for (const auto& [fps, frames] :
       std::vector<std::pair<double, std::size_t>>{{60, 240}, {30, 120}, {120, 480}, {100, 400}, {24, 96}}) {
    const Motion m = make_procedural_motion(GetParam(), fps);
    EXPECT_EQ(m.num_frames(), frames) << "fps " << fps;
    EXPECT_EQ(m.trans.size(), frames);
    EXPECT_DOUBLE_EQ(m.fps, fps);
    EXPECT_EQ(m.name, GetParam());
    EXPECT_EQ(m.source, "procedural");
    EXPECT_TRUE(m.world_from_body.isIdentity());
    EXPECT_NO_THROW(m.validate());
  }
  EXPECT_EQ(make_procedural_motion(GetParam(), 60.0, 17).num_frames(), 17u);
  EXPECT_EQ(make_procedural_motion(GetParam(), 60.0, 1).num_frames(), 1u);
}

TEST_P(ProceduralMotionTest, SampledFromOneContinuousCurve) {
  // Frame 2i at 120 fps is the same instant as frame i at 60 fps.
  const Motion a = make_procedural_motion(GetParam(), 60.0), b = make_procedural_motion(GetParam(), 120.0);
  for (std::size_t i = 0; i < a.num_frames(); i += 7) {
    EXPECT_LT((a.poses[i] - b.poses[2 * i]).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((a.trans[i] - b.trans[2 * i]).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST_P(ProceduralMotionTest, StartsAtRestPose) {
  const Motion m = make_procedural_motion(GetParam(), 60.0);
  EXPECT_EQ(m.poses[0].cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(m.trans[0].cwiseAbs().maxCoeff(), 0.0);
  // The ease-in leaves the rest pose gently: after 1/60 s everything moved by less than 0.1° / 0.1 mm.
  EXPECT_LT(m.poses[1].cwiseAbs().maxCoeff(), 0.1 * kDeg);
  EXPECT_LT(m.trans[1].cwiseAbs().maxCoeff(), 1e-4);
}

TEST_P(ProceduralMotionTest, SmoothC2) {
  // Accelerations (second differences / h²) are bounded, and the jerk estimate (third differences /
  // h³) converges under refinement: a jump in acceleration (a C¹-only curve) would make it grow like
  // 1/h, a jump in velocity like 1/h².
  const Motion coarse = make_procedural_motion(GetParam(), 240.0);
  const Motion fine = make_procedural_motion(GetParam(), 480.0);
  const auto cc = all_channels(coarse), cf = all_channels(fine);
  for (std::size_t c = 0; c < cc.size(); ++c) {
    const bool translation = c >= 3 * kNumJoints;
    const double acc = max_second_difference(cf[c], fine.fps);
    if (translation)
      EXPECT_LT(acc, 5.0 * kG) << "trans component " << c - 3 * kNumJoints;
    else
      EXPECT_LT(acc, 1500.0) << "pose component " << c << " [rad/s²]";
    const double jerk_coarse = max_third_difference(cc[c], coarse.fps);
    const double jerk_fine = max_third_difference(cf[c], fine.fps);
    EXPECT_LT(jerk_fine, 1.3 * jerk_coarse + 1e-6) << "channel " << c << ": jerk estimate grows under refinement";
  }
}

TEST_P(ProceduralMotionTest, ArmsComeDownFromTPose) {
  const Motion m = make_procedural_motion(GetParam(), 60.0);
  const JointPositions rest = pose_joints(m, 0);
  EXPECT_NEAR(rest(md::kLeftElbow, 1), 1.40, 1e-12);  // elbows at shoulder height in the T-pose
  for (std::size_t f = steady_start(m); f < m.num_frames(); f += 5) {
    const JointPositions p = pose_joints(m, f);
    for (const int side : {0, 1}) {
      const double drop = p(16 + side, 1) - p(18 + side, 1);  // shoulder above elbow
      EXPECT_GT(drop, 0.18) << "frame " << f << (side ? " right" : " left");
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllKinds, ProceduralMotionTest,
                         ::testing::Values("one_leg_jump", "running_on_spot", "shake_hips", "jiggle_on_toes",
                                           "shake_shoulders"));

// ---------------------------------------------------------------------------------------------
// Sign conventions (rig.hpp) checked with forward kinematics on the synthetic skeleton

Motion single_pose(const Pose& theta) {
  Motion m;
  m.poses = {theta};
  m.trans = {Eigen::Vector3d::Zero()};
  return m;
}

TEST(MotionConventions, AnatomicalSignsMoveSegmentsTheRightWay) {
  const JointPositions rest = synthetic_skeleton();
  auto moved = [&](const md::LegAngles& leg, const md::ArmAngles& arm) {
    Pose theta = Pose::Zero();
    md::set_leg(theta, md::Side::kLeft, leg);
    md::set_leg(theta, md::Side::kRight, leg);
    md::set_arm(theta, md::Side::kLeft, arm);
    md::set_arm(theta, md::Side::kRight, arm);
    return JointPositions(pose_joints(single_pose(theta), 0) - rest);
  };
  md::LegAngles leg;
  md::ArmAngles arm;
  leg.hip_flexion = 30 * kDeg;  // thighs forward: knees move +Z
  JointPositions d = moved(leg, arm);
  EXPECT_GT(d(md::kLeftKnee, 2), 0.15);
  EXPECT_GT(d(md::kRightKnee, 2), 0.15);
  leg = {};
  leg.knee_flexion = 60 * kDeg;  // shanks back: ankles move −Z and up
  d = moved(leg, arm);
  EXPECT_LT(d(md::kLeftAnkle, 2), -0.3);
  EXPECT_GT(d(md::kRightAnkle, 1), 0.1);
  leg = {};
  leg.ankle_plantar_flexion = 30 * kDeg;  // toes down
  d = moved(leg, arm);
  EXPECT_LT(d(md::kLeftFoot, 1), -0.05);
  leg = {};
  leg.hip_abduction = 20 * kDeg;  // legs outward: left knee +X, right knee −X
  d = moved(leg, arm);
  EXPECT_GT(d(md::kLeftKnee, 0), 0.1);
  EXPECT_LT(d(md::kRightKnee, 0), -0.1);
  leg = {};
  arm.down = 70 * kDeg;  // arms down: elbows and wrists go down, stay beside the body
  d = moved(leg, arm);
  EXPECT_LT(d(md::kLeftWrist, 1), -0.4);
  EXPECT_LT(d(md::kRightWrist, 1), -0.4);
  arm.swing = 30 * kDeg;  // arms forward
  d = moved(leg, arm);
  EXPECT_GT(d(md::kLeftWrist, 2), 0.15);
  EXPECT_GT(d(md::kRightWrist, 2), 0.15);
  arm = {};
  arm.elbow_flexion = 60 * kDeg;  // T-pose, palms down: forearms swing forward
  d = moved(leg, arm);
  EXPECT_GT(d(md::kLeftWrist, 2), 0.15);
  EXPECT_GT(d(md::kRightWrist, 2), 0.15);
  arm = {};
  arm.protraction = 15 * kDeg;  // shoulders forward
  d = moved(leg, arm);
  EXPECT_GT(d(md::kLeftShoulder, 2), 0.02);
  EXPECT_GT(d(md::kRightShoulder, 2), 0.02);
}

TEST(MotionConventions, LegInverseKinematicsReachesTarget) {
  const Eigen::Quaterniond pelvis = md::rot_y(0.2) * md::rot_z(-0.25);
  const Eigen::Vector3d pelvis_world(0.03, -0.06, 0.01);
  for (const md::Side side : {md::Side::kLeft, md::Side::kRight}) {
    const md::LegIkResult ik = md::solve_leg_ik(side, pelvis, pelvis_world, md::nominal_rest_ankle(side),
                                                Eigen::Quaterniond::Identity(), Eigen::Vector3d::UnitZ());
    Pose theta = Pose::Zero();
    const bool left = side == md::Side::kLeft;
    md::set_joint(theta, md::kPelvis, pelvis);
    md::set_joint(theta, left ? md::kLeftHip : md::kRightHip, ik.hip);
    md::set_joint(theta, left ? md::kLeftKnee : md::kRightKnee, md::rot_x(ik.knee_flexion));
    md::set_joint(theta, left ? md::kLeftAnkle : md::kRightAnkle, ik.ankle);
    Motion m = single_pose(theta);
    m.trans[0] = pelvis_world;
    const JointPositions p = pose_joints(m, 0), rest = synthetic_skeleton();
    const int ankle = left ? md::kLeftAnkle : md::kRightAnkle, ball = left ? md::kLeftFoot : md::kRightFoot;
    const int knee = left ? md::kLeftKnee : md::kRightKnee;
    EXPECT_LT((p.row(ankle) - rest.row(ankle)).norm(), 1e-9);
    EXPECT_LT((p.row(ball) - rest.row(ball)).norm(), 1e-9);  // foot flat, pointing forward
    EXPECT_GT(p(knee, 2), 0.02);                             // knee bends forward
    EXPECT_GT(ik.knee_flexion, 5 * kDeg);
  }
}

// ---------------------------------------------------------------------------------------------
// Private curve helpers

TEST(MotionCurves, JetsAndHermiteBridge) {
  // Hermite bridge matches value, slope and curvature at both ends.
  const md::Jet a{0.3, -2.0, 15.0}, b{-0.1, 4.0, -30.0};
  const double h = 0.2;
  const md::Jet s0 = md::hermite_quintic(a, b, h, 0.0), s1 = md::hermite_quintic(a, b, h, h);
  EXPECT_NEAR(s0.v, a.v, 1e-12);
  EXPECT_NEAR(s0.d, a.d, 1e-12);
  EXPECT_NEAR(s0.dd, a.dd, 1e-10);
  EXPECT_NEAR(s1.v, b.v, 1e-12);
  EXPECT_NEAR(s1.d, b.d, 1e-12);
  EXPECT_NEAR(s1.dd, b.dd, 1e-10);
  // Jet derivatives agree with finite differences.
  const double t = 0.123, e = 1e-5;
  auto f = [&](double x) { return md::acos(0.5 * md::sin(md::time_jet(x)) * md::ease_in(x, 0.4)); };
  EXPECT_NEAR(f(t).d, (f(t + e).v - f(t - e).v) / (2 * e), 1e-7);
  EXPECT_NEAR(f(t).dd, (f(t + e).v - 2 * f(t).v + f(t - e).v) / (e * e), 1e-3);
  EXPECT_EQ(md::ease_in(0.0, 0.5).v, 0.0);
  EXPECT_EQ(md::ease_in(0.5, 0.5).v, 1.0);
  EXPECT_NEAR(md::ease_in(0.25, 0.5).v, 0.5, 1e-15);
}

TEST(MotionCurves, HopProfileIsPeriodicBallisticAndConsistent) {
  const md::HopProfile hop(0.5, 0.28, 0.06, 5.0 * kG, 3.5 * kG);
  const double e = 1e-5;
  for (double t = 0.003; t < 1.0; t += 0.0137) {  // analytic derivatives match finite differences
    EXPECT_NEAR(hop.height(t).d, (hop.height(t + e).v - hop.height(t - e).v) / (2 * e), 1e-6);
    EXPECT_NEAR(hop.height(t).dd, (hop.height(t + e).v - 2 * hop.height(t).v + hop.height(t - e).v) / (e * e), 1e-2);
  }
  for (const double u : {0.0, 0.28}) {  // C² across touchdown and take-off
    const md::Jet before = hop.height(u - 1e-9), after = hop.height(u + 1e-9);
    EXPECT_NEAR(before.v, after.v, 1e-8);
    EXPECT_NEAR(before.d, after.d, 1e-6);
    EXPECT_NEAR(before.dd, after.dd, 1e-4);
  }
  EXPECT_DOUBLE_EQ(hop.height(0.4).dd, -kG);  // flight
  EXPECT_NEAR(hop.height(0.0).v, 0.0, 1e-15);
  EXPECT_NEAR(hop.height(0.5).v, 0.0, 1e-12);
  EXPECT_GT(hop.takeoff_speed(), 0.5);
}

// ---------------------------------------------------------------------------------------------
// Advertised kinematics of each motion

TEST(ProceduralMotionFigures, JiggleOnToes) {
  const Motion m = make_procedural_motion("jiggle_on_toes", 240.0);
  const std::size_t s = steady_start(m);
  const auto y = series(m, [&](std::size_t f) { return m.trans[f].y(); });
  const double bounce = max_in(y, s) - min_in(y, s);
  const double freq = peak_frequency(peaks(y, s, 0.5 * bounce), m.fps);
  RecordProperty("bounce_cm", std::to_string(100 * bounce));
  RecordProperty("bounce_hz", std::to_string(freq));
  EXPECT_GE(bounce, 0.02);
  EXPECT_LE(bounce, 0.04);
  EXPECT_GE(freq, 2.5);
  EXPECT_LE(freq, 3.0);
  // Heels rise with the body: cumulative foot pitch (hip + knee + ankle about X) in phase with y.
  const auto pitch =
      series(m, [&](std::size_t f) { return m.poses[f](3 * 1) + m.poses[f](3 * 4) + m.poses[f](3 * 7); });
  EXPECT_GT(correlation(pitch, y, s), 0.95);
  EXPECT_GT(min_in(pitch, s), 5 * kDeg);  // always on the toes
  // Knees flex slightly, more at the bottom.
  const auto knee = series(m, [&](std::size_t f) { return m.poses[f](3 * 4); });
  EXPECT_LT(max_in(knee, s), 20 * kDeg);
  EXPECT_LT(correlation(knee, y, s), -0.9);
  // Balls of the feet stay planted on the synthetic skeleton (its legs match the nominal leg).
  const JointPositions rest = synthetic_skeleton();
  double slide = 0;
  for (std::size_t f = 0; f < m.num_frames(); f += 3) {
    const JointPositions p = pose_joints(m, f);
    slide = std::max({slide, (p.row(10) - rest.row(10)).norm(), (p.row(11) - rest.row(11)).norm()});
  }
  EXPECT_LT(slide, 1e-9);
}

TEST(ProceduralMotionFigures, RunningOnSpot) {
  const Motion m = make_procedural_motion("running_on_spot", 240.0);
  const std::size_t s = steady_start(m);
  // Hip flexion is −θx of the hip (no abduction here), knee flexion +θx.
  const auto hip_l = series(m, [&](std::size_t f) { return -m.poses[f](3 * 1); });
  const auto hip_r = series(m, [&](std::size_t f) { return -m.poses[f](3 * 2); });
  const auto knee_l = series(m, [&](std::size_t f) { return m.poses[f](3 * 4); });
  const auto y = series(m, [&](std::size_t f) { return m.trans[f].y(); });
  RecordProperty("hip_max_deg", std::to_string(max_in(hip_l, s) / kDeg));
  RecordProperty("knee_max_deg", std::to_string(max_in(knee_l, s) / kDeg));
  EXPECT_NEAR(max_in(hip_l, s), 45 * kDeg, 2 * kDeg);
  EXPECT_NEAR(max_in(hip_r, s), 45 * kDeg, 2 * kDeg);
  EXPECT_NEAR(max_in(knee_l, s), 90 * kDeg, 2 * kDeg);
  EXPECT_LT(correlation(hip_l, hip_r, s), -0.3);  // legs alternate
  const double bounce = max_in(y, s) - min_in(y, s);
  EXPECT_NEAR(bounce, 0.04, 0.005);
  const double step_rate = peak_frequency(peaks(y, s, 0.5 * bounce), m.fps);  // two bounces per stride
  RecordProperty("step_rate_hz", std::to_string(step_rate));
  EXPECT_NEAR(step_rate, 2.7, 0.1);
  const double stride_rate = peak_frequency(peaks(hip_l, s, 20 * kDeg), m.fps);
  EXPECT_NEAR(stride_rate, 1.35, 0.05);
  // Arms counter-swing: the left hand goes forward while the right knee comes up.
  std::vector<double> hand_l(m.num_frames()), knee_rz(m.num_frames());
  for (std::size_t f = 0; f < m.num_frames(); ++f) {
    const JointPositions p = pose_joints(m, f);
    hand_l[f] = p(md::kLeftWrist, 2);
    knee_rz[f] = p(md::kRightKnee, 2);
  }
  EXPECT_GT(correlation(hand_l, knee_rz, s), 0.7);
  // Knee lifted in front of the body at its highest.
  const auto it = std::max_element(hip_l.begin() + static_cast<std::ptrdiff_t>(s), hip_l.end());
  const JointPositions p = pose_joints(m, static_cast<std::size_t>(it - hip_l.begin()));
  EXPECT_GT(p(md::kLeftKnee, 2) - p(md::kLeftHip, 2), 0.25);
  // The ball of a stance foot stays on the ground and in place (the swing blend costs a few mm).
  for (std::size_t f = s; f < m.num_frames(); f += 2) {
    const JointPositions q = pose_joints(m, f), rest = synthetic_skeleton();
    for (const int b : {md::kLeftFoot, md::kRightFoot}) {
      EXPECT_GT(q(b, 1), rest(b, 1) - 1e-3) << "frame " << f;
      if (q(b, 1) < rest(b, 1) + 0.005) {
        EXPECT_NEAR(q(b, 2), rest(b, 2), 0.01) << "frame " << f;
      }
    }
  }
  // Peak vertical acceleration ≈ 1 g (a foot always loaded: ÿ > −g).
  double a_max = -1e9, a_min = 1e9;
  for (std::size_t i = s; i + 1 < y.size(); ++i) {
    const double a = (y[i + 1] - 2 * y[i] + y[i - 1]) * m.fps * m.fps;
    a_max = std::max(a_max, a), a_min = std::min(a_min, a);
  }
  RecordProperty("peak_accel_g", std::to_string(a_max / kG));
  EXPECT_NEAR(a_max / kG, 1.06, 0.05);
  EXPECT_GT(a_min, -kG);
}

TEST(ProceduralMotionFigures, OneLegJump) {
  const Motion m = make_procedural_motion("one_leg_jump", 240.0);
  const std::size_t s = static_cast<std::size_t>(0.5 * m.fps);  // the hop proper starts at t = 0.5 s
  const auto y = series(m, [&](std::size_t f) { return m.trans[f].y(); });
  std::vector<double> acc(y.size(), 0.0);
  for (std::size_t i = 1; i + 1 < y.size(); ++i) acc[i] = (y[i + 1] - 2 * y[i] + y[i - 1]) * m.fps * m.fps;
  const double peak = max_in(acc, s);
  const double peak_all = *std::max_element(acc.begin(), acc.end());
  RecordProperty("landing_peak_g", std::to_string(peak / kG));
  EXPECT_GE(peak, 3.0 * kG);
  EXPECT_LE(peak, 5.0 * kG);
  EXPECT_LE(peak_all, 5.0 * kG);  // also during the ease-in
  // Physical throughout (ease-in included): the ground can push but not pull, so ÿ ≥ −g.
  EXPECT_GE(*std::min_element(acc.begin() + 1, acc.end() - 1), -kG - 1e-6);
  // Flight phases: ÿ = −g over intervals of ≈ 0.22 s, twice per second.
  std::size_t run = 0, longest = 0, flights = 0;
  for (std::size_t i = s; i + 1 < acc.size(); ++i) {
    if (std::abs(acc[i] + kG) < 1e-6) {
      if (run++ == 0) ++flights;
      longest = std::max(longest, run);
    } else {
      run = 0;
    }
  }
  RecordProperty("flight_s", std::to_string(static_cast<double>(longest) / m.fps));
  EXPECT_GT(static_cast<double>(longest) / m.fps, 0.2);
  EXPECT_NEAR(static_cast<double>(flights) / (m.duration() - 0.5), 2.0, 0.3);
  const double apex = max_in(y, s), low = min_in(y, s);
  RecordProperty("height_range_cm", std::to_string(100 * (apex - low)));
  EXPECT_GT(apex, 0.05);
  EXPECT_LT(low, -0.03);
  // Stance knee flexes at landing, the other leg stays bent and lifted.
  const auto knee_l = series(m, [&](std::size_t f) { return joint_angle(m, f, md::kLeftKnee); });
  RecordProperty("stance_knee_max_deg", std::to_string(max_in(knee_l, s) / kDeg));
  EXPECT_GT(max_in(knee_l, s), 35 * kDeg);
  EXPECT_LT(max_in(knee_l, s), 60 * kDeg);
  EXPECT_GT(min_in(knee_l, s), 5 * kDeg);  // never locked straight
  double free_leg = 0, stance_leg = 1e9;   // vertical hip-to-ankle extent [m]
  for (std::size_t f = s; f < m.num_frames(); f += 4) {
    const JointPositions p = pose_joints(m, f);
    free_leg = std::max(free_leg, p(md::kRightHip, 1) - p(md::kRightAnkle, 1));
    stance_leg = std::min(stance_leg, p(md::kLeftHip, 1) - p(md::kLeftAnkle, 1));
  }
  EXPECT_LT(free_leg, 0.7);  // of the 0.84 m leg: bent and lifted
  EXPECT_GT(stance_leg, 0.75);
  // During stance the ball of the stance foot stays put on the ground (within the few mm that the
  // adduction and the leg tilt cost vertically); in flight it is above the ground.
  const Eigen::RowVector3d ball = synthetic_skeleton().row(md::kLeftFoot);
  for (std::size_t f = s; f < m.num_frames(); ++f) {
    const Eigen::RowVector3d p = pose_joints(m, f).row(md::kLeftFoot);
    EXPECT_GT(p.y(), ball.y() - 1e-3) << "frame " << f;
    if (acc[f] < -kG + 1e-6) continue;  // in flight
    EXPECT_NEAR(p.y(), ball.y(), 0.004) << "frame " << f;
    EXPECT_NEAR(p.z(), ball.z(), 0.001) << "frame " << f;
  }
}

TEST(ProceduralMotionFigures, ShakeHips) {
  const Motion m = make_procedural_motion("shake_hips", 240.0);
  const std::size_t s = steady_start(m);
  const auto pelvis_angle = series(m, [&](std::size_t f) { return joint_angle(m, f, md::kPelvis); });
  const auto roll = series(m, [&](std::size_t f) { return m.poses[f](2); });
  RecordProperty("pelvis_max_deg", std::to_string(max_in(pelvis_angle, s) / kDeg));
  EXPECT_GE(max_in(pelvis_angle, s), 15 * kDeg);
  EXPECT_LE(max_in(pelvis_angle, s), 20 * kDeg);
  EXPECT_NEAR(peak_frequency(peaks(roll, s, 10 * kDeg), m.fps), 2.0, 0.05);
  const JointPositions rest = synthetic_skeleton();
  double head = 0, ankle = 0, chest = 0, knee_min = 1e9, knee_max = 0;
  for (std::size_t f = 0; f < m.num_frames(); f += 2) {
    // The spine undoes the pelvis rotation: chest orientation = pelvis·spine1·spine2·spine3 = I.
    const Eigen::Quaterniond q = md::joint_rotation(m.poses[f], 0) * md::joint_rotation(m.poses[f], 3) *
                                 md::joint_rotation(m.poses[f], 6) * md::joint_rotation(m.poses[f], 9);
    chest = std::max(chest, Eigen::AngleAxisd(q).angle());
    const JointPositions p = pose_joints(m, f);
    if (f >= s) {
      head = std::max(head, (p.row(md::kHead) - pose_joints(m, s).row(md::kHead)).norm());
      ankle = std::max({ankle, (p.row(7) - rest.row(7)).norm(), (p.row(8) - rest.row(8)).norm(),
                        (p.row(10) - rest.row(10)).norm(), (p.row(11) - rest.row(11)).norm()});
      knee_min = std::min({knee_min, joint_angle(m, f, 4), joint_angle(m, f, 5)});
      knee_max = std::max({knee_max, joint_angle(m, f, 4), joint_angle(m, f, 5)});
    }
  }
  RecordProperty("head_motion_cm", std::to_string(100 * head));
  RecordProperty("knee_range_deg", std::to_string(knee_min / kDeg) + ".." + std::to_string(knee_max / kDeg));
  EXPECT_LT(chest, 1e-9);
  EXPECT_LT(head, 1e-9);   // the root sways so the chest stays put on the nominal spine (= synthetic)
  EXPECT_LT(ankle, 1e-9);  // feet planted (IK on the nominal leg = the synthetic skeleton's leg)
  EXPECT_GT(knee_min, 5 * kDeg);
  EXPECT_LT(knee_max, 60 * kDeg);
}

TEST(ProceduralMotionFigures, ShakeShoulders) {
  const Motion m = make_procedural_motion("shake_shoulders", 240.0);
  const std::size_t s = steady_start(m);
  // Collar oscillation: angle between the collar's rotation and its neutral rotation (at t = 1 s the
  // shimmy wave sin(2π·3.5·t) is 0).
  const std::size_t neutral = static_cast<std::size_t>(m.fps);
  for (const int collar : {md::kLeftCollar, md::kRightCollar}) {
    const Eigen::Quaterniond q0 = md::joint_rotation(m.poses[neutral], collar);
    const auto swing = series(m, [&](std::size_t f) {
      return Eigen::AngleAxisd(q0.conjugate() * md::joint_rotation(m.poses[f], collar)).angle();
    });
    RecordProperty(collar == md::kLeftCollar ? "left_collar_deg" : "right_collar_deg",
                   std::to_string(max_in(swing, s) / kDeg));
    EXPECT_GE(max_in(swing, s), 10 * kDeg);
    EXPECT_LE(max_in(swing, s), 15 * kDeg);
  }
  // Alternating: one shoulder forward while the other goes back, at 3.5 Hz.
  std::vector<double> zl(m.num_frames()), zr(m.num_frames());
  for (std::size_t f = 0; f < m.num_frames(); ++f) {
    const JointPositions p = pose_joints(m, f);
    zl[f] = p(md::kLeftShoulder, 2);
    zr[f] = p(md::kRightShoulder, 2);
  }
  EXPECT_LT(correlation(zl, zr, s), -0.95);
  const double freq = peak_frequency(peaks(zl, s, 0.5 * (max_in(zl, s) - min_in(zl, s))), m.fps);
  RecordProperty("shimmy_hz", std::to_string(freq));
  EXPECT_NEAR(freq, 3.5, 0.1);
}

}  // namespace
}  // namespace sflsh::body
