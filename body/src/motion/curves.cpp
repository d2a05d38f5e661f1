#include "curves.hpp"

#include <sflsh/core/error.hpp>

#include <algorithm>
#include <cassert>

namespace sflsh::body::motion_detail {

Jet acos(Jet a) {
  const double x = a.v;
  const double s2 = 1.0 - x * x;
  assert(s2 > 0.0);
  const double s = std::sqrt(s2);
  return chain(a, std::acos(x), -1.0 / s, -x / (s2 * s));
}

Jet pow(Jet a, int n) {
  Jet out = constant(1.0);
  for (int i = 0; i < n; ++i) out = out * a;
  return out;
}

Jet smoothstep(Jet x) {
  if (x.v <= 0.0) return constant(0.0);
  if (x.v >= 1.0) return constant(1.0);
  // s(x) = x⁴ (35 − 84x + 70x² − 20x³); s' = 140 x³ (1 − x)³; s'' = 420 x² (1 − x)² (1 − 2x).
  const double u = x.v;
  const double s = u * u * u * u * (35.0 + u * (-84.0 + u * (70.0 - 20.0 * u)));
  const double s1 = 140.0 * u * u * u * (1.0 - u) * (1.0 - u) * (1.0 - u);
  const double s2 = 420.0 * u * u * (1.0 - u) * (1.0 - u) * (1.0 - 2.0 * u);
  return chain(x, s, s1, s2);
}

Jet ease_in(double t, double duration) {
  require(duration > 0.0, "ease_in: duration must be positive, got {}", duration);
  return smoothstep(Jet{t / duration, 1.0 / duration, 0.0});
}

Jet raised_cosine_pulse(Jet phase, int n) { return pow(0.5 * (cos(phase) + 1.0), n); }

Jet hermite_quintic(const Jet& a, const Jet& b, double h, double s) {
  assert(h > 0.0);
  const Jet x{s / h, 1.0 / h, 0.0};
  const Jet x2 = x * x, x3 = x2 * x, x4 = x3 * x, x5 = x4 * x;
  // Basis on [0, 1] (values, unit slopes, unit curvatures at x = 0 and x = 1).
  const Jet h0 = constant(1.0) - 10.0 * x3 + 15.0 * x4 - 6.0 * x5;
  const Jet h1 = x - 6.0 * x3 + 8.0 * x4 - 3.0 * x5;
  const Jet h2 = 0.5 * (x2 - 3.0 * x3 + 3.0 * x4 - x5);
  const Jet h3 = 0.5 * (x3 - 2.0 * x4 + x5);
  const Jet h4 = -4.0 * x3 + 7.0 * x4 - 3.0 * x5;
  const Jet h5 = 10.0 * x3 - 15.0 * x4 + 6.0 * x5;
  return a.v * h0 + (a.d * h) * h1 + (a.dd * h * h) * h2 + (b.dd * h * h) * h3 + (b.d * h) * h4 + b.v * h5;
}

Jet sin2_bump_integral(double u, double width) {
  if (u <= 0.0) return constant(0.0);
  if (u >= width) return {width * width / 4.0 + 0.5 * width * (u - width), 0.5 * width, 0.0};
  // ∫₀ᵘ sin²(πs/w) ds = u/2 − (w/4π) sin(2πu/w);  ∫₀ᵘ of that = u²/4 + (w²/8π²)(cos(2πu/w) − 1).
  const double k = 2.0 * kPi / width;
  const double sn = std::sin(kPi * u / width);
  return {u * u / 4.0 + (std::cos(k * u) - 1.0) / (2.0 * k * k), 0.5 * u - std::sin(k * u) / (2.0 * k), sn * sn};
}

HopProfile::HopProfile(double period, double stance, double impact_width, double impact_peak, double pushoff_peak)
    : period_(period),
      stance_(stance),
      impact_width_(impact_width),
      impact_peak_(impact_peak),
      pushoff_peak_(pushoff_peak) {
  require(period > 0.0 && stance > 0.0 && stance < period, "HopProfile: need 0 < stance ({}) < period ({})", stance,
          period);
  require(impact_width > 0.0 && 2.0 * impact_width <= stance,
          "HopProfile: need 0 < impact width ({}) <= stance / 2 ({})", impact_width, stance / 2.0);
  require(impact_peak >= 0.0 && pushoff_peak >= 0.0, "HopProfile: peaks must be non-negative");
  const double g = kGravity, T = period, tau = stance, w = impact_width, tf = T - tau;
  // Momentum over one period: ∫c = gT; a sin² bump of width w carries w/2.
  push_peak_ = (g * T - (impact_peak + pushoff_peak) * w / 2.0) / (tau / 2.0);
  require(push_peak_ > 0.0, "HopProfile: the impact and push-off peaks carry more than the period's impulse");
  // Stance: y(τ) = −v_L τ − gτ²/2 + J with J = ∫₀^τ∫₀^s c = P₁B(τ; w) + P₃ w²/4 + P₂B(τ; τ)
  // (the push-off bump's double integral is ∫₀^w q b(q/w) dq = w²/4). Flight back to y = 0 in t_f with
  // ẏ(τ) = g t_f − v_L gives y(τ) = v_L t_f − g t_f²/2. Equating: v_L T = g (t_f² − τ²)/2 + J.
  const double J = impact_peak * sin2_bump_integral(tau, w).v + pushoff_peak * w * w / 4.0 +
                   push_peak_ * sin2_bump_integral(tau, tau).v;
  landing_speed_ = (g * (tf * tf - tau * tau) / 2.0 + J) / T;
  takeoff_speed_ = g * tf - landing_speed_;
  takeoff_height_ = landing_speed_ * tf - g * tf * tf / 2.0;
  require(takeoff_speed_ > 0.0 && landing_speed_ > 0.0, "HopProfile: no flight (take-off speed {} m/s)",
          takeoff_speed_);
}

double HopProfile::cycle_time(double t) const {
  double u = std::fmod(t, period_);
  if (u < 0.0) u += period_;
  return u;
}

Jet HopProfile::height(double t) const {
  const double g = kGravity;
  const double u = cycle_time(t);
  if (u < stance_) {
    const Jet impact = sin2_bump_integral(u, impact_width_);
    const Jet push = sin2_bump_integral(u, stance_);
    // The push-off bump is the impact bump mirrored in time; sin² is symmetric, so it is the same
    // double integral started at τ − w.
    const Jet pushoff = sin2_bump_integral(u - (stance_ - impact_width_), impact_width_);
    const Jet free_fall{-landing_speed_ * u - 0.5 * g * u * u, -landing_speed_ - g * u, -g};
    return free_fall + impact_peak_ * impact + push_peak_ * push + pushoff_peak_ * pushoff;
  }
  const double f = u - stance_;
  return {takeoff_height_ + takeoff_speed_ * f - 0.5 * g * f * f, takeoff_speed_ - g * f, -g};
}

}  // namespace sflsh::body::motion_detail
