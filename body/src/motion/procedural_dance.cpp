// dance: a looping whole-body groove for crowd showcases (not a DYNA motion; SFLSH Fig. 1).
//
// One bar of four beats at 120 bpm, period T = 2 s, bar phase φ = 2π t / T; every channel is a
// trigonometric polynomial in φ with integer harmonics, so the steady part is C^∞ and exactly
// T-periodic (a motion offset by T is the same motion):
//  - hips sway once per bar, ±4.5 cm sideways (sin φ), the pelvis rolling ±7° with them (the hip of the
//    side the weight moves to goes up) and yawing ±6° (sin 2φ);
//  - knees bounce on every beat: the root drops 3–6 cm ((1 − cos 4φ)/2), the feet stay planted flat
//    where they are in the rest pose (two-bone IK on the nominal leg, rig.hpp), knees ≈ 25°–40°;
//  - the spine undoes most of the pelvis roll and adds a torso twist of ±12° (cos 2φ), the neck
//    turns half of it back so the head faces mostly forward;
//  - the arms hang 60° down and swing ±35° in opposition twice per bar (sin 2φ), elbows 45° ± 20°.
// Like the DYNA motions it leaves the rest T-pose through the 0.5 s ease-in, so a simulation starts at
// rest; a time offset shifts the phase of the steady part only (sample_dance(t, offset)).
#include "curves.hpp"
#include "procedural.hpp"
#include "rig.hpp"

#include <cmath>

namespace sflsh::body::motion_detail {

namespace {

constexpr double kBarSeconds = 2.0;  // T: four beats at 120 bpm
constexpr double kSway = 0.045;      // hip sway amplitude [m]
constexpr double kPelvisRoll = deg(7.0);
constexpr double kPelvisYaw = deg(6.0);
constexpr double kCrouch = 0.03;                          // least root drop [m] (keeps the knees bent)
constexpr double kBounce = 0.03;                          // extra drop at the bottom of each beat [m]
constexpr double kSpineUndoRoll[3] = {0.35, 0.30, 0.20};  // shares of the pelvis roll undone by spine1..3
constexpr double kTorsoTwist = deg(12.0);
constexpr double kNeckShare = 0.5;  // part of the twist the neck turns back
constexpr double kArmsDown = deg(60.0);
constexpr double kArmSwing = deg(35.0);
constexpr double kElbow = deg(45.0);
constexpr double kElbowSwing = deg(20.0);

PoseSample steady_dance(double t) {
  const double phi = 2.0 * kPi * t / kBarSeconds;
  const double sway = std::sin(phi);
  const double swing = std::sin(2.0 * phi);
  const double twist = kTorsoTwist * std::cos(2.0 * phi);
  const double drop = kCrouch + kBounce * 0.5 * (1.0 - std::cos(4.0 * phi));

  // Hips: moving toward the body's left (+X) raises the left hip (roll about +Z).
  const Eigen::Quaterniond pelvis = rot_y(kPelvisYaw * swing) * rot_z(kPelvisRoll * sway);
  PoseSample steady;
  set_joint(steady.theta, kPelvis, pelvis);
  steady.trans = {kSway * sway, -drop, 0.0};

  // Spine: undo part of the roll (the chest stays nearly upright) and twist the torso.
  const Eigen::Quaterniond unroll = rot_z(-kPelvisRoll * sway);
  set_joint(steady.theta, kSpine1, fraction(unroll, kSpineUndoRoll[0]) * rot_y(0.3 * twist));
  set_joint(steady.theta, kSpine2, fraction(unroll, kSpineUndoRoll[1]) * rot_y(0.3 * twist));
  set_joint(steady.theta, kSpine3, fraction(unroll, kSpineUndoRoll[2]) * rot_y(0.4 * twist));
  set_joint(steady.theta, kNeck, rot_y(-kNeckShare * twist));

  // Feet planted flat at their rest places (the knees bend forward, toward +Z).
  plant_feet(steady.theta, pelvis, steady.trans);

  // Arms in opposition: the left arm forward while the right goes back.
  ArmAngles arm;
  arm.down = kArmsDown;
  arm.elbow_flexion = kElbow;
  set_arms_in_opposition(steady.theta, arm, kArmSwing * swing, kElbowSwing * swing);
  return steady;
}

}  // namespace

double dance_period() { return kBarSeconds; }

PoseSample sample_dance(double t, double offset) {
  return scaled_from_rest(steady_dance(t + offset), ease_in(t, kEaseInSeconds).v);
}

}  // namespace sflsh::body::motion_detail
