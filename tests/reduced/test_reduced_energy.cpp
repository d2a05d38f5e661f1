// The reduced potential's derivatives by finite differences: cubature elasticity (gradient and Hessian of
// E(q), exact and projected), and the inertia quadratic (its closed-form linear term and mass Hessian
// against the node-by-node definition, with the joint-pair decomposition of skinned node maps).
#include "open_body.hpp"
#include "reduced_fixtures.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/reduced/cubature_elastic.hpp>
#include <sflsh/reduced/reduced_inertia.hpp>
#include <sflsh/reduced/reduced_model.hpp>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <random>
#include <set>

namespace sflsh::reduced {
namespace {

using testing::random_q;

class ReducedElasticFd : public ::testing::TestWithParam<double> {};

TEST_P(ReducedElasticFd, GradientAndHessianMatchCentralDifferences) {
  // Amplitudes from small strain to large stretch (Fung stiffening active).
  const auto c = testing::box_case({3, 3, 2});
  const Subspace s = testing::box_subspace(c);
  Cubature cub = exact_cubature(c.problem.num_tets());
  for (std::size_t k = 0; k < cub.weights.size(); ++k)
    cub.weights[k] = 0.5 + 0.1 * static_cast<double>(k % 7);  // any ω ≥ 0
  const CubatureElastic elastic(c.problem, s, cub);
  const Eigen::VectorXd q = random_q(s.num_dofs(), GetParam(), 11);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(s.num_dofs());
  elastic.add_gradient(q, g);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(s.num_dofs(), s.num_dofs());
  elastic.add_hessian(q, H, material::HessianProjection::kNone);
  const double h = 1e-7;
  Eigen::VectorXd g_fd(s.num_dofs());
  Eigen::MatrixXd H_fd(s.num_dofs(), s.num_dofs());
  for (int k = 0; k < s.num_dofs(); ++k) {
    Eigen::VectorXd qp = q, qm = q;
    qp[k] += h;
    qm[k] -= h;
    g_fd[k] = (elastic.energy(qp) - elastic.energy(qm)) / (2 * h);
    Eigen::VectorXd gp = Eigen::VectorXd::Zero(s.num_dofs()), gm = gp;
    elastic.add_gradient(qp, gp);
    elastic.add_gradient(qm, gm);
    H_fd.col(k) = (gp - gm) / (2 * h);
  }
  // Central differences: truncation ~h²|f'''| and round-off ~ε|f|/h, both ≲ 1e-6 relative here.
  EXPECT_LT((g - g_fd).cwiseAbs().maxCoeff(), 1e-6 * g.cwiseAbs().maxCoeff());
  EXPECT_LT((H - H_fd).cwiseAbs().maxCoeff(), 1e-6 * H.cwiseAbs().maxCoeff());
  EXPECT_LT((H - H.transpose()).cwiseAbs().maxCoeff(), 1e-12 * H.cwiseAbs().maxCoeff());
  // The projected Hessian is positive semi-definite.
  Eigen::MatrixXd Hp = Eigen::MatrixXd::Zero(s.num_dofs(), s.num_dofs());
  elastic.add_hessian(q, Hp, material::HessianProjection::kStressDerivative);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Hp);
  EXPECT_GE(eig.eigenvalues().minCoeff(), -1e-10 * eig.eigenvalues().cwiseAbs().maxCoeff());
}

INSTANTIATE_TEST_SUITE_P(Amplitudes, ReducedElasticFd, ::testing::Values(1e-4, 3e-3, 1e-2));

using sflsh::testing::open_body;

TEST(ReducedInertia, ClosedFormMatchesTheNodeByNodePotential) {
  model::BodyLayerOptions options;
  options.size = meshing::SizePreset::coarse;
  options.cache_dir = SFLSH_TEST_CACHE;
  const body::Motion motion = body::make_procedural_motion("shake_hips", 60.0, 30);
  body::Betas beta = body::Betas::Zero();
  beta[1] = 1.0;
  const model::BodyLayer layer = model::build_body_layer(open_body(), beta, motion, nullptr, 6, options);
  ReducedModelOptions ro;
  ro.point_handles = 30;
  ro.cubature = 50;
  ro.cache_dir = SFLSH_TEST_CACHE;
  const ReducedModel model = build_reduced_model(layer, ro);
  const model::Problem& p = layer.problem;
  ReducedInertia inertia(p, model.subspace);
  const double t = 0.37, h = 1.0 / 60.0;  // between frames: the interpolated node maps, hips rotated
  const Eigen::VectorXd x_d = Eigen::Map<const Eigen::VectorXd>(p.rest.data(), p.num_dofs());
  inertia.set_time(t, x_d);
  const std::vector<int>& active = inertia.active_nodes();
  meshing::RowMatrixX3d p_tilde(static_cast<Eigen::Index>(active.size()), 3);
  model::NodeFrame frame;
  p.frame(t, frame);
  std::mt19937 rng(5);
  std::normal_distribution<double> normal(0.0, 0.01);
  for (std::size_t a = 0; a < active.size(); ++a) {
    const int i = active[a];
    const Eigen::Vector3d skinned =
        frame.A[static_cast<std::size_t>(i)] * x_d.segment<3>(3 * i) + frame.d.row(i).transpose();
    p_tilde.row(static_cast<Eigen::Index>(a)) =
        (skinned + Eigen::Vector3d(normal(rng), normal(rng), normal(rng))).transpose();
  }
  const Eigen::VectorXd c = inertia.linear_term(p_tilde, h, true);
  Eigen::MatrixXd H;
  inertia.mass_hessian(h, H);
  // The definition: Σ_i m_i/(2h²)|A_i x_i + d_i − p̃_i|² over the active nodes, x = x_D + Bq.
  const auto potential = [&](const Eigen::VectorXd& q) {
    Eigen::VectorXd x = x_d;
    model.subspace.add_displacement(q, x);
    double value = 0.0;
    for (std::size_t a = 0; a < active.size(); ++a) {
      const int i = active[a];
      const Eigen::Vector3d pi =
          frame.A[static_cast<std::size_t>(i)] * x.segment<3>(3 * i) + frame.d.row(i).transpose();
      value += 0.5 * p.mass[i] / (h * h) * (pi - p_tilde.row(static_cast<Eigen::Index>(a)).transpose()).squaredNorm();
    }
    return value;
  };
  const Eigen::VectorXd q = random_q(model.subspace.num_dofs(), 0.005, 9);
  const double base = potential(Eigen::VectorXd::Zero(q.size()));
  // Exactly quadratic: Φ(q) − Φ(0) = cᵀq + ½qᵀHq (round-off of sums over ~5000 nodes).
  const double closed = c.dot(q) + 0.5 * q.dot(H * q);
  EXPECT_NEAR(potential(q) - base, closed, 1e-9 * std::abs(closed));
  // The joint-pair mass Hessian equals Σ_i m_i b_is b_ir A_iᵀA_i / h².
  Eigen::MatrixXd brute = Eigen::MatrixXd::Zero(H.rows(), H.cols());
  for (int i : active) {
    const Eigen::Matrix3d AtA = frame.A[static_cast<std::size_t>(i)].transpose() * frame.A[static_cast<std::size_t>(i)];
    for (SparseRowMatrix::InnerIterator si(model.subspace.basis, i); si; ++si)
      for (SparseRowMatrix::InnerIterator ri(model.subspace.basis, i); ri; ++ri)
        brute.block<3, 3>(3 * si.col(), 3 * ri.col()) += p.mass[i] * si.value() * ri.value() * AtA / (h * h);
  }
  EXPECT_LT((H - brute).cwiseAbs().maxCoeff(), 1e-10 * brute.cwiseAbs().maxCoeff());
}

TEST(BodyHandles, PlacedInsideTheLayerNestedAndDistinct) {
  model::BodyLayerOptions options;
  options.size = meshing::SizePreset::coarse;
  options.cache_dir = SFLSH_TEST_CACHE;
  const body::Motion motion = body::make_procedural_motion("jiggle_on_toes", 60.0, 4);
  const model::BodyLayer layer = model::build_body_layer(open_body(), body::Betas::Zero(), motion, nullptr, 6, options);
  const BodyHandles h86 = place_body_handles(layer, 86), h30 = place_body_handles(layer, 30);
  ASSERT_EQ(h86.point_nodes.size(), 86u);
  EXPECT_TRUE(std::equal(h30.point_nodes.begin(), h30.point_nodes.end(), h86.point_nodes.begin()));
  EXPECT_EQ(std::set<int>(h86.point_nodes.begin(), h86.point_nodes.end()).size(), 86u);
  const std::vector<char> fixed = layer.problem.dirichlet.mask(layer.problem.num_nodes());
  int torso = 0;
  const bool has_interior = !layer.mesh->nodes_of_kind(meshing::NodeKind::interior).empty();
  for (int v : h86.point_nodes) {
    EXPECT_FALSE(fixed[static_cast<std::size_t>(3 * v)]);
    // At mid-depth where the mesh has interior nodes (default, fine); the coarse layered mesh is one tet layer
    // thick (skin and bone nodes only), so its free nodes — and handles — are on the skin.
    if (has_interior) {
      EXPECT_GT(layer.depth[v], 0.25);
    }
    if (layer.mesh->node_part[static_cast<std::size_t>(v)] == meshing::Part::torso) ++torso;
  }
  EXPECT_GT(torso, 86 / 2);  // denser on the torso (paper Fig. 2)
  // Every attached node belongs to a bone handle; the bones are skeleton joints.
  for (int i = 0; i < layer.problem.num_nodes(); ++i)
    EXPECT_EQ(fixed[static_cast<std::size_t>(3 * i)] != 0, h86.bone_of_node[static_cast<std::size_t>(i)] >= 0);
  EXPECT_GE(h86.bone_joints().size(), 5u);
  EXPECT_THROW(place_body_handles(layer, 100000), Error);
}

}  // namespace
}  // namespace sflsh::reduced
