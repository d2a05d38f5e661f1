// shake_hips (DYNA training motion) and shake_shoulders (DYNA test motion).
#include "curves.hpp"
#include "procedural.hpp"
#include "rig.hpp"

namespace sflsh::body::motion_detail {

namespace {

// shake_hips: pelvis roll ±17° at 2 Hz (left hip up when rolling about +Z) with yaw ±8° a quarter
// period later, so the hips trace a flat figure rather than a pure tilt; peak pelvis rotation ≈ 17°.
constexpr double kHipsFrequency = 2.0;  // [Hz]
constexpr double kHipsRoll = deg(17.0);
constexpr double kHipsYaw = deg(8.0);
// The spine joints counter-rotate (40/35/25 % of the pelvis rotation, in reverse) so the chest keeps
// its orientation, and the root translates so that the chest (hence neck and head) stays in place on
// the nominal spine: the hips sway sideways under a still upper body.
constexpr double kSpineShare[3] = {0.40, 0.35, 0.25};
constexpr double kHipsCrouch = 0.05;  // root lowered [m] so both knees stay bent

// shake_shoulders: alternating shoulder shimmy at 3.5 Hz — the collars protract/retract ±12°
// (left forward while right goes back), the chest twists ±4° with them and the neck undoes the twist
// so the head keeps facing forward. The arms hang 65° down and follow the shoulder girdle.
constexpr double kShouldersFrequency = 3.5;  // [Hz]
constexpr double kShouldersProtraction = deg(12.0);
constexpr double kShouldersChestTwist = deg(4.0);

constexpr double kArmsDown = deg(65.0);
constexpr double kElbow = deg(20.0);

void hang_arms(Pose& theta, double protraction_left, double protraction_right) {
  ArmAngles arm;
  arm.down = kArmsDown;
  arm.elbow_flexion = kElbow;
  arm.protraction = protraction_left;
  set_arm(theta, Side::kLeft, arm);
  arm.protraction = protraction_right;
  set_arm(theta, Side::kRight, arm);
}

}  // namespace

PoseSample sample_shake_hips(double t) {
  const double phase = 2.0 * kPi * kHipsFrequency * t;
  const double roll = kHipsRoll * std::sin(phase);
  const double yaw = -kHipsYaw * std::cos(phase);
  const Eigen::Quaterniond pelvis = rot_y(yaw) * rot_z(roll);

  PoseSample steady;
  set_joint(steady.theta, kPelvis, pelvis);
  // Counter-rotation: spine1·spine2·spine3 = pelvis⁻¹ exactly (powers of one rotation commute).
  const Eigen::Quaterniond undo = pelvis.conjugate();
  set_joint(steady.theta, kSpine1, fraction(undo, kSpineShare[0]));
  set_joint(steady.theta, kSpine2, fraction(undo, kSpineShare[1]));
  set_joint(steady.theta, kSpine3, fraction(undo, kSpineShare[2]));

  // Root translation: spine3 = trans + R_p s₁ + R_p^{0.6} s₂ + R_p^{0.25} s₃ is kept at its rest
  // place (minus the crouch); the global rotations of the pelvis, spine1 and spine2 are powers of R_p.
  const Eigen::Vector3d s1 = NominalSpine::pelvis_to_spine1(), s2 = NominalSpine::spine1_to_spine2(),
                        s3 = NominalSpine::spine2_to_spine3();
  const Eigen::Vector3d chest =
      pelvis * s1 + fraction(pelvis, 1.0 - kSpineShare[0]) * s2 + fraction(pelvis, kSpineShare[2]) * s3;
  steady.trans = (s1 + s2 + s3) - chest + Eigen::Vector3d(0.0, -kHipsCrouch, 0.0);

  // Feet stay planted where they are in the rest pose (two-bone IK on the nominal leg).
  plant_feet(steady.theta, pelvis, steady.trans);
  hang_arms(steady.theta, 0.0, 0.0);
  return scaled_from_rest(steady, ease_in(t, kEaseInSeconds).v);
}

PoseSample sample_shake_shoulders(double t) {
  const double wave = std::sin(2.0 * kPi * kShouldersFrequency * t);
  PoseSample steady;
  set_joint(steady.theta, kSpine3, rot_y(-kShouldersChestTwist * wave));  // left shoulder forward: about −Y
  set_joint(steady.theta, kNeck, rot_y(kShouldersChestTwist * wave));
  hang_arms(steady.theta, kShouldersProtraction * wave, -kShouldersProtraction * wave);
  return scaled_from_rest(steady, ease_in(t, kEaseInSeconds).v);
}

}  // namespace sflsh::body::motion_detail
