// The body layer of the full-space solver: posing that reproduces `sflsh motion export`, a C¹ skinning
// trajectory whose rates are its derivatives, the attachment of inner and side nodes, and a short run.
#include "open_body.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/body/skinning.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/fullspace/reference_integrator.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/model/skinned_trajectory.hpp>

#include <gtest/gtest.h>
#include <mpi.h>

namespace sflsh::fullspace {
namespace {

using namespace sflsh::model;  // the body layer, its trajectory and writer moved to the model library

using sflsh::testing::open_body;

body::Betas some_beta() {
  body::Betas beta = body::Betas::Zero();
  beta[0] = 1.0;
  beta[1] = -0.5;
  return beta;
}

BodyLayerOptions coarse() {
  BodyLayerOptions options;
  options.size = meshing::SizePreset::coarse;
  options.cache_dir = SFLSH_TEST_CACHE;
  return options;
}

TEST(BodyLayer, RestStatePosesExactlyLikeMotionExport) {
  const body::Motion motion = body::make_procedural_motion("running_on_spot", 60.0, 12);
  const BodyLayer layer = build_body_layer(open_body(), some_beta(), motion, nullptr, 6, coarse());
  const Eigen::Map<const Eigen::VectorXd> rest(layer.problem.rest.data(), layer.problem.num_dofs());
  const body::Poser poser(open_body(), some_beta());
  for (std::size_t f : {std::size_t{0}, std::size_t{5}, std::size_t{11}}) {
    const body::RowMatrixX3d expected =
        poser.pose(motion.poses[f], motion.trans[f]) * motion.world_from_body.transpose();
    const RowMatrixX3d posed = layer.posed_surface(rest, motion.time(f));
    ASSERT_EQ(posed.rows(), expected.rows());
    // Same arithmetic up to the order of the world rotation: round-off only.
    EXPECT_LT((posed - expected).cwiseAbs().maxCoeff(), 1e-12) << "frame " << f;
  }
  EXPECT_LT(layer.surface_displacement(rest).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(BodyLayer, InnerSideAndRimNodesAreAttachedAndSkinNodesFollowTheBody) {
  const body::Motion motion = body::make_procedural_motion("shake_hips", 60.0, 8);
  const BodyLayer layer = build_body_layer(open_body(), some_beta(), motion, nullptr, 6, coarse());
  const Problem& p = layer.problem;
  const std::vector<char> mask = p.dirichlet.mask(p.num_nodes());
  std::vector<char> on_rim(static_cast<std::size_t>(p.num_nodes()), 0);  // the skin's rim is attached too (issue 18)
  for (int v : layer.mesh->rim_nodes()) on_rim[static_cast<std::size_t>(v)] = 1;
  for (int v = 0; v < p.num_nodes(); ++v) {
    const meshing::NodeKind kind = layer.mesh->kind[static_cast<std::size_t>(v)];
    const bool attached =
        kind == meshing::NodeKind::inner || kind == meshing::NodeKind::side || on_rim[static_cast<std::size_t>(v)];
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(mask[static_cast<std::size_t>(3 * v + c)] != 0, attached) << "node " << v;
    }
  }
  EXPECT_GT(p.num_nodes() * 3 - static_cast<int>(p.dirichlet.dof.size()), 0);
  // A skin node that is a body vertex (layered mesher keeps them) rides with that vertex at rest.
  const Eigen::Map<const Eigen::VectorXd> rest(p.rest.data(), p.num_dofs());
  NodeFrame frame;
  p.frame(motion.time(6), frame);
  const RowMatrixX3d nodes = posed_positions(frame, rest);
  const RowMatrixX3d surface = layer.posed_surface(rest, motion.time(6));
  double worst = 0.0;
  int checked = 0;
  for (std::size_t r = 0; r < layer.mesh->skin.node.size(); ++r) {
    const int node = layer.mesh->skin.node[r];
    if (node < 0) continue;
    worst = std::max(worst, (nodes.row(node) - surface.row(layer.mesh->region_surface.vertices[r])).norm());
    ++checked;
  }
  ASSERT_GT(checked, 100);
  // Node weights are the vertex weights carried through the anchors, thinned below 1e-4 and renormalized:
  // the posed positions agree to well under a millimetre.
  EXPECT_LT(worst, 2e-4);
}

TEST(SkinnedTrajectory, RatesAreTimeDerivativesAndFramesAreExact) {
  const body::Motion motion = body::make_procedural_motion("one_leg_jump", 60.0, 20);
  const MotionCurve curve(open_body(), some_beta(), motion);
  JointTransforms m, rate, mp, mm;
  for (double t : {0.1, 0.1 + 0.3 / 60.0, 0.2 + 0.77 / 60.0}) {
    curve.transforms(t, m, &rate);
    const double dt = 1e-6;
    curve.transforms(t + dt, mp);
    curve.transforms(t - dt, mm);
    for (std::size_t k = 0; k < m.size(); ++k) {
      const Matrix34d fd = (mp[k] - mm[k]) / (2 * dt);
      EXPECT_LT((fd - rate[k]).norm(), 1e-5 * (1.0 + rate[k].norm())) << "t = " << t << " joint " << k;
    }
  }
  // C¹ across a frame: left and right rates agree.
  const double tf = 7.0 / 60.0;
  JointTransforms left, right, dummy;
  curve.transforms(tf - 1e-9, dummy, &left);
  curve.transforms(tf + 1e-9, dummy, &right);
  for (std::size_t k = 0; k < left.size(); ++k) EXPECT_LT((left[k] - right[k]).norm(), 1e-5 * (1.0 + left[k].norm()));
}

TEST(BodyLayer, ShortRunStaysFiniteAndProducesSoftTissueMotion) {
  const body::Motion motion = body::make_procedural_motion("running_on_spot", 60.0, 10);
  const BodyLayer layer = build_body_layer(open_body(), body::Betas::Zero(), motion, nullptr, 6, coarse());
  FullSpaceSolver integrator(layer.problem, MPI_COMM_WORLD);
  integrator.initialize(initial_state(layer.problem, 0.0));
  SimulationWriter writer(layer, nullptr, false);
  writer.add_frame(0.0, integrator.state());
  long newton = 0;
  for (std::size_t f = 1; f < motion.num_frames(); ++f) {
    newton += integrator.step(1.0 / 60.0).newton_iterations;
    writer.add_frame(motion.time(f), integrator.state());
  }
  EXPECT_GT(newton, 0);
  const Energies e = energies(layer.problem, integrator.state());
  EXPECT_TRUE(std::isfinite(e.kinetic) && std::isfinite(e.elastic));
  const nlohmann::json d = writer.dynamics_summary();
  // Running shakes the belly: the mean σ is positive and physically sized (between 1 µm and 5 cm).
  EXPECT_GT(d["sigma_mean_mm"].get<double>(), 1e-3);
  EXPECT_LT(d["sigma_max_mm"].get<double>(), 50.0);
}

}  // namespace
}  // namespace sflsh::fullspace
