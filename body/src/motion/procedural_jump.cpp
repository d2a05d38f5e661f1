// one_leg_jump: hopping on the left leg, the right leg bent and lifted (DYNA training motion).
//
// The root's height is a HopProfile (curves.hpp): 2 hops/s, 0.28 s contact, 0.22 s of ballistic
// flight (ÿ = −g exactly), an M-shaped contact acceleration with a 60 ms landing impact of 5 g and a
// push-off peak of 3.5 g. Net root deceleration peaks at ≈ 4.2 g just after touchdown.
//
// The stance leg keeps the ball of the foot on the ground (nominal leg, rig.hpp) during contact:
//  - the knee follows a smooth periodic curve, 12° + 30° · pulse, deepest (42°) at the lowest point;
//  - the ankle supplies the rest of the height: the heel rise A = y_root + leg_drop(κ) gives the foot
//    pitch p = toe_rise⁻¹(A) (forefoot landing at ≈ 13°, heel nearly down (≈ 3°) just after the
//    impact, ≈ 21° at take-off);
//  - during flight the foot pitch follows quintic Hermite bridges from take-off through a mid-flight
//    waypoint (toes pointed, ≈ 32–35°) to the next touchdown, so θ stays C².
// The hip flexes κ/2 plus the forward tilt that keeps the ball of the foot in place while the foot
// pivots (rig.hpp planted_leg), and adducts so the foot is under the body, whose root shifts 5 cm
// toward the stance side. The root itself only moves vertically (the flight stays exactly ballistic).
// The stance geometry ignores the tilt's and the adduction's vertical effect (≈ 1–2 mm).
// Joint angles and the lateral shift are scaled by the 0.5 s ease-in from the T-pose; the root
// height does a countermovement during the ease-in and joins the hop at its lowest point (t = 0.5 s),
// so the first take-off is at t ≈ 0.66 s and the first landing at t ≈ 0.88 s. (During the ease-in
// the legs are the scaled hop pose, not kinematically tied to the root.)
#include "curves.hpp"
#include "procedural.hpp"
#include "rig.hpp"

#include <sflsh/core/error.hpp>

#include <algorithm>
#include <cmath>

