// The guard of the tets outside the cubature (cubature_guard.hpp): its bound never misses a tet over the limit
// (checked against every tet's exact Fung exponent along a random walk of states), and in the solver a state that
// strains tets the cubature does not see is caught, the tets join the cubature and the step is solved again, where
// without the guard the same step leaves the material's range.
#include "reduced_fixtures.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/material/orthotropic_fung.hpp>
#include <sflsh/reduced/cubature_guard.hpp>
#include <sflsh/reduced/reduced_sensitivity.hpp>
#include <sflsh/reduced/reduced_solver.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <set>

namespace sflsh::reduced {
namespace {

/// Every tet's Fung exponent at the full state x (+∞ where F is not finite or the strain energy overflows).
std::vector<double> exponents(const model::Problem& p, const Eigen::VectorXd& x) {
  std::vector<double> out(static_cast<std::size_t>(p.num_tets()));
  for (int e = 0; e < p.num_tets(); ++e) {
    material::TetNodes nodes;
    for (int a = 0; a < 4; ++a) nodes.col(a) = x.segment<3>(3 * p.tets(e, a));
    try {
      out[static_cast<std::size_t>(e)] =
          material::fung_exponent(material::tet_deformation_gradient(p.tet_rest[static_cast<std::size_t>(e)], nodes),
                                  p.tet_material[static_cast<std::size_t>(e)]);
    } catch (const Error&) {
      out[static_cast<std::size_t>(e)] = std::numeric_limits<double>::infinity();
    }
  }
  return out;
}

Eigen::VectorXd state_of(const model::Problem& p, const Subspace& s, const Eigen::VectorXd& q) {
  Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(p.rest.data(), p.num_dofs());
  s.add_displacement(q, x);
  return x;
}

/// A cubature of `count` tets with Voronoi-like weights that keep the volume: the farthest-point tets.
Cubature sparse_cubature(const model::Problem& p, int count) {
  Cubature c;
  c.tets = farthest_point_tets(p, count, {});
  c.weights = voronoi_weights(p, c.tets);
  c.method = "voronoi";
  return c;
}

TEST(CubatureGuard, TheBoundNeverMissesATetOverTheLimit) {
  const auto c = testing::box_case({5, 4, 3});
  const Subspace s = testing::box_subspace(c);
  const Cubature cubature = sparse_cubature(c.problem, 4);
  constexpr double kLimit = 5.0;  // low, so that the walk crosses it on many tets
  CubatureGuard guard(c.problem, s, cubature, kLimit);
  std::set<int> weighted(cubature.tets.begin(), cubature.tets.end());
  // A random walk from rest with growing steps: the bound must pass every tet under the limit only when it is.
  Eigen::VectorXd q = Eigen::VectorXd::Zero(s.num_dofs());
  int crossed = 0, states = 0;
  for (int step = 0; step < 60; ++step) {
    q += testing::random_q(s.num_dofs(), 0.0005 * (1 + step / 10), 1000 + static_cast<unsigned>(step));
    const std::vector<double> x = exponents(c.problem, state_of(c.problem, s, q));
    std::set<int> expected;
    for (int e = 0; e < c.problem.num_tets(); ++e)
      if (!weighted.count(e) && !(x[static_cast<std::size_t>(e)] <= kLimit)) expected.insert(e);
    std::set<int> reported;
    for (const GuardViolation& v : guard.check(q)) {
      reported.insert(v.tet);
      EXPECT_NEAR(v.exponent, x[static_cast<std::size_t>(v.tet)], 1e-9 * std::max(1.0, v.exponent)) << "tet " << v.tet;
    }
    EXPECT_EQ(reported, expected) << "state " << step;
    crossed += expected.empty() ? 0 : 1;
    ++states;
  }
  EXPECT_GT(crossed, 5) << "the walk must cross the limit for the test to mean anything";
  // The bound saves work: fewer exact evaluations than every guarded tet at every check.
  EXPECT_LT(guard.exact_evaluations(), static_cast<long>(states) * guard.num_guarded());
}

TEST(CubatureGuard, ReleasedTetsAreNoLongerWatched) {
  const auto c = testing::box_case({4, 4, 3});
  const Subspace s = testing::box_subspace(c);
  CubatureGuard guard(c.problem, s, sparse_cubature(c.problem, 4), 1e-6);
  const Eigen::VectorXd q = testing::random_q(s.num_dofs(), 0.01, 7);
  const std::vector<GuardViolation> first = guard.check(q);
  ASSERT_FALSE(first.empty());
  const int before = guard.num_guarded();
  for (const GuardViolation& v : first) guard.release(v.tet);
  EXPECT_EQ(guard.num_guarded(), before - static_cast<int>(first.size()));
  EXPECT_TRUE(guard.check(q).empty());
}

/// The box's free nodes thrown upwards at `speed` [m/s]: the handles carry the layer away from its attached floor.
model::State thrown(const model::Problem& p, double speed) {
  model::State state = model::initial_state(p, 0.0);
  const std::vector<char> fixed = p.dirichlet.mask(p.num_nodes());
  for (int i = 0; i < p.num_nodes(); ++i)
    if (!fixed[static_cast<std::size_t>(3 * i)]) state.w[3 * i + 2] = speed;
  return state;
}

/// One cubature tet carrying the whole volume: most of the layer is invisible to the reduced energy.
Cubature one_tet_cubature(const model::Problem& problem) {
  Cubature cubature;
  cubature.tets = {farthest_point_tets(problem, 1, {}).front()};
  cubature.weights = voronoi_weights(problem, cubature.tets);
  cubature.method = "voronoi";
  return cubature;
}

// A differentiated run whose guard grows the cubature follows it: each substep is differentiated on the cubature it
// was solved with (the new tets' Young-map rows from set_young_rows), in one pass, and dq/dY is the derivative of
// the plain run, which grows its cubature at the same states. Without the rows the run stops with one line.
TEST(CubatureGuard, ADifferentiatedRunFollowsTheCubatureTheGuardGrows) {
  auto c = testing::box_case({5, 4, 3});
  Eigen::MatrixX2d base(2, 2);  // [Pa]: the fixture's skin at both ends of the box's two-control ramp
  base << 5000.0, 2000.0, 5000.0, 2000.0;
  testing::set_box_young(c.problem, base);
  const Subspace s = testing::box_subspace(c);
  const Cubature cubature = one_tet_cubature(c.problem);
  constexpr int kSteps = 6;
  constexpr double kStep = 1.0 / 60.0;
  const model::State start = thrown(c.problem, 3.0);
  const auto rows = [&](const std::vector<int>& tets) { return testing::box_young_map(c.problem, tets); };
  {
    SensitivityIntegrator without(c.problem, s, cubature, rows(cubature.tets));
    without.initialize(start);
    try {
      for (int k = 0; k < kSteps; ++k) without.step(kStep);
      FAIL() << "the one-tet cubature must need the guard here";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("cubature"), std::string::npos) << e.what();
    }
  }
  SensitivityIntegrator integrator(c.problem, s, cubature, rows(cubature.tets));
  integrator.set_young_rows(rows);
  integrator.initialize(start);
  for (int k = 0; k < kSteps; ++k) ASSERT_NO_THROW(integrator.step(kStep)) << "step " << k;
  ASSERT_GT(integrator.integrator().cubature_added(), 0);
  const Eigen::MatrixXd analytic = integrator.dq_dyoung();
  ASSERT_TRUE(analytic.allFinite());
  const auto end_state = [&](const Eigen::MatrixX2d& young, int& added) {
    testing::set_box_young(c.problem, young);
    ReducedSolver plain(c.problem, s, cubature, sensitivity_solver_options());
    plain.initialize(start);
    for (int k = 0; k < kSteps; ++k) plain.step(kStep);
    added = plain.cubature_added();
    return Eigen::VectorXd(plain.q());
  };
  // Central differences with a relative step of 1e-4 (truncation ~1e-9 relative, Newton's error ≲ 1e-13 m
  // against differences of ~1e-6 m: test_sensitivity.cpp's budget). Both runs must grow the cubature as the
  // differentiated one did, or the difference straddles a switch of the cubature and measures nothing.
  // Measured: 2e-9 to 1e-8 with 97 tets added; leaving the added tets out of dq/dY (zero rows) is an O(1) error.
  for (int column : {0, 1, 2, 3}) {
    const int control = column % 2, modulus = column / 2;
    const double delta = 1e-4 * base(control, modulus);
    Eigen::MatrixX2d plus = base, minus = base;
    plus(control, modulus) += delta;
    minus(control, modulus) -= delta;
    int added_plus = 0, added_minus = 0;
    const Eigen::VectorXd fd = (end_state(plus, added_plus) - end_state(minus, added_minus)) / (2.0 * delta);
    ASSERT_EQ(added_plus, integrator.integrator().cubature_added());
    ASSERT_EQ(added_minus, integrator.integrator().cubature_added());
    ASSERT_GT(fd.norm(), 0.0);
    EXPECT_LE((analytic.col(column) - fd).norm(), 1e-5 * fd.norm()) << "column " << column;
    // The negative control: new tets taken as if their Y did not depend on the controls.
    SensitivityIntegrator blind(c.problem, s, cubature, rows(cubature.tets));
    blind.set_young_rows([](const std::vector<int>& tets) {
      return Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(tets.size()), 2).eval();
    });
    testing::set_box_young(c.problem, base);
    blind.initialize(start);
    for (int k = 0; k < kSteps; ++k) blind.step(kStep);
    EXPECT_GT((blind.dq_dyoung().col(column) - fd).norm(), 0.1 * fd.norm()) << "column " << column;
  }
}

