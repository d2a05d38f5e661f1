// Convergence in time of the full-space solver's integrators: backward Euler first order, BDF2 and Newmark
// second order (docs/integrators.md), on the driven block of the FEBio comparison (against the SUNDIALS
// reference) and on a body layer (self-convergence: the difference of runs at h and h/2). docs/verification.md.
#include "convergence_log.hpp"
#include "febio_block.hpp"
#include "open_body.hpp"
#include "scratch_dir.hpp"

#include <sflsh/body/motion.hpp>
#include <sflsh/model/body_layer.hpp>

#include <gtest/gtest.h>

#include <cstdio>
#include <ostream>

namespace sflsh::testing {
namespace {

constexpr double kBlockDuration = 0.25;  // [s]: the drive's rise to 10 mm and the block's response to it

const FebioBlock& block() {
  static const FebioBlock b = [] {
    BlockSettings s;
    s.duration = kBlockDuration;
    s.integrator = "reference";
    s.rtol = 1e-10;  // ARKODE order 5: ~1e-8 of the motion, far below the smallest error measured here (~1e-5)
    s.atol = 1e-13;
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "sflsh_tests" / "TimeOrder.block";
    std::filesystem::create_directories(dir);
    return load_febio_block(dir, s);
  }();
  return b;
}

const TopTrajectory& block_reference() {
  static const TopTrajectory t = run_reference(block());
  return t;
}

/// The block run with `integrator` at step h (sampled every 1/60 s), its error against the reference.
double block_error(model::Integrator integrator, double h) {
  FebioBlock b = block();
  b.spec.step = h;
  const TopTrajectory run = run_fullspace(b, integrator);
  return relative_difference(run, block_reference(), block_reference());
}

struct OrderCase {
  model::Integrator integrator;
  const char* name;
  double order;  ///< the scheme's order
};

void PrintTo(const OrderCase& c, std::ostream* os) { *os << c.name; }  // gtest's name for a case

class BlockTimeOrder : public ::testing::TestWithParam<OrderCase> {};

TEST_P(BlockTimeOrder, ErrorFallsAtTheSchemesOrder) {
  const OrderCase c = GetParam();
  const std::vector<double> h = {1.0 / 480.0, 1.0 / 960.0, 1.0 / 1920.0};
  std::vector<double> error;
  for (double step : h) error.push_back(block_error(c.integrator, step));
  const double first = observed_order(error[0], error[1]);
  const double second = observed_order(error[1], error[2]);
  std::printf(
      "[ measured ] block, %s: error %.3e / %.3e / %.3e of the motion at h = 1/480, 1/960, 1/1920 s; "
      "observed orders %.2f, %.2f\n",
      c.name, error[0], error[1], error[2], first, second);
  log_convergence("time_block", c.name, h, error);
  // Measured observed orders (coarser pair, finer pair): backward Euler 0.76, 0.80; BDF2 1.97, 2.03; Newmark
  // 2.04, 2.04 (0.67 for backward Euler between 1/240 and 1/480 s). BDF2 and Newmark are asymptotic at these
  // steps. Backward Euler's error is mostly its numerical damping of the block's first shear mode (≈ 9 Hz),
  // a factor exp(−ω²hT/2) that is linear in h only once ω²hT/2 ≪ 1, so its order approaches 1 from below.
  // ±0.25 on the finer pair holds every scheme at its order; a scheme of the other order is off by ≥ 0.75. The
  // reference's own error (rtol 1e-10) is below 1e-3 of the smallest error here.
  EXPECT_NEAR(second, c.order, 0.25);
  EXPECT_NEAR(first, c.order, 0.4);  // the coarser pair, a little farther from the asymptote
  EXPECT_LT(error[2], 0.1);          // and the runs converge onto the reference, not elsewhere
}

INSTANTIATE_TEST_SUITE_P(EveryIntegrator, BlockTimeOrder,
                         ::testing::Values(OrderCase{model::Integrator::backward_euler, "backward_euler", 1.0},
                                           OrderCase{model::Integrator::bdf2, "bdf2", 2.0},
                                           OrderCase{model::Integrator::newmark, "newmark", 2.0}),
                         [](const ::testing::TestParamInfo<OrderCase>& param_info) {
                           return std::string(param_info.param.name);
                         });

// The coarse body layer of a subject along a procedural motion: the soft tissue's response to the skeleton.
class BodyLayerTimeOrder : public ::testing::TestWithParam<OrderCase> {};

TEST_P(BodyLayerTimeOrder, SelfConvergenceFallsAtTheSchemesOrder) {
  const OrderCase c = GetParam();
  static const model::BodyLayer layer = [] {
    model::BodyLayerOptions options;
    options.size = meshing::SizePreset::coarse;
    options.cache_dir = SFLSH_TEST_CACHE;
    options.mass = model::MassKind::consistent;
    const body::Motion motion = body::make_procedural_motion("shake_hips", 60.0, 12);
    body::Betas beta = body::Betas::Zero();
    beta[0] = 1.0;
    return model::build_body_layer(open_body(), beta, motion, nullptr, 6, options);
  }();
  constexpr double kFrame = 1.0 / 60.0;
  constexpr int kFrames = 1;  // [frames of 1/60 s]: the skin answering the first frame of the motion
  const std::vector<double> h = {kFrame / 16.0, kFrame / 32.0, kFrame / 64.0};  // whole frames: the skeleton's
  // trajectory is C¹ between frames, so every step size ends on the frame times.
  std::vector<std::vector<Eigen::VectorXd>> runs;  // per h, the skin's elastic displacement at each frame
  for (double step : h) {
    fullspace::FullSpaceOptions options;
    options.integrator = c.integrator;
    options.default_snes_rtol = 1e-10;
    options.default_snes_atol = 1e-12;
    options.default_ksp_rtol = 1e-10;
    fullspace::FullSpaceSolver solver(layer.problem, MPI_COMM_SELF, options);
    model::State initial = model::initial_state(layer.problem, 0.0);
    if (c.integrator == model::Integrator::newmark) initial.a = model::initial_acceleration(layer.problem, initial);
    solver.initialize(initial);
    std::vector<Eigen::VectorXd> frames;
    const long per_frame = std::lround(kFrame / step);
    for (int f = 1; f <= kFrames; ++f) {
      for (long k = 0; k < per_frame; ++k) solver.step(step);
      const model::RowMatrixX3d d = layer.surface_displacement(solver.state().x);
      frames.push_back(Eigen::Map<const Eigen::VectorXd>(d.data(), d.size()));
    }
    runs.push_back(frames);
  }
  auto difference = [&](std::size_t a, std::size_t b) {
    double out = 0.0;
    for (std::size_t f = 0; f < runs[a].size(); ++f)
      out = std::max(out, (runs[a][f] - runs[b][f]).lpNorm<Eigen::Infinity>());
    return out;
  };
  double motion = 0.0;
  for (const Eigen::VectorXd& d : runs.back()) motion = std::max(motion, d.lpNorm<Eigen::Infinity>());
  const double coarse = difference(0, 1) / motion;
  const double fine = difference(1, 2) / motion;
  const double order = observed_order(coarse, fine);
  std::printf(
      "[ measured ] body layer (%d tets), %s: |u_h − u_h/2| = %.3e, |u_h/2 − u_h/4| = %.3e of the largest "
      "soft-tissue displacement (%.3e m); observed order %.2f\n",
      layer.problem.num_tets(), c.name, coarse, fine, motion, order);
  log_convergence("time_body_layer", c.name, {h[0], h[1]}, {coarse, fine});
  // The differences of successive halvings fall as h^p like the errors. Measured: backward Euler 0.84, BDF2
  // 1.84, Newmark 2.01. At twice these steps (1/480 to 1/1920 s, two frames) BDF2 gave 1.46 and backward
  // Euler 0.70: the thin layer's through-thickness modes (a few hundred rad/s) are resolved only from
  // ωh ≲ 0.25, and below that the implicit schemes' damping of them, not their order, sets the differences.
  // ±0.35 holds each scheme at its order and keeps first and second order apart.
  EXPECT_NEAR(order, c.order, 0.35);
}

INSTANTIATE_TEST_SUITE_P(EveryIntegrator, BodyLayerTimeOrder,
                         ::testing::Values(OrderCase{model::Integrator::backward_euler, "backward_euler", 1.0},
                                           OrderCase{model::Integrator::bdf2, "bdf2", 2.0},
                                           OrderCase{model::Integrator::newmark, "newmark", 2.0}),
                         [](const ::testing::TestParamInfo<OrderCase>& param_info) {
                           return std::string(param_info.param.name);
                         });

}  // namespace
}  // namespace sflsh::testing
