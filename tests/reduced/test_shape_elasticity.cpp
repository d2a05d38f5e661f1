// Shape-dependent elasticity (SFLSH §4, eqs. 1, 4, 7): the linear model, its Jacobian, the local shape
// metric Q_i and the regularizer matrix L.
#include "open_body.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/material/layer_material.hpp>
#include <sflsh/material/surface_operators.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/reduced/layer_parameterization.hpp>
#include <sflsh/reduced/shape_elasticity.hpp>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <random>

namespace sflsh {

using namespace sflsh::reduced;

namespace {

ShapeElasticity random_model(int N, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  ShapeElasticity s;
  s.A.resize(static_cast<std::size_t>(N));
  for (auto& a : s.A) a = ShapeMatrix::NullaryExpr([&] { return u(rng); });
  s.b = material::KappaMatrix::NullaryExpr(N, 3, [&] { return 0.5 + u(rng); });
  return s;
}

using sflsh::testing::open_body;

const model::BodyLayer& coarse_layer() {
  static const model::BodyLayer layer = [] {
    model::BodyLayerOptions options;
    options.size = meshing::SizePreset::coarse;
    options.cache_dir = SFLSH_TEST_CACHE;
    return model::build_body_layer(open_body(), body::Betas::Zero(),
                                   body::make_procedural_motion("shake_hips", 60.0, 3), nullptr, 1, options);
  }();
  return layer;
}

}  // namespace

TEST(ShapeElasticity, PackUnpackAndLinearModel) {
  const ShapeElasticity s = random_model(5, 1);
  const Eigen::VectorXd p = s.pack();
  ASSERT_EQ(p.size(), 33 * 5);
  const ShapeElasticity t = ShapeElasticity::unpack(p, 5);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(t.A[static_cast<std::size_t>(i)], s.A[static_cast<std::size_t>(i)]);
  EXPECT_EQ(t.b, s.b);
  body::Betas beta;
  beta << 1.0, -2.0, 0.5, 0.0, 3.0, -1.0, 0.2, 0.1, -0.3, 2.0;
  const material::KappaMatrix k = s.kappa_normalized(beta);
  for (int i = 0; i < 5; ++i)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(k(i, c), s.A[static_cast<std::size_t>(i)].col(c).dot(beta) + s.b(i, c), 1e-15);
  // dq/dp (eq. 8) reproduces the linear model exactly (row 3i + c).
  const Eigen::VectorXd q = kappa_jacobian(beta, 5) * p;
  for (int i = 0; i < 5; ++i)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(q[3 * i + c], k(i, c), 1e-14);
  EXPECT_THROW(ShapeElasticity::unpack(p.head(32), 1), Error);
}

TEST(ShapeElasticity, L2RegularizerIsTheFrobeniusNorm) {
  const int N = 4;
  const ShapeElasticity s = random_model(N, 2);
  const Eigen::SparseMatrix<double> L = regularizer_matrix({}, N);  // Q = I
  double expected = 0.0;
  for (const ShapeMatrix& a : s.A) expected += (a.transpose() * a).trace();
  EXPECT_NEAR((L * s.pack()).squaredNorm(), expected / N, 1e-14);
  // The b_i are not regularized.
  ShapeElasticity only_b = s;
  for (auto& a : only_b.A) a.setZero();
  EXPECT_EQ((L * only_b.pack()).norm(), 0.0);
}

TEST(ShapeElasticity, LocalMetricIsSymmetricPositiveDefiniteAndGivesTheTrace) {
  const model::BodyLayer& layer = coarse_layer();
  const LayerParameterization param(layer, 12);
  const meshing::LayerMesh& mesh = *layer.mesh;
  const Eigen::VectorXd area =
      material::lumped_mass(material::region_positions(open_body(), mesh), mesh.region_surface.faces);
  const std::vector<ShapeMetric> Q = local_shape_metric(open_body(), mesh.region_surface.vertices, area, param.phi());
  ASSERT_EQ(Q.size(), 12u);
  const std::vector<ShapeMetric> M =
      local_shape_covariance(open_body(), mesh.region_surface.vertices, area, param.phi());
  ASSERT_EQ(M.size(), 12u);
  double trace_sum = 0.0;
  double largest = 0.0;
  for (std::size_t i = 0; i < Q.size(); ++i) {
    const ShapeMetric& q = Q[i];
    EXPECT_LT((q - q.transpose()).norm(), 1e-12 * q.norm());
    const Eigen::SelfAdjointEigenSolver<ShapeMetric> eig(q);
    EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
    EXPECT_LT((q * M[i] - ShapeMetric::Identity()).norm(), 1e-8);  // Q_i = (M_i / m)⁻¹ (eq. 4)
    trace_sum += M[i].trace();
    largest = std::max(largest, Eigen::SelfAdjointEigenSolver<ShapeMetric>(M[i]).eigenvalues().maxCoeff());
  }
  // The common scale sits on the covariance (shape_elasticity.hpp): mean tr(M_i)/10 = 1, so the leading
  // directions of β (eigenvalues of M_i of order one to ten; 11 measured) cost about what L² charges, not
  // 10⁵× less as when the inverse carried the scale.
  EXPECT_NEAR(trace_sum / (10.0 * 12.0), 1.0, 1e-12);
  EXPECT_GT(largest, 1.0);
  EXPECT_LT(largest, 100.0);
  // ‖L p‖² = (1/N) Σ tr(A_iᵀ Q_i A_i) (eq. 7).
  const ShapeElasticity s = random_model(12, 3);
  double expected = 0.0;
  for (int i = 0; i < 12; ++i)
    expected += (s.A[static_cast<std::size_t>(i)].transpose() * Q[static_cast<std::size_t>(i)] *
                 s.A[static_cast<std::size_t>(i)])
                    .trace();
  EXPECT_NEAR((regularizer_matrix(Q, 12) * s.pack()).squaredNorm(), expected / 12.0, 1e-10 * expected);
  // Directions of β that barely change the local shape cost more than the ones that change it a lot:
  // the metrics differ between control points (they are local), unlike L².
  double spread = 0.0;
  for (int i = 1; i < 12; ++i) spread = std::max(spread, (Q[static_cast<std::size_t>(i)] - Q[0]).norm() / Q[0].norm());
  EXPECT_GT(spread, 0.05);
}

TEST(ShapeElasticity, ControlValuesTransferBetweenNestedSets) {
  const model::BodyLayer& layer = coarse_layer();
  const LayerParameterization small(layer, 4), large(layer, 12);
  // Nested: the first 4 of the 12 are the 4, and a field given on the 4 is kept at those points.
  for (int i = 0; i < 4; ++i)
    EXPECT_EQ(small.control_vertices()[static_cast<std::size_t>(i)],
              large.control_vertices()[static_cast<std::size_t>(i)]);
  Eigen::MatrixXd values(4, 2);
  values << 1, 10, 2, 20, 3, 30, 4, 40;
  const Eigen::MatrixXd t = transfer_control_values(small, large, values);
  EXPECT_LT((t.topRows(4) - values).norm(), 1e-9);
  // A constant stays constant (partition of unity).
  const Eigen::MatrixXd c = transfer_control_values(small, large, Eigen::MatrixXd::Constant(4, 1, 0.7));
  EXPECT_LT((c.array() - 0.7).abs().maxCoeff(), 1e-9);
}

TEST(ShapeElasticity, BoundsAndClamp) {
  Eigen::VectorXd lo, hi;
  parameter_bounds(material::ParameterBounds{}, 2, 0.3, lo, hi);
  EXPECT_EQ(lo.size(), 66);
  EXPECT_DOUBLE_EQ(lo[0], -0.3);
  EXPECT_DOUBLE_EQ(hi[30], 1.0);
  EXPECT_NEAR(lo[30], 0.1 / 0.9, 1e-15);
  material::KappaMatrix k(1, 3);
  k << 1.5, 0.001, 0.5;
  int moved = 0;
  const material::KappaMatrix c = clamp_normalized(k, material::ParameterBounds{}, &moved);
  EXPECT_EQ(moved, 2);
  EXPECT_DOUBLE_EQ(c(0, 0), 1.0);
  EXPECT_DOUBLE_EQ(c(0, 1), 0.01);
  EXPECT_DOUBLE_EQ(c(0, 2), 0.5);
}

}  // namespace sflsh
