// The reduced model's integrators and masses: with every free node a handle and every tet as cubature it is the
// full-space step (against a dense full-space reference and against the PETSc full-space solver, for every
// integrator × mass); Newmark keeps the energy of a small free oscillation; BDF2 counts its start-up steps; a failed
// step leaves the history untouched; a full state carries the history from one solver to another; the
// sensitivities refuse what they are not derived for.
#include "integrator_fixtures.hpp"
#include "reduced_fixtures.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/reduced/reduced_history.hpp>
#include <sflsh/reduced/reduced_sensitivity.hpp>
#include <sflsh/reduced/reduced_solver.hpp>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>
#include <petscsys.h>

#include <cmath>
#include <limits>
#include <memory>
#include <string>

namespace sflsh::reduced {
namespace {

using testing::shake;

enum class Motion { drive, swing };

struct Combination {
  model::Integrator integrator;
  model::MassKind mass;
  Motion motion;
};

std::string combination_name(const ::testing::TestParamInfo<Combination>& info) {
  return std::string(model::to_string(info.param.integrator)) + "_" + std::string(model::to_string(info.param.mass)) +
         "_" + (info.param.motion == Motion::drive ? "drive" : "swing");
}

/// The 3 × 3 × 2 box (bottom face attached) under gravity, its bottom face shaken in z (drive) or the whole box swung
/// and shaken by node maps R(t), d(t) (swing), with the given mass.
testing::BoxCase moving_box(const Combination& c, const model::ScalarDrive& drive) {
  auto box = testing::box_case({3, 3, 2}, 1000.0, c.motion == Motion::drive ? &drive : nullptr);
  model::Problem& p = box.problem;
  p.gravity =
      Eigen::Vector3d(0.2, -0.3, -1.0);  // a tenth of g, tilted: the 2 kPa box would sag by its own height under g
  p.mass_kind = c.mass;
  if (c.motion == Motion::swing)
    p.trajectory = std::make_shared<testing::SwingTrajectory>(p.num_nodes(), Eigen::Vector3d(0.06, 0.05, 0.0),
                                                              Eigen::Vector3d(1.0, 0.3, 0.2), 0.1, 2.0,
                                                              Eigen::Vector3d(0.005, -0.01, 0.008), 1.0);
  p.validate();
  return box;
}

/// Newton to round-off, from q_n (no predictor), so that two solvers of the same Φ agree to their tolerance.
ReducedOptions tight_options(model::Integrator integrator) {
  ReducedOptions ro;
  ro.integrator = integrator;
  ro.gradient_rtol = 1e-13;
  ro.gradient_atol = 1e-14;
  ro.step_tolerance = 1e-14;
  ro.use_predictor = false;
  return ro;
}

const Combination kCombinations[] = {
    {model::Integrator::backward_euler, model::MassKind::lumped, Motion::drive},
    {model::Integrator::backward_euler, model::MassKind::consistent, Motion::drive},
    {model::Integrator::bdf2, model::MassKind::lumped, Motion::drive},
    {model::Integrator::bdf2, model::MassKind::consistent, Motion::drive},
    {model::Integrator::newmark, model::MassKind::lumped, Motion::drive},
    {model::Integrator::newmark, model::MassKind::consistent, Motion::drive},
    {model::Integrator::backward_euler, model::MassKind::lumped, Motion::swing},
    {model::Integrator::backward_euler, model::MassKind::consistent, Motion::swing},
    {model::Integrator::bdf2, model::MassKind::lumped, Motion::swing},
    {model::Integrator::bdf2, model::MassKind::consistent, Motion::swing},
    {model::Integrator::newmark, model::MassKind::lumped, Motion::swing},
    {model::Integrator::newmark, model::MassKind::consistent, Motion::swing},
};

// Tolerances of the trajectory comparisons [m, or m/s for velocities, per mm of motion]. Both sides minimize the
// same Φ until ‖∇Φ‖ ≤ 1e-13 ‖∇Φ₀‖, so each state agrees to ~1e-13 of the step's motion; over 40 steps the
// differences add up at most linearly (backward Euler and BDF2 damp them, Newmark carries them without growth).
// Measured against the dense reference: ≤ 2e-14 m on 5–25 mm of motion, hence 1e-10 (four orders of margin). The
// PETSc solver stops on its own criteria (SNES and KSP rtol 1e-13): 1e-8, as in ReducedIntegrator.FullBasis….
// A wrong ĥ, p̃ or mass block is an O(1) disagreement after one step.
constexpr double kDenseAgreement = 1e-10;
constexpr double kFullSpaceAgreement = 1e-8;

class FullBasis : public ::testing::TestWithParam<Combination> {};

TEST_P(FullBasis, ReproducesTheDenseFullSpaceReference) {
  const Combination combination = GetParam();
  const model::ScalarDrive drive = shake(0.006, 4.0);
  const auto box = moving_box(combination, drive);
  const model::Problem& p = box.problem;
  const Subspace s = testing::full_basis(p);
  const Cubature all = exact_cubature(p.num_tets());
  ReducedSolver reduced(p, s, all, tight_options(combination.integrator));
  testing::DenseReference reference(p, combination.integrator);
  const model::State start = model::initial_state(p, 0.0);
  reduced.initialize(start);    // Newmark: p̈ in the subspace …
  reference.initialize(start);  // … and from model::initial_acceleration
  if (combination.integrator == model::Integrator::newmark) {
    // With the full basis the subspace solve (JᵀMJ) q̈ = −∇E + JᵀM(g − ζ) is the full-space one: M_FF a_F = r_F − M_FC
    // a_C.
    const Eigen::VectorXd a = reduced.full_state().a;
    ASSERT_EQ(a.size(), p.num_dofs());
    EXPECT_LT((a - reference.state().a).cwiseAbs().maxCoeff(), 1e-9 * reference.state().a.cwiseAbs().maxCoeff());
  }
  const Eigen::Map<const Eigen::VectorXd> rest(p.rest.data(), p.num_dofs());
  // Velocities are compared on the free nodes: on attached ones the full-space history carries the integrator's
  // difference quotient, the reduced state the exact velocity of the prescribed motion (unless a consistent mass
  // makes them inertia nodes).
  std::vector<int> free;
  const std::vector<char> fixed = p.dirichlet.mask(p.num_nodes());
  for (int d = 0; d < p.num_dofs(); ++d)
    if (!fixed[static_cast<std::size_t>(d)]) free.push_back(d);
  double worst_x = 0.0, worst_w = 0.0, largest_u = 0.0, largest_w = 0.0;
  int startup = 0;
  for (int k = 0; k < 40; ++k) {
    const model::StepStats st = reduced.step(1.0 / 120.0);
    ASSERT_EQ(st.substeps, 1) << "step " << k << ": the reduced solver split the step, the reference did not";
    startup += st.startup_steps;
    reference.step(1.0 / 120.0);
    const model::State a = reduced.full_state();
    worst_x = std::max(worst_x, (a.x - reference.state().x).cwiseAbs().maxCoeff());
    worst_w = std::max(worst_w, (a.w(free) - reference.state().w(free)).cwiseAbs().maxCoeff());
    largest_u = std::max(largest_u, (reference.state().x - rest).cwiseAbs().maxCoeff());
    largest_w = std::max(largest_w, reference.state().w.cwiseAbs().maxCoeff());
  }
  EXPECT_EQ(startup, combination.integrator == model::Integrator::bdf2 ? 1 : 0);
  ASSERT_GT(largest_u, 1e-4);
  EXPECT_LT(worst_x, kDenseAgreement * std::max(1.0, largest_u / 1e-3)) << "largest displacement " << largest_u;
  EXPECT_LT(worst_w, kDenseAgreement * std::max(1.0, largest_w / 1e-3)) << "largest velocity " << largest_w;
}

TEST_P(FullBasis, ReproducesTheFullSpaceSolver) {
  const Combination combination = GetParam();
  const model::ScalarDrive drive = shake(0.006, 4.0);
  const auto box = moving_box(combination, drive);
  const model::Problem& p = box.problem;
  const Subspace s = testing::full_basis(p);
  const Cubature all = exact_cubature(p.num_tets());
  ReducedSolver reduced(p, s, all, tight_options(combination.integrator));
  fullspace::FullSpaceOptions fo;
  fo.integrator = combination.integrator;
  fo.default_snes_rtol = 1e-13;
  fo.default_snes_atol = 1e-14;
  fo.default_ksp_rtol = 1e-13;
  fo.use_predictor = false;
  fullspace::FullSpaceSolver full(p, PETSC_COMM_WORLD, fo);
  const model::State start = model::initial_state(p, 0.0);
  reduced.initialize(start);
  full.initialize(start);
  const Eigen::Map<const Eigen::VectorXd> rest(p.rest.data(), p.num_dofs());
  double worst = 0.0, largest = 0.0;
  for (int k = 0; k < 40; ++k) {
    reduced.step(1.0 / 120.0);
    full.step(1.0 / 120.0);
    worst = std::max(worst, (reduced.full_state().x - full.state().x).cwiseAbs().maxCoeff());
    largest = std::max(largest, (full.state().x - rest).cwiseAbs().maxCoeff());
  }
  ASSERT_GT(largest, 1e-4);
  EXPECT_LT(worst, kFullSpaceAgreement * std::max(1.0, largest / 1e-3)) << "largest displacement " << largest;
}

INSTANTIATE_TEST_SUITE_P(IntegratorsAndMasses, FullBasis, ::testing::ValuesIn(kCombinations), combination_name);

// ---------------------------------------------------------------------------------------------------------
// Newmark keeps the energy of a free oscillation.

class NewmarkEnergy : public ::testing::TestWithParam<model::MassKind> {};

TEST_P(NewmarkEnergy, SmallUndampedOscillationKeepsItsEnergyOverFiftyPeriods) {
  auto c = testing::box_case({4, 4, 3});
  c.problem.mass_kind = GetParam();
  c.problem.validate();
  const model::Problem& p = c.problem;
  const Subspace s = testing::box_subspace(c);
  const Cubature all = exact_cubature(p.num_tets());
  // The slowest mode of the linearized reduced system: K v = ω² (JᵀMJ) v at rest.
  CubatureElastic elastic(p, s, all);
  ReducedInertia inertia(p, s);
  inertia.set_time(0.0, Eigen::Map<const Eigen::VectorXd>(p.rest.data(), p.num_dofs()));
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(s.num_dofs());
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(s.num_dofs(), s.num_dofs()), M;
  elastic.add_hessian(zero, K, material::HessianProjection::kNone);
  inertia.mass_hessian(1.0, M);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> modes(K, M);
  ASSERT_EQ(modes.info(), Eigen::Success);
  const double omega = std::sqrt(modes.eigenvalues()[0]), period = 2.0 * M_PI / omega;
  // 0.2 mm at the handles (0.3 % strain on the 6 cm box: the Fung term is negligible, the system nearly linear).
  Eigen::VectorXd q0 = modes.eigenvectors().col(0);
  q0 *= 2e-4 / q0.cwiseAbs().maxCoeff();
  model::State start = model::initial_state(p, 0.0);
  s.add_displacement(q0, start.x);
  ReducedOptions ro;
  ro.integrator = model::Integrator::newmark;
  ro.gradient_rtol = 1e-12;
  ro.gradient_atol = 1e-14;
  ro.step_tolerance = 1e-14;
  ReducedSolver reduced(p, s, all, ro);
  reduced.initialize(start);
  const auto total = [&] {
    const model::Energies e = model::energies(p, reduced.full_state());
    return e.kinetic + e.elastic;
  };
  const double e0 = total();
  ASSERT_GT(e0, 0.0);
  const int steps_per_period = 20, periods = 50;
  const double h = period / steps_per_period;
  double worst = 0.0, smallest_kinetic_share = 1.0, largest_kinetic_share = 0.0;
  for (int k = 0; k < periods * steps_per_period; ++k) {
    const model::StepStats st = reduced.step(h);
    ASSERT_EQ(st.failed_attempts, 0) << "step " << k;
    const model::Energies e = model::energies(p, reduced.full_state());
    const double now = e.kinetic + e.elastic;
    worst = std::max(worst, std::abs(now - e0) / e0);
    smallest_kinetic_share = std::min(smallest_kinetic_share, e.kinetic / now);
    largest_kinetic_share = std::max(largest_kinetic_share, e.kinetic / now);
  }
  // It oscillates (the energy moves between kinetic and elastic) …
  EXPECT_LT(smallest_kinetic_share, 0.05);
  EXPECT_GT(largest_kinetic_share, 0.95);
  // … without losing or gaining energy: trapezoidal Newmark conserves ½vᵀMv + ½qᵀKq of a linear system exactly,
  // so what is left is the Fung and geometric nonlinearity at 0.3 % strain and the Newton tolerance: measured
  // ≤ 4e-6 of E₀ (lumped and consistent). The bound is the 0.5 % asked of it; in the same run BDF2 loses 98 % and
  // backward Euler all of it.
  EXPECT_LT(worst, 5e-3) << "period " << period << " s";
  EXPECT_LT(std::abs(total() - e0) / e0, 5e-3);
}

std::string mass_name(const ::testing::TestParamInfo<model::MassKind>& info) {
  return std::string(model::to_string(info.param));
}

INSTANTIATE_TEST_SUITE_P(Masses, NewmarkEnergy, ::testing::Values(model::MassKind::lumped, model::MassKind::consistent),
                         mass_name);

// ---------------------------------------------------------------------------------------------------------
// History bookkeeping.

TEST(ReducedIntegrators, Bdf2CountsItsStartUpSteps) {
  auto c = testing::box_case({3, 3, 2});
  const Subspace s = testing::box_subspace(c);
  const Cubature all = exact_cubature(c.problem.num_tets());
  ReducedOptions ro;
  ro.integrator = model::Integrator::bdf2;
  ReducedSolver reduced(c.problem, s, all, ro);
  model::State start = model::initial_state(c.problem, 0.0);
  Eigen::VectorXd q0 = Eigen::VectorXd::Zero(s.num_dofs());
  q0[0] = 0.002;
  s.add_displacement(q0, start.x);
  reduced.initialize(start);
  const double h = 1.0 / 120.0;
  EXPECT_EQ(reduced.step(h).startup_steps, 1);  // no previous step: backward Euler
  EXPECT_EQ(reduced.step(h).startup_steps, 0);
  EXPECT_EQ(reduced.step(2.0 * h).startup_steps, 0);  // ω = 2: still zero-stable
  EXPECT_EQ(reduced.step(6.0 * h).startup_steps, 1);  // ω = 3: restarts as backward Euler
  EXPECT_EQ(reduced.step(6.0 * h).startup_steps, 0);
}

TEST(ReducedIntegrators, AFailedStepLeavesTheHistoryUntouched) {
  // Quiet until t = 0.02 s, then the bottom face is pulled 30 cm down within 0.01 s while the top face is held:
  // the third step of 0.01 s cannot be taken (as in ReducedIntegrator.AnImpossibleStepFailsLoudly…).
  const model::ScalarDrive drive{[](double t) { return t <= 0.02 ? 0.0 : -0.3 * (t - 0.02) / 0.01; },
                                 [](double t) { return t <= 0.02 ? 0.0 : -30.0; }};
  for (model::Integrator integrator : {model::Integrator::bdf2, model::Integrator::newmark}) {
    auto c = testing::box_case({3, 3, 2}, 1000.0, &drive);
    model::Problem& p = c.problem;
    for (int v : c.mesh.node_groups.at("zmax")) p.dirichlet.add(v, 0b111u);
    p.mass_kind = model::MassKind::consistent;
    p.validate();
    std::vector<char> attached = testing::attached_flags(c);
    for (int v : c.mesh.node_groups.at("zmax")) attached[static_cast<std::size_t>(v)] = 1;
    const Eigen::MatrixXd W =
        handle_weights(p.rest, p.tets, testing::box_handle_sets(c), static_cast<int>(c.point_handles.size()));
    const Subspace s = point_handle_subspace(W, attached, p.rest, c.point_handles, BasisOptions{});
    const Cubature all = exact_cubature(p.num_tets());
    ReducedOptions ro;
    ro.integrator = integrator;
    ro.max_halvings = 2;
    ReducedSolver reduced(p, s, all, ro);
    reduced.initialize(model::initial_state(p, 0.0));
    reduced.step(0.01);
    reduced.step(0.01);
    const model::PosedHistory before = reduced.history();
    const Eigen::VectorXd q_before = reduced.q();
    EXPECT_THROW(reduced.step(0.01), Error) << model::to_string(integrator);
    const model::PosedHistory& after = reduced.history();
    EXPECT_EQ(reduced.time(), 0.02);
    // Bit for bit (the sizes first: Eigen compares equal sizes only).
    const auto same = [](const Eigen::VectorXd& a, const Eigen::VectorXd& b) { return a.size() == b.size() && a == b; };
    EXPECT_TRUE(same(reduced.q(), q_before));
    EXPECT_TRUE(same(after.p, before.p));
    EXPECT_TRUE(same(after.v, before.v));
    EXPECT_TRUE(same(after.a, before.a));
    EXPECT_TRUE(same(after.p_previous, before.p_previous));
    EXPECT_TRUE(same(after.v_previous, before.v_previous));
    EXPECT_EQ(after.h_previous, before.h_previous);
  }
}

// A checkpoint holds the step state the ladder saves plus the factorization: steps taken after restoring it repeat the
// steps taken after it was made, bit for bit (the scene's body-contact exchange solves a step again this way).
TEST(ReducedIntegrators, StepsAfterARestoredCheckpointRepeatBitForBit) {
  const model::ScalarDrive drive = testing::shake(0.01, 6.0);
  for (model::Integrator integrator :
       {model::Integrator::backward_euler, model::Integrator::bdf2, model::Integrator::newmark}) {
    auto c = testing::box_case({3, 3, 2}, 1000.0, &drive);
    model::Problem& p = c.problem;
    p.mass_kind = model::MassKind::consistent;
    p.validate();
    const Eigen::MatrixXd W =
        handle_weights(p.rest, p.tets, testing::box_handle_sets(c), static_cast<int>(c.point_handles.size()));
    const Subspace s = point_handle_subspace(W, testing::attached_flags(c), p.rest, c.point_handles, BasisOptions{});
    ReducedOptions ro;
    ro.integrator = integrator;
    ReducedSolver reduced(p, s, exact_cubature(p.num_tets()), ro);
    reduced.initialize(model::initial_state(p, 0.0));
    for (int k = 0; k < 3; ++k) reduced.step(0.005);
    const ReducedSolver::Checkpoint checkpoint = reduced.checkpoint();
    std::vector<Eigen::VectorXd> first;
    for (int k = 0; k < 3; ++k) {
      reduced.step(0.005);
      first.push_back(reduced.q());
    }
    const model::PosedHistory history = reduced.history();
    reduced.restore(checkpoint);
    EXPECT_EQ(reduced.time(), checkpoint.state.t);
    for (int k = 0; k < 3; ++k) {
      reduced.step(0.005);
      EXPECT_TRUE(reduced.q() == first[static_cast<std::size_t>(k)]) << model::to_string(integrator) << " step " << k;
    }
    EXPECT_TRUE(reduced.history().p == history.p && reduced.history().v == history.v) << model::to_string(integrator);
  }
}

class FullStateHandOver : public ::testing::TestWithParam<std::tuple<model::Integrator, model::MassKind>> {};

TEST_P(FullStateHandOver, ASecondSolverStartedFromTheFullStateContinuesTheFirst) {
  const auto [integrator, mass] = GetParam();
  const model::ScalarDrive drive = shake(0.006, 4.0);
  auto c = testing::box_case({3, 3, 2}, 1000.0, &drive);
  c.problem.mass_kind = mass;
  c.problem.validate();
  const model::Problem& p = c.problem;
  const Subspace s = testing::box_subspace(c);
  const Cubature all = exact_cubature(p.num_tets());
  ReducedOptions ro = tight_options(integrator);
  ReducedSolver first(p, s, all, ro);
  first.initialize(model::initial_state(p, 0.0));
  const double h = 1.0 / 120.0;
  for (int k = 0; k < 5; ++k) first.step(h);
  const model::State handed = first.full_state();
  ASSERT_EQ(handed.a.size(), integrator == model::Integrator::newmark ? p.num_dofs() : 0);
  ASSERT_EQ(handed.p_previous.size(), integrator == model::Integrator::bdf2 ? p.num_dofs() : 0);
  ReducedSolver second(p, s, all, ro);
  second.initialize(handed);
  // The history went across whole: the second solver's first step is already BDF2, and its history is the first's.
  EXPECT_LT((second.history().p - first.history().p).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_TRUE(second.history().v == first.history().v);
  if (integrator == model::Integrator::newmark) {
    ASSERT_EQ(second.history().a.size(), first.history().a.size());
    EXPECT_TRUE(second.history().a == first.history().a);
  } else {
    ASSERT_EQ(second.history().p_previous.size(), first.history().p_previous.size());
    EXPECT_TRUE(second.history().p_previous == first.history().p_previous);
    EXPECT_TRUE(second.history().v_previous == first.history().v_previous);
    EXPECT_EQ(second.history().h_previous, first.history().h_previous);
  }
  double worst = 0.0;
  for (int k = 0; k < 5; ++k) {
    first.step(h);
    EXPECT_EQ(second.step(h).startup_steps, 0);
    worst = std::max(worst, (second.q() - first.q()).cwiseAbs().maxCoeff());
  }
  // Same Φ per step to ‖∇Φ‖ ≤ 1e-13 ‖∇Φ₀‖, started from the same state up to the projection's round-off.
  EXPECT_LT(worst, 1e-11);
  // The accelerations and previous positions of nodes without basis functions are the prescribed motion's.
  if (integrator == model::Integrator::bdf2) {
    const model::State previous = model::initial_state(p, handed.t - h);
    for (int v : c.attached)
      EXPECT_LT((handed.p_previous.segment<3>(3 * v) - previous.x.segment<3>(3 * v)).norm(), 1e-15);
  }
}

std::string hand_over_name(const ::testing::TestParamInfo<std::tuple<model::Integrator, model::MassKind>>& info) {
  return std::string(model::to_string(std::get<0>(info.param))) + "_" +
         std::string(model::to_string(std::get<1>(info.param)));
}

INSTANTIATE_TEST_SUITE_P(IntegratorsAndMasses, FullStateHandOver,
                         ::testing::Combine(::testing::Values(model::Integrator::bdf2, model::Integrator::newmark),
                                            ::testing::Values(model::MassKind::lumped, model::MassKind::consistent)),
                         hand_over_name);

TEST(ReducedIntegrators, AQuasiStaticRunIsTheSameForEveryIntegrator) {
  auto c = testing::box_case({3, 3, 2});
  c.problem.gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
  const Subspace s = testing::box_subspace(c);
  const Cubature all = exact_cubature(c.problem.num_tets());
  Eigen::VectorXd last_q;
  for (model::Integrator integrator :
       {model::Integrator::backward_euler, model::Integrator::bdf2, model::Integrator::newmark}) {
    ReducedOptions ro;
    ro.integrator = integrator;
    ro.quasi_static = true;
    ro.step_tolerance = 1e-12;  // compared to 1e-9 below: solve far below the default 10 µm stopping distance
    ReducedSolver reduced(c.problem, s, all, ro);
    reduced.initialize(model::initial_state(c.problem, 0.0));
    for (int k = 0; k < 3; ++k) reduced.step(0.01);
    ASSERT_TRUE(reduced.q().allFinite());
    if (last_q.size()) {
      EXPECT_LT((reduced.q() - last_q).cwiseAbs().maxCoeff(), 1e-9);  // the same equilibria under gravity
    }
    last_q = reduced.q();
  }
  EXPECT_GT(last_q.cwiseAbs().maxCoeff(), 1e-6);  // it sagged
}

TEST(ReducedIntegrators, BadInputIsRefusedWithOneLine) {
  auto c = testing::box_case({3, 3, 2});
  const Subspace s = testing::box_subspace(c);
  const Cubature all = exact_cubature(c.problem.num_tets());
  ReducedOptions ro;
  ro.integrator = model::Integrator::newmark;
  ReducedSolver reduced(c.problem, s, all, ro);
  EXPECT_THROW(reduced.step(0.01), Error);  // no state yet
  model::State start = model::initial_state(c.problem, 0.0);
  start.a = Eigen::VectorXd::Zero(7);
  EXPECT_THROW(reduced.initialize(start), Error);  // accelerations of the wrong size
  start.a = Eigen::VectorXd::Constant(c.problem.num_dofs(), std::numeric_limits<double>::quiet_NaN());
  EXPECT_THROW(reduced.initialize(start), Error);  // not finite
}

TEST(ReducedIntegrators, SensitivitiesRefuseBdf2AndNewmark) {
  auto c = testing::box_case({3, 3, 2});
  const Subspace s = testing::box_subspace(c);
  const Cubature all = exact_cubature(c.problem.num_tets());
  const Eigen::MatrixXd young_map = Eigen::MatrixXd::Ones(all.size(), 1);
  for (model::Integrator integrator : {model::Integrator::bdf2, model::Integrator::newmark}) {
    ReducedOptions ro = sensitivity_solver_options();
    ro.integrator = integrator;
    try {
      SensitivityIntegrator sensitivity(c.problem, s, all, young_map, ro);
      FAIL() << "the sensitivity integrator accepted " << model::to_string(integrator);
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(std::string(model::to_string(integrator))), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  }
}

}  // namespace
}  // namespace sflsh::reduced
