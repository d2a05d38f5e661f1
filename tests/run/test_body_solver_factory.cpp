// The body-run layer (run/): the solver factory builds each kind behind model::BodySolver with the choice's
// integrator, the SUNDIALS adaptor steps exactly to the frame times of the reference integrator it wraps, and the
// one set of run defaults reaches every description of a body run (the command line's, Python's, a scene's).
#include "open_body.hpp"
#include "scratch_dir.hpp"

#include <sflsh/body/motion.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/model/frame_loop.hpp>
#include <sflsh/run/body_simulation.hpp>
#include <sflsh/run/body_solver_factory.hpp>
#include <sflsh/scene/scene_file.hpp>

#include <gtest/gtest.h>

#include <fstream>
#include <string>

namespace sflsh::run {
namespace {

using sflsh::testing::open_body;

/// The β = 0 open body's coarse layer along a few frames of `jiggle_on_toes`, lumped masses.
struct CoarseLayer {
  body::Motion motion = body::make_procedural_motion("jiggle_on_toes", 60.0, 3);
  model::BodyLayer layer;
  CoarseLayer() : layer(build()) {}
  model::BodyLayer build() const {
    model::BodyLayerOptions options;
    options.size = meshing::SizePreset::coarse;
    options.cache_dir = SFLSH_TEST_CACHE;
    options.mass = model::MassKind::lumped;
    return model::build_body_layer(open_body(), body::Betas::Zero(), motion, nullptr, 12, options);
  }
};

const CoarseLayer& coarse_layer() {
  static const CoarseLayer layer;
  return layer;
}

model::FrameLoopOptions loop_of(const body::Motion& motion) {
  model::FrameLoopOptions loop;
  loop.frames = static_cast<int>(motion.num_frames());
  loop.fps = motion.fps;
  return loop;
}

TEST(BodySolverFactory, SundialsAdaptorEndsItsStepsOnTheFrameTimesOfTheIntegratorItWraps) {
  const CoarseLayer& c = coarse_layer();
  const model::Problem& problem = c.layer.problem;
  fullspace::ReferenceOptions ro;
  // Loose tolerances keep ARKODE's steps few: the test compares two runs of the same integrator, not an answer.
  ro.rtol = 1e-2;
  ro.atol = 1e-4;
  fullspace::ReferenceIntegrator direct(problem, ro);
  direct.initialize(model::initial_state(problem, 0.0));

  SolverChoice choice;
  choice.kind = SolverKind::sundials;
  choice.sundials = ro;
  choice.step_rate = c.motion.fps;
  const BuiltSolver built = make_body_solver(problem, choice, model::initial_state(problem, 0.0));
  ASSERT_NE(built.sundials, nullptr);
  EXPECT_EQ(built.full, nullptr);
  EXPECT_EQ(built.reduced, nullptr);
  int frames = 0;
  long newton = 0;
  model::run_frames(*built, loop_of(c.motion), [&](int f, double t, const model::StepStats& st) {
    const model::State expected = direct.advance_to(c.motion.time(static_cast<std::size_t>(f)));
    EXPECT_EQ(built->current_state().t, expected.t);  // k / fps exactly, not a sum of rounded steps
    EXPECT_EQ(t, expected.t);
    // The same ARKODE run with the same stop times: the same numbers, bit for bit.
    EXPECT_EQ((built->current_state().x - expected.x).cwiseAbs().maxCoeff(), 0.0) << "frame " << f;
    EXPECT_EQ((built->current_state().w - expected.w).cwiseAbs().maxCoeff(), 0.0) << "frame " << f;
    EXPECT_GE(st.substeps, 1);  // ARKODE's internal steps of the interval
    newton += st.newton_iterations;
    ++frames;
  });
  EXPECT_EQ(frames, 2);
  EXPECT_EQ(newton, direct.stats().nonlin_iters);
  EXPECT_GT(direct.stats().nonlin_iters, 0);
}

TEST(BodySolverFactory, FullSpaceSolverTakesTheChoicesIntegrator) {
  const CoarseLayer& c = coarse_layer();
  const model::Problem& problem = c.layer.problem;
  for (model::Integrator integrator : {model::Integrator::backward_euler, model::Integrator::newmark}) {
    SolverChoice choice;
    choice.integrator = integrator;
    const BuiltSolver built = make_body_solver(problem, choice, model::initial_state(problem, 0.0));
    ASSERT_NE(built.full, nullptr);
    fullspace::FullSpaceOptions options;
    options.integrator = integrator;
    fullspace::FullSpaceSolver direct(problem, MPI_COMM_WORLD, options);
    direct.initialize(model::initial_state(problem, 0.0));
    built->step(1.0 / 60.0);
    direct.step(1.0 / 60.0);
    EXPECT_EQ((built->current_state().x - direct.state().x).cwiseAbs().maxCoeff(), 0.0) << model::to_string(integrator);
  }
}

TEST(BodySolverFactory, ReducedSolverNeedsItsModelAndRefusesBadChoices) {
  const CoarseLayer& c = coarse_layer();
  const model::Problem& problem = c.layer.problem;
  SolverChoice choice;
  choice.kind = SolverKind::reduced;
  EXPECT_THROW((void)make_body_solver(problem, choice, model::initial_state(problem, 0.0)), Error);
  choice.handles = 12;
  choice.cubature = 60;
  const reduced::ReducedModel model = make_reduced_model(c.layer, choice, SFLSH_TEST_CACHE);
  const BuiltSolver built = make_body_solver(problem, choice, model::initial_state(problem, 0.0), parts_of(model));
  ASSERT_NE(built.reduced, nullptr);
  reduced::ReducedOptions options;  // what the factory must have set: the choice's integrator and tolerance
  options.integrator = choice.integrator;
  options.step_tolerance = choice.newton_tolerance;
  reduced::ReducedSolver direct(problem, model.subspace, model.cubature, options);
  direct.initialize(model::initial_state(problem, 0.0));
  model::run_frames(*built, loop_of(c.motion), [&](int f, double, const model::StepStats&) {
    direct.step(1.0 / c.motion.fps);
    EXPECT_EQ((built->current_state().x - direct.full_state().x).cwiseAbs().maxCoeff(), 0.0) << "frame " << f;
  });
  EXPECT_GT((built->current_state().x - problem.rest.reshaped<Eigen::RowMajor>()).cwiseAbs().maxCoeff(), 0.0);
  SolverChoice bad = choice;
  bad.newton_tolerance = -1.0;
  EXPECT_THROW((void)make_body_solver(problem, bad, model::initial_state(problem, 0.0), parts_of(model)), Error);
  bad = choice;
  bad.handles = 0;
  EXPECT_THROW((void)make_reduced_model(c.layer, bad, SFLSH_TEST_CACHE), Error);
  EXPECT_EQ(parse_solver_kind("sundials", "--solver"), SolverKind::sundials);
  EXPECT_THROW((void)parse_solver_kind("exact", "--solver"), Error);
}

TEST(RunDefaults, OneSetReachesTheCommandLinePythonAndScenes) {
  // The command line's and Python's description of a body run (BodyRunSettings: simulate, sweep, Simulation).
  const BodyRunSettings settings;
  EXPECT_EQ(settings.mesh, kDefaultMesh);
  EXPECT_EQ(settings.handles, kDefaultHandles);
  EXPECT_EQ(settings.cubature, kDefaultCubature);
  EXPECT_EQ(settings.newton_tolerance, kDefaultNewtonTolerance);
  EXPECT_EQ(settings.integrator, model::to_string(model::kDefaultIntegrator));
  EXPECT_EQ(settings.layer.mass, model::to_string(model::kDefaultMassKind));
  EXPECT_EQ(settings.layer.control_points, model::kDefaultControlPoints);
  EXPECT_EQ(settings.layer.density, model::kDefaultDensity);
  const SolverChoice choice = solver_choice(settings);
  EXPECT_EQ(choice.handles, kDefaultHandles);
  EXPECT_EQ(choice.integrator, model::kDefaultIntegrator);
  EXPECT_EQ(choice.newton_tolerance, kDefaultNewtonTolerance);

  // A scene's [[body]] and [crowd] without those keys, as read from a file.
  const std::filesystem::path dir = sflsh::testing::scratch_dir();
  std::ofstream(dir / "body.toml") << "[scene]\nduration = 0.1\n[effects]\ninertia = true\n[[body]]\nname = \"a\"\n";
  std::ofstream(dir / "crowd.toml") << "[scene]\nduration = 0.1\n[effects]\ninertia = true\n[crowd]\ncount = 2\n";
  const scene::Scene scene = scene::load_scene(dir / "body.toml");
  ASSERT_EQ(scene.bodies.size(), 1u);
  const scene::BodySpec& body = scene.bodies[0];
  EXPECT_EQ(body.mesh, kDefaultMesh);
  EXPECT_EQ(body.handles, kDefaultHandles);
  EXPECT_EQ(body.cubature, kDefaultCubature);
  EXPECT_EQ(body.control_points, model::kDefaultControlPoints);
  EXPECT_EQ(body.density, model::kDefaultDensity);
  EXPECT_EQ(body.integrator, model::kDefaultIntegrator);
  EXPECT_EQ(body.mass, model::kDefaultMassKind);
  const scene::Scene crowd = scene::load_scene(dir / "crowd.toml");
  ASSERT_TRUE(crowd.crowd.has_value());
  EXPECT_EQ(crowd.crowd->mesh, kDefaultMesh);
  EXPECT_EQ(crowd.crowd->handles, kDefaultHandles);
  EXPECT_EQ(crowd.crowd->cubature, kDefaultCubature);
}

}  // namespace
}  // namespace sflsh::run
