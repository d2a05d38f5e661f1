// Handle weights (Wang et al. 2015): linear precision of the operator, interpolation at the handles,
// partition of unity, smoothness, the truncated basis; handle placement on the body layer.
#include "reduced_fixtures.hpp"

#include <sflsh/core/error.hpp>

#include <gtest/gtest.h>

#include <random>

namespace sflsh::reduced {
namespace {

using testing::box_case;
using testing::box_handle_sets;

TEST(Weights, LinearlyPreciseLaplacianAnnihilatesAffineFunctions) {
  const auto c = box_case({3, 3, 2});
  const SparseMatrixd K = linearly_precise_laplacian(c.problem.rest, c.problem.tets);
  const Eigen::VectorXd one = Eigen::VectorXd::Ones(c.problem.num_nodes());
  const Eigen::VectorXd affine =
      0.3 * one + 2.0 * c.problem.rest.col(0) - 1.5 * c.problem.rest.col(1) + 0.7 * c.problem.rest.col(2);
  // Round-off only: entries of K are V|∇φ|² ~ 1e-3, so 1e-12 is ~1e-9 relative.
  EXPECT_LT((K * one).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((K * affine).cwiseAbs().maxCoeff(), 1e-12);
  // Hence the energy Kᵀ M⁻¹ K has affine functions in its null space (entries ~1e2: 1e-9 is round-off).
  const SparseMatrixd Q = linearly_precise_biharmonic(c.problem.rest, c.problem.tets);
  EXPECT_LT((Q * affine).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_GT(Q.cwiseAbs().sum(), 0.0);
}

TEST(Weights, AffineConstraintValuesAreReproducedEverywhere) {
  // Linear precision: handle values sampled from an affine function give that function at every node.
  const auto c = box_case();
  std::vector<int> constrained = c.attached;
  constrained.insert(constrained.end(), c.point_handles.begin(), c.point_handles.end());
  const auto f = [](const Eigen::RowVector3d& x) { return 0.2 + 3.0 * x[0] - x[1] + 5.0 * x[2]; };
  Eigen::VectorXd values(static_cast<Eigen::Index>(constrained.size()));
  for (std::size_t k = 0; k < constrained.size(); ++k)
    values[static_cast<Eigen::Index>(k)] = f(c.problem.rest.row(constrained[k]));
  const Eigen::VectorXd w = biharmonic_interpolate(c.problem.rest, c.problem.tets, constrained, values);
  double worst = 0.0;
  for (int i = 0; i < c.problem.num_nodes(); ++i) worst = std::max(worst, std::abs(w[i] - f(c.problem.rest.row(i))));
  EXPECT_LT(worst, 1e-9);  // values ~0.5; a sparse direct solve: round-off amplified by the condition number
}

TEST(Weights, InterpolateAtHandlesAndSumToOne) {
  const auto c = box_case();
  const HandleSets sets = box_handle_sets(c);
  const Eigen::MatrixXd W = handle_weights(c.problem.rest, c.problem.tets, sets);
  ASSERT_EQ(W.cols(), static_cast<Eigen::Index>(sets.handle_nodes.size()));
  for (std::size_t j = 0; j < sets.handle_nodes.size(); ++j)
    for (std::size_t k = 0; k < sets.handle_nodes.size(); ++k)
      for (int v : sets.handle_nodes[k]) EXPECT_EQ(W(v, static_cast<Eigen::Index>(j)), j == k ? 1.0 : 0.0);
  EXPECT_LT((W.rowwise().sum().array() - 1.0).abs().maxCoeff(), 1e-10);
  // Each column is the constrained minimizer: any perturbation that keeps the constraints raises the energy.
  const SparseMatrixd Q = linearly_precise_biharmonic(c.problem.rest, c.problem.tets);
  std::vector<char> constrained(static_cast<std::size_t>(c.problem.num_nodes()), 0);
  for (const auto& set : sets.handle_nodes)
    for (int v : set) constrained[static_cast<std::size_t>(v)] = 1;
  std::mt19937 rng(4);
  std::normal_distribution<double> normal(0.0, 0.05);
  for (Eigen::Index j = 0; j < W.cols(); ++j) {
    const Eigen::VectorXd w = W.col(j);
    const double energy = w.dot(Q * w);
    for (int trial = 0; trial < 5; ++trial) {
      Eigen::VectorXd v(w.size());
      for (Eigen::Index i = 0; i < v.size(); ++i) v[i] = constrained[static_cast<std::size_t>(i)] ? 0.0 : normal(rng);
      EXPECT_GT((w + v).dot(Q * (w + v)), energy) << "handle " << j;
      // First-order optimality: the energy's gradient vanishes on the free nodes (relative round-off).
      EXPECT_LT(std::abs(v.dot(Q * w)), 1e-9 * std::sqrt(energy * v.dot(Q * v)) + 1e-12) << "handle " << j;
    }
  }
}

TEST(Weights, OnlyRequestedColumnsMatchTheFullSolve) {
  const auto c = box_case();
  const Eigen::MatrixXd all = handle_weights(c.problem.rest, c.problem.tets, box_handle_sets(c));
  const Eigen::MatrixXd first = handle_weights(c.problem.rest, c.problem.tets, box_handle_sets(c), 2);
  ASSERT_EQ(first.cols(), 2);
  EXPECT_LT((first - all.leftCols(2)).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(Weights, BadHandleSetsAreRejected) {
  const auto c = box_case({2, 2, 2});
  HandleSets overlap = box_handle_sets(c);
  overlap.handle_nodes[0].push_back(overlap.handle_nodes[1][0]);
  EXPECT_THROW(handle_weights(c.problem.rest, c.problem.tets, overlap), Error);
  HandleSets empty = box_handle_sets(c);
  empty.handle_nodes[1].clear();
  EXPECT_THROW(handle_weights(c.problem.rest, c.problem.tets, empty), Error);
}

TEST(Subspace, TruncationKeepsTheLargestInfluencesAndZeroRowsOnAttachedNodes) {
  const auto c = box_case();
  const Eigen::MatrixXd W =
      handle_weights(c.problem.rest, c.problem.tets, box_handle_sets(c), static_cast<int>(c.point_handles.size()));
  BasisOptions options;
  options.max_influences = 2;
  options.drop_below = 0.05;
  const Subspace s = point_handle_subspace(W, testing::attached_flags(c), c.problem.rest, c.point_handles, options);
  EXPECT_EQ(s.num_functions(), static_cast<int>(c.point_handles.size()));
  for (int i = 0; i < s.num_nodes(); ++i) {
    EXPECT_LE(s.basis.row(i).nonZeros(), 2);
    for (SparseRowMatrix::InnerIterator it(s.basis, i); it; ++it) {
      EXPECT_GE(std::abs(it.value()), 0.05);
      EXPECT_EQ(it.value(), W(i, it.col()));
    }
  }
  for (int v : c.attached) EXPECT_EQ(s.basis.row(v).nonZeros(), 0);
  // The handle itself keeps its own weight 1.
  for (std::size_t j = 0; j < c.point_handles.size(); ++j)
    EXPECT_EQ(s.basis.coeff(c.point_handles[j], static_cast<Eigen::Index>(j)), 1.0);
}

TEST(Subspace, AffineHandlesReproduceARigidTranslationAndALinearField) {
  const auto c = box_case();
  const Subspace s = testing::box_subspace(c, true);
  ASSERT_EQ(s.num_functions(), 4 * static_cast<int>(c.point_handles.size()));
  // Every handle translating by t: u = (Σ_j w_j) t, the point weights' share of a translation.
  Eigen::VectorXd q = Eigen::VectorXd::Zero(s.num_dofs());
  for (std::size_t j = 0; j < c.point_handles.size(); ++j)
    q.segment<3>(3 * 4 * static_cast<Eigen::Index>(j)) = Eigen::Vector3d(0.01, 0, 0);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * c.problem.num_nodes());
  s.add_displacement(q, x);
  for (int v : c.point_handles) EXPECT_NEAR(x[3 * v], 0.01, 1e-15);
  for (int v : c.attached) EXPECT_EQ(x.segment<3>(3 * v).norm(), 0.0);
}

}  // namespace
}  // namespace sflsh::reduced
