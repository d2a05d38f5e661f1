// The integrators of model/time_integrator.hpp on an undamped oscillator m p̈ = −k p (three independent axes),
// whose step minimizes m/(2ĥ²)|p − p̃|² + k/2 |p|² in closed form: p = (m/ĥ²) p̃ / (m/ĥ² + k).
#include <sflsh/core/error.hpp>
#include <sflsh/model/time_integrator.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace sflsh::model {
namespace {

constexpr double kMass = 2.0;        // [kg]
constexpr double kStiffness = 50.0;  // [N/m]
const double kOmega = std::sqrt(kStiffness / kMass);
const double kPeriod = 2.0 * std::numbers::pi / kOmega;

PosedHistory start() {
  PosedHistory history;
  history.p = Eigen::Vector3d(0.01, -0.02, 0.0);  // [m]
  history.v = Eigen::Vector3d(0.0, 0.05, 0.1);    // [m/s]
  history.a = -kStiffness / kMass * history.p;    // the equation of motion at t = 0
  return history;
}

void step(Integrator integrator, PosedHistory& history, double h) {
  const InertiaTarget target = inertia_target(integrator, history, h);
  const double w = kMass / (target.h_eff * target.h_eff);
  advance_history(target, history, Eigen::VectorXd(w * target.p_tilde / (w + kStiffness)));
}

double energy(const PosedHistory& history) {
  return 0.5 * kMass * history.v.squaredNorm() + 0.5 * kStiffness * history.p.squaredNorm();
}

Eigen::Vector3d exact(double t) {
  const PosedHistory s = start();
  return s.p * std::cos(kOmega * t) + s.v / kOmega * std::sin(kOmega * t);
}

/// |p(T) − p_exact(T)| after T = `periods` periods in steps of T/(steps per period).
double error_after(Integrator integrator, double periods, int steps_per_period) {
  PosedHistory history = start();
  const int steps = static_cast<int>(std::lround(periods * steps_per_period));
  const double h = kPeriod / steps_per_period;
  for (int k = 0; k < steps; ++k) step(integrator, history, h);
  return (history.p - exact(steps * h)).norm();
}

TEST(TimeIntegrator, NewmarkKeepsTheEnergyOfAnUndampedOscillatorOver50Periods) {
  // 20 steps per period (ωh = 0.31): the trapezoidal rule conserves the quadratic energy of a linear system
  // exactly (up to round-off), so no growth and far below the 0.5 % allowed.
  PosedHistory history = start();
  const double e0 = energy(history);
  double largest = e0, smallest = e0;
  for (int k = 0; k < 50 * 20; ++k) {
    step(Integrator::newmark, history, kPeriod / 20.0);
    largest = std::max(largest, energy(history));
    smallest = std::min(smallest, energy(history));
  }
  EXPECT_LE(largest, e0 * (1.0 + 1e-10));
  EXPECT_GE(smallest, e0 * (1.0 - 5e-3));
}

TEST(TimeIntegrator, BackwardEulerAndBdf2DampNewmarkDoesNot) {
  auto energy_after = [](Integrator integrator) {
    PosedHistory history = start();
    for (int k = 0; k < 5 * 20; ++k) step(integrator, history, kPeriod / 20.0);
    return energy(history) / energy(start());
  };
  const double be = energy_after(Integrator::backward_euler), bdf2 = energy_after(Integrator::bdf2),
               newmark = energy_after(Integrator::newmark);
  EXPECT_LT(be, bdf2);   // first-order damping removes most of the energy in 5 periods
  EXPECT_LT(bdf2, 1.0);  // BDF2 damps mildly
  EXPECT_GT(bdf2, 0.5);
  EXPECT_NEAR(newmark, 1.0, 1e-10);
}

TEST(TimeIntegrator, ObservedOrdersOfConvergence) {
  // Error after two periods at n and 2n steps per period: the ratio is 2^order within the asymptotic range, which
  // for backward Euler starts only near ωh ≈ 0.01 (its amplitude decays as exp(−ω²ht/2): 63 % in two periods at
  // 40 steps per period), for the second-order schemes already at 40 steps per period.
  auto order = [](Integrator integrator, int steps_per_period) {
    return std::log2(error_after(integrator, 2.0, steps_per_period) /
                     error_after(integrator, 2.0, 2 * steps_per_period));
  };
  EXPECT_NEAR(order(Integrator::backward_euler, 800), 1.0, 0.1);
  EXPECT_NEAR(order(Integrator::bdf2, 40), 2.0, 0.1);
  EXPECT_NEAR(order(Integrator::newmark, 40), 2.0, 0.1);
}

TEST(TimeIntegrator, VariableStepBdf2StaysSecondOrder) {
  // Alternating steps h and h/2 (ω = ½ and 2): still second order.
  auto error = [](int pairs_per_period) {
    PosedHistory history = start();
    const double h = kPeriod / (1.5 * pairs_per_period);
    double t = 0.0;
    for (int k = 0; k < 2 * pairs_per_period; ++k) {
      step(Integrator::bdf2, history, h);
      step(Integrator::bdf2, history, 0.5 * h);
      t += 1.5 * h;
    }
    return (history.p - exact(t)).norm();
  };
  EXPECT_NEAR(std::log2(error(30) / error(60)), 2.0, 0.2);
}

TEST(TimeIntegrator, Bdf2StartsAndRestartsAsBackwardEuler) {
  PosedHistory history = start();
  EXPECT_EQ(inertia_target(Integrator::bdf2, history, 0.01).integrator, Integrator::backward_euler);
  step(Integrator::bdf2, history, 0.01);
  EXPECT_EQ(inertia_target(Integrator::bdf2, history, 0.01).integrator, Integrator::bdf2);
  EXPECT_EQ(inertia_target(Integrator::bdf2, history, 0.05).integrator, Integrator::backward_euler);  // ω = 5
}

TEST(TimeIntegrator, NewmarkNeedsAccelerationsAndNamesParse) {
  PosedHistory history = start();
  history.a.resize(0);
  EXPECT_THROW(inertia_target(Integrator::newmark, history, 0.01), Error);
  EXPECT_EQ(parse_integrator("bdf2", "test"), Integrator::bdf2);
  EXPECT_EQ(to_string(parse_integrator("newmark", "test")), "newmark");
  try {
    parse_integrator("rk4", "scene.toml:3: integrator");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("backward_euler, bdf2, newmark"), std::string::npos);
  }
  EXPECT_EQ(parse_mass_kind("consistent", "x"), MassKind::consistent);
  EXPECT_THROW(parse_mass_kind("diagonal", "x"), Error);
}

}  // namespace
}  // namespace sflsh::model
