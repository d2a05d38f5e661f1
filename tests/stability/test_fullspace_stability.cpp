// The hard cases of docs/architecture.md §8 for the full-space solver: extreme shapes, thin and thick layers, large
// steps, a 100× stiffness contrast, the landing of a jump and an initially inverted element. Each run must
// finish with a finite state at every frame and bounded energy (or fail with a clear sflsh::Error, which
// these cases must not need).
#include "long_test.hpp"
#include "stability_support.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/material/layer_material.hpp>
#include <sflsh/meshing/layer_cache.hpp>
#include <sflsh/model/body_layer.hpp>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <mpi.h>

#include <functional>
#include <iostream>

namespace sflsh::fullspace {
namespace {

using namespace sflsh::stability;
using model::BodyLayer;
using model::build_body_layer;

/// Runs backward Euler along the motion, checking every frame's state and energies for finiteness.
Outcome run_case(const body::Betas& beta, const body::Motion& motion, const material::MaterialFile* material,
                 int substeps = 1, const std::function<void(const Problem&, State&)>& perturb = {},
                 const FullSpaceOptions& options = {}) {
  const model::BodyLayer layer = model::build_body_layer(open_body(), beta, motion, material, 12, coarse());
  const Problem& p = layer.problem;
  State state = initial_state(p, 0.0);
  if (perturb) perturb(p, state);
  FullSpaceSolver integrator(p, MPI_COMM_WORLD, options);
  integrator.initialize(state);
  if (std::getenv("SFLSH_PROBE"))
    std::cerr << fmt::format("{} nodes {} tets {} constrained\n", p.num_nodes(), p.num_tets(), p.dirichlet.dof.size());
  Outcome out;
  out.initial_elastic = energies(p, integrator.state()).elastic;
  for (std::size_t f = 0; f < motion.num_frames(); ++f) {
    if (f > 0) {
      for (int k = 0; k < substeps; ++k) {
        const StepStats st = integrator.step(1.0 / (motion.fps * substeps));
        record_step(st, out);
        if (std::getenv("SFLSH_PROBE"))
          std::cerr << fmt::format("f {} newton {} lin {} sub {} fail {} s {:.3f} fn {:.3f} jac {:.3f} reason {}\n", f,
                                   st.newton_iterations, st.linear_iterations, st.substeps, st.failed_attempts,
                                   st.seconds, st.function_seconds, st.jacobian_seconds, st.converged_reason);
      }
    }
    record_frame(p, integrator.state(), motion.time(f), f, out);
  }
  return out;
}

TEST(FullspaceStability, ExtremeShapesBetaPlusMinusFour) {
  SFLSH_LONG_TEST();  // tens of seconds on 2 cores: label long
  const body::Motion motion = body::make_procedural_motion("running_on_spot", 60.0, 24);
  for (int component : {0, 1}) {
    for (double value : {-4.0, 4.0}) {
      SCOPED_TRACE(::testing::Message() << "beta[" << component << "] = " << value);
      expect_bounded(run_case(beta_with(component, value), motion, nullptr));
    }
  }
}

TEST(FullspaceStability, ThinLayer) {
  const body::Motion motion = body::make_procedural_motion("running_on_spot", 60.0, 24);
  const material::MaterialFile file = material_with([](int) { return material::Kappa{0.05, 5000.0, 2000.0}; });
  expect_bounded(run_case(body::Betas::Zero(), motion, &file));
}

TEST(FullspaceStability, ThickLayersSimulateOrAreRefusedBeforeTheSolve) {
  // Thick layers: where the inner surfaces of neighbouring parts (armpits, groin) meet, the retargeter cannot
  // place the template's tets without inverting some and refuses with a one-line error naming the parts
  // (measured on the coarse layered template: uniform h ≥ 0.7 is refused, 0.6 is accepted; docs/fullspace.md,
  // known limits). Each thickness must either simulate with bounded energy or be refused that way; the
  // thickest accepted one is simulated.
  const body::Motion motion = body::make_procedural_motion("running_on_spot", 60.0, 12);
  int simulated = 0;
  for (double h : {0.95, 0.8, 0.6}) {
    SCOPED_TRACE(::testing::Message() << "h = " << h);
    const material::MaterialFile file = material_with([h](int) { return material::Kappa{h, 5000.0, 2000.0}; });
    try {
      expect_bounded(run_case(body::Betas::Zero(), motion, &file));
      ++simulated;
      break;
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find("inverts"), std::string::npos) << error.what();
    }
  }
  EXPECT_EQ(simulated, 1);
}

TEST(FullspaceStability, LargeStepsOfOneTwentyFourthSecond) {
  SFLSH_LONG_TEST();  // tens of seconds on 2 cores: label long
  const body::Motion motion = body::make_procedural_motion("one_leg_jump", 24.0, 30);  // through the first landing
  expect_bounded(run_case(body::Betas::Zero(), motion, nullptr));
}

TEST(FullspaceStability, HundredfoldStiffnessContrastBetweenNeighbours) {
  const body::Motion motion = body::make_procedural_motion("shake_hips", 60.0, 30);
  const material::MaterialFile file = material_with([](int i) {
    const double young = i % 2 ? 50000.0 : 500.0;  // Y_max / Y_min = 100, alternating along the sampling order
    return material::Kappa{0.5, young, young};
  });
  expect_bounded(run_case(body::Betas::Zero(), motion, &file));
}

TEST(FullspaceStability, LandingOfAJump) {
  SFLSH_LONG_TEST();  // tens of seconds on 2 cores: label long
  // First landing at t ≈ 0.88 s with a 5 g impact (procedural_jump.cpp); run through it at 60 fps.
  const body::Motion motion = body::make_procedural_motion("one_leg_jump", 60.0, 58);
  expect_bounded(run_case(beta_with(0, 2.0), motion, nullptr));
}

TEST(FullspaceStability, ElementInvertedByTheInitialState) {
  const body::Motion motion = body::make_procedural_motion("running_on_spot", 60.0, 12);
  int inverted_before = 0;
  const auto invert_one = [&](const Problem& p, State& state) {
    const std::vector<char> fixed = p.dirichlet.mask(p.num_nodes());
    for (int e = 0; e < p.num_tets(); ++e) {
      const int v = p.tets(e, 0);
      if (fixed[static_cast<std::size_t>(3 * v)]) continue;
      // Push node 0 through the plane of the opposite face to 20% of its height on the other side: the tet
      // turns inside out (volume × −0.2) while its neighbours stay within ordinary strains.
      const Eigen::Vector3d a = state.x.segment<3>(3 * p.tets(e, 1)), b = state.x.segment<3>(3 * p.tets(e, 2)),
                            c = state.x.segment<3>(3 * p.tets(e, 3));
      const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
      const Eigen::Vector3d x = state.x.segment<3>(3 * v);
      state.x.segment<3>(3 * v) = x - 1.2 * n.dot(x - a) * n;
      const Eigen::Vector3d moved = state.x.segment<3>(3 * v);
      inverted_before = (b - a).cross(c - a).dot(moved - a) * (b - a).cross(c - a).dot(x - a) < 0.0 ? 1 : 0;
      return;
    }
  };
  const Outcome o = run_case(body::Betas::Zero(), motion, nullptr, 1, invert_one);
  ASSERT_EQ(inverted_before, 1);
  EXPECT_GT(o.initial_elastic, 0.0);
  expect_bounded(o);
}

// Issue 23: the softest material of the documented bounds (Y_t = Y_n = 500 Pa, docs/physics.md §6.5) on shake_hips.
// There the exact Hessian turns indefinite (StVK's negative curvature in compression times the Fung factor
// e^{2Ψ₀/c} of tets stretched at the same time, against a mass term M/h² that does not soften with Y): before
// truncated Newton–CG the first indefinite CG solve failed the attempt, the projected retry converged linearly
// (‖∇Φ‖ × 0.9 per iteration) into the 40-iteration cap and the steps were split (from t ≈ 0.33 s; measured
// with truncate_on_negative_curvature = false, this test fails: projected retries and failed attempts, 250 s instead
// of 33 s).
constexpr int kSoftFrames = 31;  // through t = 0.5 s, past the first failures of the old ladder
// Measured at β = 0 (30 frames): softest 288 Newton iterations, at most 23 in a frame; stiffest 79, at most 3. The
// bounds are SNES's 40-iteration cap of one attempt (a frame over it had to be solved twice) and 10 (a stiff frame
// takes 3–5; more means the exact Hessian is being given up again).
constexpr int kSoftMaxNewton = 40;
constexpr int kStiffMaxNewton = 10;

material::MaterialFile uniform_material(double young) {
  return material_with([young](int) { return material::Kappa{0.5, young, young}; });
}

TEST(FullspaceStability, SoftestMaterialShakeHipsWithoutRetries) {
  SFLSH_LONG_TEST();  // tens of seconds on 2 cores: label long
  const body::Motion motion = body::make_procedural_motion("shake_hips", 60.0, kSoftFrames);
  const material::MaterialFile soft = uniform_material(500.0);
  const Outcome o = run_case(body::Betas::Zero(), motion, &soft);
  expect_bounded(o);
  // No step needs the projected Hessian or a split: every frame is one exact-Hessian Newton solve.
  EXPECT_EQ(o.failed_attempts, 0);
  EXPECT_EQ(o.projected_retries, 0);
  // Bounded Newton work (see kSoftMaxNewton); the old ladder spent 40+ per frame from t = 0.33 s (a 40-iteration
  // projected attempt, then the split steps).
  EXPECT_LE(o.max_newton_per_frame, kSoftMaxNewton);
}

TEST(FullspaceStability, StiffestMaterialShakeHips) {
  const body::Motion motion = body::make_procedural_motion("shake_hips", 60.0, kSoftFrames);
  const material::MaterialFile stiff = uniform_material(50000.0);
  const Outcome o = run_case(body::Betas::Zero(), motion, &stiff);
  expect_bounded(o);
  EXPECT_EQ(o.failed_attempts, 0);
  EXPECT_LE(o.max_newton_per_frame, kStiffMaxNewton);
}

TEST(FullspaceStability, ShakeHipsOfOpenTrain1WithoutRetries) {
  // The default material on OPEN_TRAIN_1/shake_hips: at t = 0.42–0.55 s the exact Hessian turns indefinite (as above)
  // and the old ladder took 84–115 Newton iterations and 1–2 failed attempts per frame (frames 25–33; `sflsh simulate
  // --solver full --mesh coarse --subject OPEN_TRAIN_1 --motion shake_hips`). With truncated Newton–CG the CLI run
  // takes at most 15 in a frame over 60 frames; 20 leaves room and stays far below the old count.
  const body::Betas beta = body::find_subject(body::default_subjects(), "OPEN_TRAIN_1").beta;
  const body::Motion motion = body::make_procedural_motion("shake_hips", 60.0, 36);
  const Outcome o = run_case(beta, motion, nullptr);
  expect_bounded(o);
  EXPECT_EQ(o.failed_attempts, 0);
  EXPECT_EQ(o.projected_retries, 0);
  EXPECT_LE(o.max_newton_per_frame, 20);
}

}  // namespace
}  // namespace sflsh::fullspace
