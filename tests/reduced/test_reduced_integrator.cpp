// The reduced backward-Euler integrator: with every tet as cubature and a basis spanning the free space it
// is the full-space solver; a free oscillation in the handle subspace decays; failures are loud and leave
// the state untouched; the body model is cached and rebuilt when the cache entry is corrupt.
#include "open_body.hpp"
#include "reduced_fixtures.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/reduced/reduced_model.hpp>
#include <sflsh/reduced/reduced_solver.hpp>

#include <gtest/gtest.h>
#include <petscsys.h>

#include <cmath>
#include <fstream>

namespace sflsh::reduced {
namespace {

using testing::shake;

TEST(ReducedIntegrator, FullBasisAndExactCubatureReproduceTheFullSpaceSolver) {
  const model::ScalarDrive drive = shake(0.006, 4.0);
  const auto c = testing::box_case({3, 3, 2}, 1000.0, &drive);
  const Subspace s = testing::full_basis(c.problem);
  const Cubature all = exact_cubature(c.problem.num_tets());
  ReducedOptions ro;
  ro.gradient_rtol = 1e-13;
  ro.gradient_atol = 1e-14;
  ro.step_tolerance = 1e-14;
  ro.use_predictor = false;
  ReducedSolver reduced(c.problem, s, all, ro);
  fullspace::FullSpaceOptions fo;
  fo.default_snes_rtol = 1e-13;
  fo.default_snes_atol = 1e-14;
  fo.default_ksp_rtol = 1e-13;
  fo.use_predictor = false;
  fullspace::FullSpaceSolver full(c.problem, PETSC_COMM_WORLD, fo);
  const model::State start = model::initial_state(c.problem, 0.0);
  reduced.initialize(start);
  full.initialize(start);
  double worst = 0.0, largest = 0.0;
  const Eigen::Map<const Eigen::VectorXd> rest(c.problem.rest.data(), c.problem.num_dofs());
  for (int k = 0; k < 40; ++k) {
    reduced.step(1.0 / 120.0);
    full.step(1.0 / 120.0);
    const model::State a = reduced.full_state();
    worst = std::max(worst, (a.x - full.state().x).cwiseAbs().maxCoeff());
    largest = std::max(largest, (full.state().x - rest).cwiseAbs().maxCoeff());
  }
  ASSERT_GT(largest, 1e-3);
  // Both minimize the same incremental potential to ~1e-13 relative gradient: the trajectories agree to
  // the solver tolerance (accumulated over 40 steps), far below the 6 mm motion.
  EXPECT_LT(worst, 1e-8 * std::max(1.0, largest / 1e-3)) << "largest displacement " << largest;
}

TEST(ReducedIntegrator, FreeOscillationInTheHandleSubspaceDecays) {
  const auto c = testing::box_case({4, 4, 3});
  const Subspace s = testing::box_subspace(c);
  const Cubature all = exact_cubature(c.problem.num_tets());
  ReducedSolver reduced(c.problem, s, all);
  model::State start = model::initial_state(c.problem, 0.0);
  Eigen::VectorXd q0 = Eigen::VectorXd::Zero(s.num_dofs());
  for (int j = 0; j < s.num_functions(); ++j) q0[3 * j] = 0.004;  // every handle pulled 4 mm along x
  s.add_displacement(q0, start.x);
  reduced.initialize(start);
  EXPECT_LT((reduced.q() - q0).cwiseAbs().maxCoeff(), 1e-12);  // the initial state lies in the subspace
  const auto total = [&]() {
    const model::State st = reduced.full_state();
    return model::energies(c.problem, st).kinetic + model::energies(c.problem, st).elastic;
  };
  const double e0 = total();
  ASSERT_GT(e0, 0.0);
  double previous = e0, last = e0;
  for (int k = 0; k < 120; ++k) {
    const model::StepStats st = reduced.step(1.0 / 60.0);
    EXPECT_EQ(st.failed_attempts, 0);
    last = total();
    // Backward Euler dissipates: the energy never grows (1e-9 relative slack for Newton's tolerance).
    EXPECT_LE(last, previous * (1.0 + 1e-9) + 1e-15) << "step " << k;
    previous = last;
  }
  EXPECT_LT(last, 0.5 * e0);
}

TEST(ReducedIntegrator, AnImpossibleStepFailsLoudlyAndLeavesTheStateUnchanged) {
  // The bottom face is pulled 30 cm down within one step while the top face is held: the 6 cm box would have
  // to stretch sixfold, the Fung exponent exceeds its cap in every state of the last substep, and no step
  // can be taken.
  const model::ScalarDrive drive{[](double t) { return -0.3 * t / 0.01; }, [](double) { return -30.0; }};
  auto c = testing::box_case({3, 3, 2}, 1000.0, &drive);
  model::Problem& p = c.problem;
  for (int v : c.mesh.node_groups.at("zmax")) p.dirichlet.add(v, 0b111u);
  p.validate();
  std::vector<char> attached = testing::attached_flags(c);
  for (int v : c.mesh.node_groups.at("zmax")) attached[static_cast<std::size_t>(v)] = 1;
  const HandleSets sets = testing::box_handle_sets(c);
  const Eigen::MatrixXd W = handle_weights(p.rest, p.tets, sets, static_cast<int>(c.point_handles.size()));
  const Subspace s = point_handle_subspace(W, attached, p.rest, c.point_handles, BasisOptions{});
  const Cubature all = exact_cubature(p.num_tets());
  ReducedOptions ro;
  ro.max_halvings = 2;
  ReducedSolver reduced(p, s, all, ro);
  reduced.initialize(model::initial_state(p, 0.0));
  const Eigen::VectorXd q_before = reduced.q();
  try {
    reduced.step(0.01);
    FAIL() << "the step should have failed";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("t = 0.01 s"), std::string::npos) << message;  // the robustness ladder names the step's end
    EXPECT_NE(message.find("4 substeps"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  EXPECT_EQ(reduced.time(), 0.0);
  EXPECT_EQ((reduced.q() - q_before).cwiseAbs().maxCoeff(), 0.0);
}

TEST(ReducedIntegrator, PartiallyAttachedNodesAreRefused) {
  auto c = testing::box_case({2, 2, 2});
  model::Problem p = c.problem;
  p.dirichlet = {};
  p.dirichlet.add(c.attached[0], 0b001u);
  for (std::size_t k = 1; k < c.attached.size(); ++k) p.dirichlet.add(c.attached[k], 0b111u);
  p.validate();
  const Subspace s = testing::full_basis(p);
  const Cubature all = exact_cubature(p.num_tets());
  EXPECT_THROW(ReducedSolver(p, s, all), Error);
}

using sflsh::testing::open_body;

TEST(ReducedModel, CachedModelEqualsTheBuiltOneAndACorruptEntryIsRebuilt) {
  model::BodyLayerOptions options;
  options.size = meshing::SizePreset::coarse;
  options.cache_dir = SFLSH_TEST_CACHE;
  const body::Motion motion = body::make_procedural_motion("jiggle_on_toes", 60.0, 4);
  const model::BodyLayer layer = model::build_body_layer(open_body(), body::Betas::Zero(), motion, nullptr, 6, options);
  const std::filesystem::path dir = std::filesystem::path(SFLSH_TEST_CACHE) / "reduced-cache-test";
  std::filesystem::remove_all(dir);
  ReducedModelOptions ro;
  ro.point_handles = 24;
  ro.cubature = 60;
  ro.cache_dir = dir;
  const ReducedModel built = build_reduced_model(layer, ro);
  EXPECT_EQ(built.cache_outcome, "built");
  const ReducedModel hit = build_reduced_model(layer, ro);
  EXPECT_EQ(hit.cache_outcome, "hit");
  EXPECT_EQ(hit.handles.point_nodes, built.handles.point_nodes);
  EXPECT_EQ(hit.cubature.tets, built.cubature.tets);
  EXPECT_EQ(hit.cubature.weights, built.cubature.weights);
  EXPECT_EQ(
      (Eigen::SparseMatrix<double>(hit.subspace.basis) - Eigen::SparseMatrix<double>(built.subspace.basis)).norm(),
      0.0);
  EXPECT_EQ(hit.handles.bone_of_node, built.handles.bone_of_node);
  for (const auto& entry : std::filesystem::directory_iterator(dir)) std::ofstream(entry.path()) << "not a zip archive";
  const ReducedModel rebuilt = build_reduced_model(layer, ro);
  EXPECT_EQ(rebuilt.cache_outcome, "built");
  EXPECT_EQ(rebuilt.cubature.tets, built.cubature.tets);
  std::filesystem::remove_all(dir);
}

TEST(ReducedModel, BodyRunStaysFiniteAndMovesTheSkin) {
  model::BodyLayerOptions options;
  options.size = meshing::SizePreset::coarse;
  options.cache_dir = SFLSH_TEST_CACHE;
  const body::Motion motion = body::make_procedural_motion("jiggle_on_toes", 60.0, 40);
  const model::BodyLayer layer = model::build_body_layer(open_body(), body::Betas::Zero(), motion, nullptr, 6, options);
  ReducedModelOptions ro;
  ro.cache_dir = SFLSH_TEST_CACHE;
  const ReducedModel model = build_reduced_model(layer, ro);
  EXPECT_EQ(model.subspace.num_dofs(), 3 * 86);
  ReducedSolver integrator(layer.problem, model.subspace, model.cubature);
  integrator.initialize(model::initial_state(layer.problem, 0.0));
  double largest = 0.0;
  long newton = 0, factorizations = 0;
  for (std::size_t f = 1; f < motion.num_frames(); ++f) {
    const model::StepStats st = integrator.step(1.0 / 60.0);
    EXPECT_LE(st.newton_iterations, 20);
    EXPECT_EQ(st.failed_attempts, 0);
    newton += st.newton_iterations;
    factorizations += st.factorizations;
    const model::State s = integrator.full_state();
    ASSERT_TRUE(s.x.allFinite() && s.w.allFinite());
    largest = std::max(largest, layer.surface_displacement(s.x).cwiseAbs().maxCoeff());
  }
  // From the predictor, Newton with a reused factor needs a few cheap iterations per 1/60 s step (measured
  // ≈ 7) and rarely a new factorization (measured < 1 per step): bounds with a margin of ~1.5×.
  const double steps = static_cast<double>(motion.num_frames() - 1);
  EXPECT_LE(static_cast<double>(newton) / steps, 11.0);
  EXPECT_LE(static_cast<double>(factorizations) / steps, 1.5);
  // Jiggling on the toes shakes the tissue by millimetres to centimetres, not microns and not metres.
  EXPECT_GT(largest, 1e-3);
  EXPECT_LT(largest, 0.1);
}

}  // namespace
}  // namespace sflsh::reduced
