// jiggle_on_toes: bouncing on the balls of both feet (DYNA test motion).
//
// The feet pivot about the balls of the feet: plantar flexion p(t) raises the heels, the knees flex
// slightly in antiphase (more flexed at the bottom), the legs tilt forward by the ankles' shift about
// the pivot (rig.hpp planted_leg) so the body stays over the balls of the feet, and the root height follows
// from the nominal leg geometry so that the balls of the feet stay planted:
//   y = planted_leg_height(κ, p)   (docs/architecture.md §2: 2–4 cm at 2.5–3 Hz).
// With p = 18° ± 7° and κ = 8° ∓ 5° at 2.75 Hz the root bounces ≈ 3.1 cm peak to peak (≈ 0.6 g peak
// acceleration). Everything is scaled by a 0.5 s ease-in from the T-pose.
#include "curves.hpp"
#include "procedural.hpp"
#include "rig.hpp"

namespace sflsh::body::motion_detail {

namespace {
constexpr double kFrequency = 2.75;       // bounces per second [Hz]
constexpr double kPitchMean = deg(18.0);  // heel raise (foot pitch) [rad]
constexpr double kPitchAmplitude = deg(7.0);
constexpr double kKneeMean = deg(8.0);
constexpr double kKneeAmplitude = deg(5.0);
constexpr double kArmsDown = deg(65.0);
constexpr double kElbow = deg(15.0);
}  // namespace

PoseSample sample_jiggle_on_toes(double t) {
  const double e = ease_in(t, kEaseInSeconds).v;
  const double wave = std::sin(2.0 * kPi * kFrequency * t);
  const double pitch = e * (kPitchMean + kPitchAmplitude * wave);
  const double knee = e * (kKneeMean - kKneeAmplitude * wave);

  PoseSample out;
  const LegAngles leg = planted_leg(knee, pitch);
  set_leg(out.theta, Side::kLeft, leg);
  set_leg(out.theta, Side::kRight, leg);

  ArmAngles arm;
  arm.down = e * kArmsDown;
  arm.elbow_flexion = e * kElbow;
  set_arm(out.theta, Side::kLeft, arm);
  set_arm(out.theta, Side::kRight, arm);

  out.trans = {0.0, planted_leg_height(knee, pitch), 0.0};
  return out;
}

}  // namespace sflsh::body::motion_detail