namespace sflsh::body::motion_detail {

namespace {

constexpr double kPeriod = 0.5;        // [s] (2 hops/s)
constexpr double kStance = 0.28;       // [s]
constexpr double kImpactWidth = 0.06;  // [s]
constexpr double kImpactPeak = 5.0 * kGravity;
constexpr double kPushoffPeak = 3.5 * kGravity;
constexpr double kRootOffset = 0.018;  // root height above the touchdown reference [m] (keeps the heel up)
constexpr double kKneeBase = deg(12.0);
constexpr double kKneeLoad = deg(30.0);
constexpr double kFlightPitch = deg(32.0);  // toes pointed at mid-flight
constexpr double kLateralShift = 0.05;      // root toward the stance (left) side [m]
constexpr double kFreeHip = deg(30.0);
constexpr double kFreeKnee = deg(75.0);
constexpr double kFreeAnkle = deg(10.0);
constexpr double kArmsDown = deg(55.0);
constexpr double kElbow = deg(35.0);

const HopProfile& hop() {
  static const HopProfile profile(kPeriod, kStance, kImpactWidth, kImpactPeak, kPushoffPeak);
  return profile;
}

/// Time of the root's lowest point after touchdown [s] (where the knee is most flexed).
double lowest_point_time() {
  static const double u_low = [] {
    double best = 0.0, y_best = 0.0;
    for (int i = 0; i <= 2800; ++i) {
      const double u = kStance * i / 2800.0;
      const double y = hop().height(u).v;
      if (y < y_best) y_best = y, best = u;
    }
    return best;
  }();
  return u_low;
}

/// Knee flexion over the cycle (u = time since touchdown), a smooth periodic function.
Jet knee_flexion(double u) {
  const Jet phase{2.0 * kPi * (u - lowest_point_time()) / kPeriod, 2.0 * kPi / kPeriod, 0.0};
  return kKneeBase + kKneeLoad * raised_cosine_pulse(phase, 2);
}

/// Foot pitch p with toe_rise(p) = a, and its time derivatives (inverse-function rule).
Jet inverse_toe_rise(const Jet& a) {
  double p = a.v / NominalLeg::ankle_to_ball;
  for (int it = 0; it < 30; ++it) {  // Newton; toe_rise is increasing and concave on [0, 60°]
    const double r1 = NominalLeg::ankle_to_ball * std::cos(p) - NominalLeg::ankle_height * std::sin(p);
    const double step = (toe_rise(p) - a.v) / r1;
    p -= step;
    if (std::abs(step) < 1e-15) break;
  }
  require(p >= 0.0 && p < deg(60.0), "one_leg_jump: heel rise {:.4f} m out of the foot's range", a.v);
  const double r1 = NominalLeg::ankle_to_ball * std::cos(p) - NominalLeg::ankle_height * std::sin(p);
  const double r2 = -NominalLeg::ankle_to_ball * std::sin(p) - NominalLeg::ankle_height * std::cos(p);
  const double p1 = a.d / r1;
  return {p, p1, (a.dd - r2 * p1 * p1) / r1};
}

/// Stance-leg foot pitch while the ball of the foot is on the ground (u ∈ [0, τ]).
Jet stance_pitch(double u) {
  const Jet knee = knee_flexion(u);
  const Jet drop = 2.0 * NominalLeg::thigh * (constant(1.0) - cos(0.5 * knee));
  return inverse_toe_rise(hop().height(u) + kRootOffset + drop);
}

/// Foot pitch over the whole cycle: the stance formula, bridged through the flight by two quintics
/// that meet at mid-flight with the toes pointed at kFlightPitch (at rest: zero slope and curvature).
/// One quintic from take-off to touchdown would carry the push-off's plantar-flexion rate
/// (≈ 8 rad/s) to ≈ 50°; the mid-flight waypoint keeps the ankle near 35°.
double foot_pitch(double u) {
  if (u <= kStance) return stance_pitch(u).v;
  static const Jet takeoff = stance_pitch(kStance);
  static const Jet touchdown = stance_pitch(0.0);
  const double half = 0.5 * (kPeriod - kStance);
  const Jet apex = constant(kFlightPitch);
  if (u <= kStance + half) return hermite_quintic(takeoff, apex, half, u - kStance).v;
  return hermite_quintic(apex, touchdown, half, u - kStance - half).v;
}

/// Root height: the hop after the ease-in; during it, a countermovement from standing (quintic from
/// rest to the hop's lowest point, matching height, speed 0 and acceleration), so that ÿ stays
/// within [−0.25 g, 0.7 g] there (scaling the hop itself would make ÿ < −g in the first flight).
double root_height(double t, double t_hop) {
  if (t >= kEaseInSeconds) return hop().height(t_hop).v + kRootOffset;
  static const Jet lowest = hop().height(lowest_point_time()) + kRootOffset;
  return hermite_quintic(constant(0.0), lowest, kEaseInSeconds, std::max(t, 0.0)).v;
}

}  // namespace

PoseSample sample_one_leg_jump(double t) {
  // The steady hop is timed so that t = kEaseInSeconds is its lowest point (mid-stance).
  const double t_hop = t - kEaseInSeconds + lowest_point_time();
  const double u = hop().cycle_time(t_hop);
  const double knee = knee_flexion(u).v;
  const double pitch = foot_pitch(u);

  PoseSample steady;
  LegAngles stance = planted_leg(knee, pitch);  // cumulative foot pitch p, ankle under the pivot
  const double leg_length = NominalLeg::thigh + NominalLeg::shank;
  stance.hip_abduction = -std::atan2(kLateralShift, leg_length);  // foot under the shifted root
  set_leg(steady.theta, Side::kLeft, stance);

  LegAngles free;
  free.hip_flexion = kFreeHip;
  free.knee_flexion = kFreeKnee;
  free.ankle_plantar_flexion = kFreeAnkle;
  set_leg(steady.theta, Side::kRight, free);

  ArmAngles arm;
  arm.down = kArmsDown;
  arm.elbow_flexion = kElbow;
  set_arm(steady.theta, Side::kLeft, arm);
  set_arm(steady.theta, Side::kRight, arm);

  steady.trans = {kLateralShift, 0.0, 0.0};
  PoseSample out = scaled_from_rest(steady, ease_in(t, kEaseInSeconds).v);
  out.trans.y() = root_height(t, t_hop);
  return out;
}

}  // namespace sflsh::body::motion_detail