TEST(CubatureGuard, TheSolverRepairsAStateThatLeavesTheMaterialOutsideTheCubature) {
  const auto c = testing::box_case({5, 4, 3});
  const Subspace s = testing::box_subspace(c);
  const Cubature cubature = one_tet_cubature(c.problem);
  constexpr double kSpeed =
      3.0;  // [m/s] against a 6 cm tall box: strains far beyond the material's range unless resisted
  constexpr double kStep = 1.0 / 60.0;

  ReducedOptions unguarded;
  unguarded.guard = false;
  ReducedSolver blind(c.problem, s, cubature, unguarded);
  blind.initialize(thrown(c.problem, kSpeed));
  double worst = 0.0;
  for (int k = 0; k < 6; ++k) {
    try {
      blind.step(kStep);
    } catch (const Error&) {
      worst = std::numeric_limits<double>::infinity();
      break;
    }
    const std::vector<double> x = exponents(c.problem, blind.full_state().x);
    worst = std::max(worst, *std::max_element(x.begin(), x.end()));
  }
  ASSERT_GT(worst, material::kFungExponentCap) << "without the guard this case must leave the material's range";

  ReducedOptions guarded;
  ReducedSolver solver(c.problem, s, cubature, guarded);
  solver.initialize(thrown(c.problem, kSpeed));
  int added = 0;
  for (int k = 0; k < 6; ++k) {
    model::StepStats stats;
    ASSERT_NO_THROW(stats = solver.step(kStep)) << "step " << k;
    added += stats.cubature_added;
    const std::vector<double> x = exponents(c.problem, solver.full_state().x);
    // Tets outside the cubature stay under the guard's limit; those inside under the material's cap.
    for (int e = 0; e < c.problem.num_tets(); ++e) {
      const bool in_cubature =
          std::find(solver.cubature().tets.begin(), solver.cubature().tets.end(), e) != solver.cubature().tets.end();
      EXPECT_LE(x[static_cast<std::size_t>(e)], in_cubature ? material::kFungExponentCap : guarded.guard_exponent)
          << "tet " << e << ", step " << k;
    }
  }
  EXPECT_GT(added, 0);
  EXPECT_EQ(added, solver.cubature_added());
  EXPECT_EQ(solver.cubature().size(), 1 + added);
  // The volume the cubature integrates is kept when tets join it.
  double volume = 0.0, integrated = 0.0;
  for (int e = 0; e < c.problem.num_tets(); ++e) volume += c.problem.tet_rest[static_cast<std::size_t>(e)].volume;
  for (int k = 0; k < solver.cubature().size(); ++k)
    integrated +=
        solver.cubature().weights[static_cast<std::size_t>(k)] *
        c.problem.tet_rest[static_cast<std::size_t>(solver.cubature().tets[static_cast<std::size_t>(k)])].volume;
  EXPECT_NEAR(integrated, volume, 1e-9 * volume);
}

}  // namespace
}  // namespace sflsh::reduced
