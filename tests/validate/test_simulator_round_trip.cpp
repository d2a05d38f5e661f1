// docs/physics.md §4, last paragraph: for a simulation driven by the same poses, inverse skinning returns the
// elastic displacement exactly, so the metric pipeline run on the simulator's posed surfaces (written to and
// read back from a DYNA file) must reproduce the simulator's own σ on the region's vertices.
#include "scratch_dir.hpp"
#include "validate_fixtures.hpp"

#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/validate/dyna_file.hpp>
#include <sflsh/validate/dynamics_metrics.hpp>

#include <gtest/gtest.h>
#include <mpi.h>

namespace sflsh::validate {
namespace {

using testing::open_body;
using testing::some_beta;

TEST(SimulatorRoundTrip, MetricOfSimulatedSurfacesEqualsTheSimulatorsSigma) {
  const body::Motion motion = body::make_procedural_motion("running_on_spot", 60.0, 14);
  model::BodyLayerOptions options;
  options.size = meshing::SizePreset::coarse;
  options.cache_dir = SFLSH_TEST_CACHE;
  const model::BodyLayer layer = model::build_body_layer(open_body(), some_beta(), motion, nullptr, 6, options);
  fullspace::FullSpaceSolver integrator(layer.problem, MPI_COMM_WORLD);
  integrator.initialize(model::initial_state(layer.problem, 0.0));
  model::SimulationWriter writer(layer, nullptr, false);
  DynaSequence simulated;
  simulated.key = "sim_running_on_spot";
  for (std::size_t f = 0; f < motion.num_frames(); ++f) {
    if (f > 0) integrator.step(1.0 / motion.fps);
    const model::State state = integrator.state();
    writer.add_frame(motion.time(f), state);
    simulated.frames.push_back(layer.posed_surface(state.x, motion.time(f)));
  }
  const auto path = sflsh::testing::scratch_dir() / "simulated.h5";
  write_dyna_file(path, open_body().faces, {simulated});
  const DynaFile file(path);
  file.require_vertices(open_body());
  const DynaSequence read = file.read(simulated.key);

  const std::vector<int>& region = layer.mesh->region_surface.vertices;
  EXPECT_EQ(region, soft_region_vertices(open_body()));  // the metric's soft region is the layer's
  const DynamicsResult r = dynamics_metrics(open_body(), some_beta(), motion, read.frames, region);
  const Eigen::VectorXd expected = writer.sigma_per_vertex();
  ASSERT_GT(expected.maxCoeff(), 1e-5);  // the run produced soft-tissue motion (≥ 10 µm somewhere)
  double worst = 0.0;
  for (int v : region) worst = std::max(worst, std::abs(r.sigma[v] - expected[v]));
  // Same poses, same skinning arithmetic (posed_surface reproduces body::forward_kinematics to 1e-12 m,
  // test_body_layer), float64 storage: σ agrees to round-off; 1e-9 m is 1e-6 of a millimetre amplitude.
  EXPECT_LT(worst, 1e-9);
  // Outside the region the surfaces follow the skeleton exactly: σ vanishes there.
  std::vector<char> inside(static_cast<std::size_t>(open_body().num_vertices()), 0);
  for (int v : region) inside[static_cast<std::size_t>(v)] = 1;
  double outside = 0.0;
  for (Eigen::Index v = 0; v < open_body().num_vertices(); ++v)
    if (!inside[static_cast<std::size_t>(v)]) outside = std::max(outside, r.sigma[v]);
  EXPECT_LT(outside, 1e-9);
  EXPECT_NEAR(r.mean_sigma_soft(), writer.dynamics_summary()["sigma_mean_mm"].get<double>() * 1e-3, 1e-9);
}

}  // namespace
}  // namespace sflsh::validate
