#include "skeleton.hpp"

#include "factors.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sflsh::body::detail {
namespace {

// Stature fractions (Drillis & Contini) of the levels the trunk is split at.
constexpr double kCrotchFraction = 0.465;
constexpr double kShoulderFraction = 0.818;
constexpr double kPelvisFraction = 0.555;
constexpr double kArmDropDegrees = 12.0;  // arms below horizontal in the rest pose

/// A trunk knot of the average body and how strongly each factor acts on it (weights in [0, 1]).
struct TrunkKnot {
  double fraction;                                 // height as a fraction of stature
  double a, b, c;                                  // half-width, half-depth, z-centre at the average body [m]
  double hips, shoulders, chest, belly, buttocks;  // factor weights at this level
};

// Bottom (crotch) to top (neck base). Half-widths and depths are those of a 1.70 m average adult
// (hip breadth 0.191 H at fraction 0.525, waist at 0.615, chest at 0.735, armpit at 0.77).
constexpr std::array<TrunkKnot, 12> kTrunkKnots = {{
    {0.455, 0.075, 0.060, -0.010, 0.5, 0.0, 0.0, 0.0, 0.5},
    {0.490, 0.148, 0.092, -0.012, 1.0, 0.0, 0.0, 0.0, 1.0},
    {0.525, 0.163, 0.098, -0.012, 1.0, 0.0, 0.0, 0.0, 1.0},
    {0.570, 0.155, 0.097, -0.006, 1.0, 0.0, 0.0, 0.5, 0.3},
    {0.615, 0.136, 0.092, 0.000, 0.5, 0.0, 0.0, 1.0, 0.0},
    {0.660, 0.140, 0.098, 0.005, 0.0, 0.0, 0.3, 1.0, 0.0},
    {0.700, 0.150, 0.110, 0.012, 0.0, 0.0, 1.0, 0.3, 0.0},
    {0.735, 0.157, 0.115, 0.012, 0.0, 0.5, 1.0, 0.0, 0.0},
    {0.770, 0.160, 0.106, 0.000, 0.0, 1.0, 1.0, 0.0, 0.0},
    {0.800, 0.145, 0.085, -0.010, 0.0, 1.0, 0.5, 0.0, 0.0},
    {0.825, 0.090, 0.065, -0.020, 0.0, 1.0, 0.0, 0.0, 0.0},
    {0.845, 0.058, 0.052, -0.020, 0.0, 0.5, 0.0, 0.0, 0.0},
}};
constexpr int kArmpitKnot = 8;

BodyScales make_scales(const AnthroFactors& z) {
  BodyScales s;
  s.stature = 1.70 * (1.0 + 0.04 * z(kStature));
  s.trunk = 1.0 + 0.03 * z(kTorsoLength);
  // Head and neck keep their share; the legs give what the trunk takes.
  s.legs = (1.0 - (kShoulderFraction - kCrotchFraction) * s.trunk - (1.0 - kShoulderFraction)) / kCrotchFraction;
  s.frame = 1.0 + 0.02 * z(kStature);
  s.girth = (1.0 + 0.07 * z(kGirth)) * (1.0 + 0.02 * z(kStature));
  s.shoulders = 1.0 + 0.05 * z(kShoulderWidth);
  s.hips = 1.0 + 0.05 * z(kHipWidth);
  s.chest = 1.0 + 0.03 * z(kChest);
  s.breasts = std::max(0.4, 1.0 + 0.15 * z(kChest));
  s.belly = std::max(0.3, 1.0 + 0.18 * z(kBelly));
  s.buttocks = std::max(0.5, 1.0 + 0.12 * z(kButtocks));
  s.thighs = 1.0 + 0.06 * z(kThighGirth);
  s.arms = 1.0 + 0.07 * z(kArmGirth);
  s.extremities = s.stature / 1.70;
  return s;
}

Eigen::Vector3d mirrored(const Eigen::Vector3d& p) { return {-p.x(), p.y(), p.z()}; }

}  // namespace

double Skeleton::level(double fraction) const {
  const double h = scales.stature;
  double height;
  if (fraction <= kCrotchFraction) {
    height = fraction * h * scales.legs;
  } else if (fraction <= kShoulderFraction) {
    height = kCrotchFraction * h * scales.legs + (fraction - kCrotchFraction) * h * scales.trunk;
  } else {
    height = kCrotchFraction * h * scales.legs + (kShoulderFraction - kCrotchFraction) * h * scales.trunk +
             (fraction - kShoulderFraction) * h;
  }
  return height - pelvis_height;
}

TrunkSection Skeleton::trunk_at(double y) const {
  if (y <= trunk.front().y) return trunk.front();
  if (y >= trunk.back().y) return trunk.back();
  std::size_t k = 0;
  while (k + 2 < trunk.size() && y > trunk[k + 1].y) ++k;
  const TrunkSection& lo = trunk[k];
  const TrunkSection& hi = trunk[k + 1];
  const double t = (y - lo.y) / (hi.y - lo.y);
  return {y, lo.a + t * (hi.a - lo.a), lo.b + t * (hi.b - lo.b), lo.c + t * (hi.c - lo.c)};
}

