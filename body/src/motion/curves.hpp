#pragma once
// Smooth scalar curves of time for the procedural motions (private to sflsh::body).
//
// Every curve is returned as a Jet (value and first two time derivatives), so that motions can be
// glued together with C² continuity (quintic Hermite bridges) and tests can compare the analytic
// accelerations against finite differences. Units: time in seconds, angles in radians, lengths in
// metres, unless a comment says otherwise.
#include <cmath>

namespace sflsh::body::motion_detail {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kGravity = 9.81;  ///< [m/s²]

inline constexpr double deg(double degrees) { return degrees * kPi / 180.0; }

/// A value with its first and second derivatives with respect to time: (f, f', f'').
struct Jet {
  double v = 0.0;
  double d = 0.0;
  double dd = 0.0;
};

inline Jet constant(double value) { return {value, 0.0, 0.0}; }
inline Jet operator+(Jet a, Jet b) { return {a.v + b.v, a.d + b.d, a.dd + b.dd}; }
inline Jet operator-(Jet a, Jet b) { return {a.v - b.v, a.d - b.d, a.dd - b.dd}; }
inline Jet operator-(Jet a) { return {-a.v, -a.d, -a.dd}; }
inline Jet operator*(double s, Jet a) { return {s * a.v, s * a.d, s * a.dd}; }
inline Jet operator*(Jet a, double s) { return s * a; }
/// Product rule: (fg)'' = f''g + 2f'g' + fg''.
inline Jet operator*(Jet a, Jet b) {
  return {a.v * b.v, a.d * b.v + a.v * b.d, a.dd * b.v + 2.0 * a.d * b.d + a.v * b.dd};
}
inline Jet operator+(Jet a, double s) { return {a.v + s, a.d, a.dd}; }
inline Jet operator-(Jet a, double s) { return {a.v - s, a.d, a.dd}; }
inline Jet operator+(double s, Jet a) { return a + s; }
inline Jet operator-(double s, Jet a) { return {s - a.v, -a.d, -a.dd}; }

/// Chain rule for an outer function with value g, slope g1 and curvature g2 at a.v:
/// (g∘a)' = g1 a',  (g∘a)'' = g2 a'² + g1 a''.
inline Jet chain(Jet a, double g, double g1, double g2) { return {g, g1 * a.d, g2 * a.d * a.d + g1 * a.dd}; }
inline Jet sin(Jet a) { return chain(a, std::sin(a.v), std::cos(a.v), -std::sin(a.v)); }
inline Jet cos(Jet a) { return chain(a, std::cos(a.v), -std::sin(a.v), -std::cos(a.v)); }
/// acos on (−1, 1): slope −1/√(1−x²), curvature −x/(1−x²)^{3/2}.
Jet acos(Jet a);
/// Integer power n ≥ 0.
Jet pow(Jet a, int n);

/// The time variable itself: t ↦ (t, 1, 0).
inline Jet time_jet(double t) { return {t, 1.0, 0.0}; }

/// Septic smoothstep s(x) = 35x⁴ − 84x⁵ + 70x⁶ − 20x⁷ on [0, 1], 0 below, 1 above: its first three
/// derivatives vanish at both ends, so a curve switched on with it stays C³.
Jet smoothstep(Jet x);

/// Ease-in envelope of duration `duration` [s]: smoothstep(t / duration). 0 at t ≤ 0, 1 after.
Jet ease_in(double t, double duration);

/// Raised-cosine pulse ((1 + cos φ)/2)^n: 1 at φ = 0 (mod 2π), smooth (analytic) and periodic,
/// narrower for larger n (n = 2: half width at half maximum 65.5°; n = 4: 47°).
Jet raised_cosine_pulse(Jet phase, int n);

/// Quintic Hermite bridge on [0, h]: the unique quintic with the given value, slope and curvature
/// at both ends (a = start, b = end), evaluated at s ∈ [0, h]. Gluing curve pieces with it keeps C².
Jet hermite_quintic(const Jet& a, const Jet& b, double h, double s);

/// Double integral of the sin² bump b(u) = sin²(πu/w) on [0, w] (zero outside), from u = 0:
/// B(u) = ∫₀ᵘ∫₀ˢ b. Returned as (B, B' = ∫₀ᵘ b, B'' = b(u)). For u ≥ w: B = w²/4 + (w/2)(u − w).
Jet sin2_bump_integral(double u, double width);

/// Vertical motion of periodic hopping with a flight phase, as a point mass under gravity with a
/// smooth contact acceleration (docs/architecture.md §2, one-leg jump).
///
/// One period T: stance u ∈ [0, τ) from touchdown (u = 0) to take-off, then ballistic flight
/// (ÿ = −g exactly) until the next touchdown at u = T. The contact acceleration is an M-shaped
/// ground reaction: a short landing impact, a push bump spanning the stance and a short push-off peak,
/// \f[ c(u) = P_1\, b\!\left(\tfrac{u}{w}\right) + P_2\, b\!\left(\tfrac{u}{\tau}\right)
///          + P_3\, b\!\left(\tfrac{\tau - u}{w}\right), \qquad b(x) = \sin^2(\pi x)\ \text{on}\ [0, 1], \f]
/// Each bump starts and ends with zero value and slope, so ÿ is C¹ (y is C³, jerk continuous).
/// P₂ follows from momentum (the stance impulse ∫c = gT), the landing speed from closing the period
/// (the flight parabola ends at the touchdown height). With P₃ ≠ P₁ the body takes off at a different
/// height than it lands (takeoff_height()); the legs account for that with the ankles.
class HopProfile {
 public:
  /// @param period        T, time between touchdowns [s]
  /// @param stance        τ < T, contact duration [s]
  /// @param impact_width  w ≤ τ/2, duration of the landing impact and of the push-off peak [s]
  /// @param impact_peak   P₁, peak contact acceleration of the landing impact [m/s²] (before −g)
  /// @param pushoff_peak  P₃, peak contact acceleration of the push-off [m/s²]
  HopProfile(double period, double stance, double impact_width, double impact_peak, double pushoff_peak);

  /// Height relative to the touchdown height at time t [s] (t = 0 is a touchdown), with ẏ and ÿ.
  Jet height(double t) const;
  /// Time since the last touchdown, in [0, T).
  double cycle_time(double t) const;

  double period() const { return period_; }
  double stance() const { return stance_; }
  double flight() const { return period_ - stance_; }
  double push_peak() const { return push_peak_; }            ///< P₂ [m/s²]
  double landing_speed() const { return landing_speed_; }    ///< |ẏ| at touchdown [m/s]
  double takeoff_speed() const { return takeoff_speed_; }    ///< ẏ at take-off [m/s]
  double takeoff_height() const { return takeoff_height_; }  ///< y at take-off [m]

 private:
  double period_, stance_, impact_width_, impact_peak_, pushoff_peak_;
  double push_peak_ = 0.0, landing_speed_ = 0.0, takeoff_speed_ = 0.0, takeoff_height_ = 0.0;
};

}  // namespace sflsh::body::motion_detail
