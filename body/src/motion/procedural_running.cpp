// running_on_spot: jogging in place with high knees (DYNA training motion).
//
// Stride phase φ = 2π t / T_stride with 2.7 steps/s (T_stride = 0.741 s); the left foot's mid-stance
// is at φ = 0, the right one's at φ = π. Each leg is a blend of a stance posture (on the forefoot,
// heel up 8°, the knee flexing with the bounce, ≈ 17°–31°, so the ball of the foot stays on the ground
// on the nominal leg) and a swing posture (hip 45°, knee 90°), weighted by a raised-cosine lift
// pulse that peaks 0.1 stride after the other foot's mid-stance. The arms counter-swing ±30° with
// elbows near 85°, and the chest twists ±6° with the arms.
//
// The root bounces twice per stride (step phase ψ = 2φ): y = −a (cos ψ + 0.2 cos 2ψ), a = 2 cm, i.e.
// 4 cm peak to peak, lowest at mid-stance. The second harmonic sharpens the landing: peak upward
// acceleration ≈ 1.06 g at mid-stance, least −0.55 g, so a foot is always loaded (jogging in place
// has little flight; the flight phase is the one-leg jump's job).
#include "curves.hpp"
#include "procedural.hpp"
#include "rig.hpp"

namespace sflsh::body::motion_detail {

namespace {
constexpr double kStepsPerSecond = 2.7;
constexpr double kBounce = 0.02;          // a [m]; peak to peak 2a
constexpr double kBounceSharpness = 0.2;  // second-harmonic share
constexpr double kCrouch = 0.015;         // mean root lowering [m]
constexpr double kSwingLead = 0.2 * kPi;  // lift peak after the other foot's mid-stance [rad of stride]
constexpr double kHipMax = deg(45.0);
constexpr double kKneeMax = deg(90.0);
constexpr double kStancePitch = deg(8.0);   // on the forefoot, heel slightly up
constexpr double kSwingAnkle = deg(-15.0);  // swing foot slightly dorsiflexed (toes 30° down)
constexpr double kArmSwing = deg(30.0);
constexpr double kElbow = deg(85.0);
constexpr double kElbowSwing = deg(10.0);
constexpr double kArmsDown = deg(70.0);
constexpr double kTrunkLean = deg(4.0);
constexpr double kChestTwist = deg(6.0);

/// One leg: `lift` ∈ [0, 1] blends the stance posture (ball of the foot planted under the root at
/// height `root_y`) into the swing posture.
LegAngles leg_angles(double lift, double root_y) {
  const double stance_knee = knee_for_drop(toe_rise(kStancePitch) - root_y);
  const LegAngles stance = planted_leg(stance_knee, kStancePitch);
  LegAngles leg;
  leg.hip_flexion = (1.0 - lift) * stance.hip_flexion + lift * kHipMax;
  leg.knee_flexion = (1.0 - lift) * stance.knee_flexion + lift * kKneeMax;
  leg.ankle_plantar_flexion = (1.0 - lift) * stance.ankle_plantar_flexion + lift * kSwingAnkle;
  leg.toe_extension = (1.0 - lift) * stance.toe_extension;
  return leg;
}
}  // namespace

PoseSample sample_running_on_spot(double t) {
  const double stride_period = 2.0 / kStepsPerSecond;
  const double phi = 2.0 * kPi * t / stride_period;
  const double lift_left = raised_cosine_pulse(constant(phi - kPi - kSwingLead), 2).v;
  const double lift_right = raised_cosine_pulse(constant(phi - kSwingLead), 2).v;
  const double psi = 2.0 * phi;
  const double root_y = -kBounce * (std::cos(psi) + kBounceSharpness * std::cos(2.0 * psi)) - kCrouch;

  PoseSample steady;
  set_leg(steady.theta, Side::kLeft, leg_angles(lift_left, root_y));
  set_leg(steady.theta, Side::kRight, leg_angles(lift_right, root_y));

  // Counter-swing: the left arm goes forward while the right knee is up.
  const double a = lift_right - lift_left;
  ArmAngles arm;
  arm.down = kArmsDown;
  arm.elbow_flexion = kElbow;
  set_arms_in_opposition(steady.theta, arm, kArmSwing * a, kElbowSwing * a);
  set_joint(steady.theta, kSpine1, rot_x(kTrunkLean));
  set_joint(steady.theta, kSpine3, rot_y(-kChestTwist * a));  // left shoulder forward with the left arm

  steady.trans.y() = root_y;
  return scaled_from_rest(steady, ease_in(t, kEaseInSeconds).v);
}

}  // namespace sflsh::body::motion_detail