Skeleton make_skeleton(const AnthroFactors& z) {
  Skeleton sk;
  sk.scales = make_scales(z);
  const BodyScales& s = sk.scales;
  sk.pelvis_height = 0.0;
  sk.pelvis_height = sk.level(kPelvisFraction);
  sk.floor_y = sk.level(0.0);
  sk.head_top_y = sk.level(1.0);

  // Trunk sections.
  sk.trunk.reserve(kTrunkKnots.size());
  for (const TrunkKnot& k : kTrunkKnots) {
    const double a = k.a * s.girth * (1.0 + (s.hips - 1.0) * k.hips) * (1.0 + (s.shoulders - 1.0) * k.shoulders);
    const double b = k.b * s.girth * (1.0 + (s.chest - 1.0) * k.chest) * (1.0 + 0.15 * (s.belly - 1.0) * k.belly) *
                     (1.0 + 0.25 * (s.buttocks - 1.0) * k.buttocks);
    sk.trunk.push_back({sk.level(k.fraction), a, b, k.c * s.girth});
  }

  // Limb radii.
  sk.thigh_top = 0.088 * s.girth * s.thighs;
  sk.thigh_knee = 0.055 * s.girth * (1.0 + 0.5 * (s.thighs - 1.0));
  sk.shank_knee = 0.052 * s.girth * (1.0 + 0.5 * (s.thighs - 1.0));
  sk.shank_ankle = 0.031 * (1.0 + 0.4 * (s.girth - 1.0)) * s.extremities;
  sk.upper_arm_top = 0.049 * s.girth * s.arms;
  sk.upper_arm_elbow = 0.038 * s.girth * s.arms;
  sk.forearm_elbow = 0.040 * s.girth * (1.0 + 0.7 * (s.arms - 1.0));
  sk.forearm_wrist = 0.027 * (1.0 + 0.5 * (s.girth - 1.0)) * s.extremities;
  sk.neck_base = 0.058 * s.girth;
  sk.neck_top = 0.050 * (1.0 + 0.7 * (s.girth - 1.0));

  // Joints of the left side and the spine; the right side mirrors x.
  auto& j = sk.joints;
  const double h = s.stature;
  j[0] = {0.0, 0.0, 0.0};
  j[3] = {0.0, sk.level(0.615), -0.015};
  j[6] = {0.0, sk.level(0.695), -0.010};
  j[9] = {0.0, sk.level(0.730), -0.005};
  j[12] = {0.0, sk.level(0.848), -0.020};
  j[15] = {0.0, sk.level(0.905), 0.000};
  // Legs move apart as the thighs grow, which keeps the crotch gap of the average body.
  const double hip_x = 0.090 * s.frame + kThighSquash * (sk.thigh_top - 0.088 * s.frame);
  j[1] = {hip_x, sk.level(0.505), 0.0};
  j[4] = {hip_x + 0.020 * s.frame, sk.level(0.285), 0.005};
  j[7] = {hip_x + 0.032 * s.frame, sk.level(0.042), -0.015 * s.extremities};
  j[10] = {j[7].x() + 0.008 * s.extremities, sk.floor_y + 0.022 * s.extremities, j[7].z() + 0.120 * s.extremities};
  // Arms: the shoulders follow the width of the chest and the thickness of the upper arm, so the
  // armpit keeps its shape.
  const double armpit_a = sk.trunk[kArmpitKnot].a;
  const double shoulder_x = 0.175 * s.frame * s.shoulders + (armpit_a - kTrunkKnots[kArmpitKnot].a * s.shoulders) +
                            (sk.upper_arm_top - 0.049 * s.frame);
  const double drop = kArmDropDegrees * std::numbers::pi / 180.0;
  sk.arm_direction = Eigen::Vector3d(std::cos(drop), -std::sin(drop), 0.0);
  j[13] = {0.075 * s.frame * s.shoulders, sk.level(0.797), -0.010};
  j[16] = {shoulder_x, sk.level(0.803), -0.015};
  // Upper arm and forearm between joint centres (Drillis & Contini measure from the acromion, which
  // sits lateral to the shoulder joint; this keeps the arm span close to the stature).
  j[18] = j[16] + 0.160 * h * sk.arm_direction;
  j[20] = j[18] + 0.146 * h * sk.arm_direction;
  j[22] = j[20] + 0.055 * h * sk.arm_direction;
  for (int left : {1, 4, 7, 10, 13, 16, 18, 20, 22}) j[mirror_joint(left)] = mirrored(j[left]);
  return sk;
}

int mirror_joint(int joint) {
  static constexpr std::array<int, kNumJoints> kMirror = {0,  2,  1,  3,  5,  4,  6,  8,  7,  9,  11, 10,
                                                          12, 14, 13, 15, 17, 16, 19, 18, 21, 20, 23, 22};
  return kMirror[static_cast<std::size_t>(joint)];
}

}  // namespace sflsh::body::detail
