// Local functions for contact (local_basis.hpp) and their exact energy (local_elastic.hpp) on the box: one function
// per free node near the given ones (or bumps at a spacing), none on attached nodes; the patch's gradient and Hessian
// match finite differences; the patch plus an exact cubature of the other tets is the full-space energy.
#include "term_fixtures.hpp"

#include <sflsh/model/problem.hpp>
#include <sflsh/reduced/local_basis.hpp>
#include <sflsh/reduced/local_elastic.hpp>
#include <sflsh/reduced/newton_factor.hpp>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

namespace sflsh::reduced {
namespace {

using namespace testing_terms;

/// Free nodes on the top face (largest z) of the box, where an object would press.
std::vector<int> top_nodes(const model::Problem& p, int count) {
  const double top = p.rest.col(2).maxCoeff();
  std::vector<int> nodes;
  for (int i = 0; i < p.num_nodes() && static_cast<int>(nodes.size()) < count; ++i)
    if (p.rest(i, 2) > top - 1e-9) nodes.push_back(i);
  return nodes;
}

TEST_F(ReducedTermsFixture, LocalBasisGivesTheFreeNodesNearTheReachedOnesAFunctionEach) {
  const model::Problem& p = box.problem;
  LocalBasisOptions options;  // spacing 0: one function per node
  options.depth = 0.025;
  const std::vector<int> reached = top_nodes(p, 3);
  const LocalBasis local = local_basis(p, reached, options);
  ASSERT_GT(local.size(), static_cast<int>(reached.size()));  // the neighbours within 2.5 cm too
  const std::set<int> attached(box.attached.begin(), box.attached.end());
  std::set<int> free_nodes;
  for (int k = 0; k < local.size(); ++k) {
    const int node = local.centres[static_cast<std::size_t>(k)];
    EXPECT_EQ(attached.count(node), 0u);
    EXPECT_EQ(Eigen::VectorXd(local.functions.col(k)).cwiseAbs().sum(), 1.0);  // one entry, 1
    EXPECT_EQ(local.functions.coeff(node, k), 1.0);
    free_nodes.insert(node);
  }
  for (int r : reached) EXPECT_EQ(free_nodes.count(r), 1u);
  // Exactly the tets with a local node are integrated exactly.
  const std::set<int> tets(local.tets.begin(), local.tets.end());
  for (int e = 0; e < p.num_tets(); ++e) {
    bool touched = false;
    for (int a = 0; a < 4; ++a) touched = touched || free_nodes.count(p.tets(e, a)) > 0;
    EXPECT_EQ(tets.count(e), touched ? 1u : 0u) << "tet " << e;
  }
  // The enriched subspace: the handles' columns first, unchanged.
  const Subspace enriched = local_subspace(subspace, local);
  ASSERT_EQ(enriched.num_functions(), subspace.num_functions() + local.size());
  EXPECT_EQ((Eigen::MatrixXd(enriched.basis).leftCols(subspace.num_functions()) - Eigen::MatrixXd(subspace.basis))
                .cwiseAbs()
                .maxCoeff(),
            0.0);
  // Nothing reached (or only attached nodes): no function.
  EXPECT_EQ(local_basis(p, {}, options).size(), 0);
  EXPECT_EQ(local_basis(p, box.attached, options).size(), 0);
}

TEST_F(ReducedTermsFixture, LocalBumpsAreOneAtTheirCentresAndVanishOnAttachedNodes) {
  const model::Problem& p = box.problem;
  LocalBasisOptions options;
  options.spacing = 0.03;
  options.depth = 0.03;
  const LocalBasis local = local_basis(p, top_nodes(p, 5), options);
  ASSERT_GE(local.size(), 2);
  const Eigen::MatrixXd phi(local.functions);
  for (int k = 0; k < local.size(); ++k) {
    EXPECT_DOUBLE_EQ(phi(local.centres[static_cast<std::size_t>(k)], k), 1.0);
    EXPECT_LE(phi.col(k).maxCoeff(), 1.0);
    EXPECT_GE(phi.col(k).minCoeff(), 0.0);
    for (int a : box.attached) EXPECT_EQ(phi(a, k), 0.0);
    // Compact support: nothing farther than ρ (straight-line distance ≤ path length).
    for (int i = 0; i < p.num_nodes(); ++i) {
      if (phi(i, k) > 0.0) {
        EXPECT_LT((p.rest.row(i) - p.rest.row(local.centres[static_cast<std::size_t>(k)])).norm(), local.radius);
      }
    }
  }
}

TEST_F(ReducedTermsFixture, LocalPatchEnergyMatchesFiniteDifferences) {
  const model::Problem& p = box.problem;
  LocalBasisOptions options;
  options.depth = 0.03;
  const LocalBasis local = local_basis(p, top_nodes(p, 4), options);
  const Subspace enriched = local_subspace(subspace, local);
  LocalElasticTerm term(p, enriched, local);
  term.set_prescribed_state(x_prescribed);
  unsigned seed = 11;
  for (double amplitude : kAmplitudes) {
    SCOPED_TRACE(amplitude);
    const Eigen::VectorXd x = testing::random_q(enriched.num_dofs(), amplitude, seed++);
    check_derivatives(term, x);
    // Projected: positive semi-definite.
    term.set_projection(material::HessianProjection::kStressDerivative);
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(x.size(), x.size());
    term.add_hessian(x, H);
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H).eigenvalues().minCoeff(),
              -1e-9 * H.cwiseAbs().maxCoeff());
    term.set_projection(material::HessianProjection::kNone);
  }
}

TEST_F(ReducedTermsFixture, PatchAndCubatureOutsideItSumToTheFullSpaceEnergyWhenBothAreExact) {
  // The patch's tets exactly, every other tet with ω = 1: the full-space energy at any x in [B  Φ].
  const model::Problem& p = box.problem;
  LocalBasisOptions options;
  options.depth = 0.03;
  const LocalBasis local = local_basis(p, top_nodes(p, 4), options);
  const Subspace enriched = local_subspace(subspace, local);
  std::vector<char> in_patch(static_cast<std::size_t>(p.num_tets()), 0);
  for (int e : local.tets) in_patch[static_cast<std::size_t>(e)] = 1;
  Cubature outside;
  for (int e = 0; e < p.num_tets(); ++e)
    if (!in_patch[static_cast<std::size_t>(e)]) {
      outside.tets.push_back(e);
      outside.weights.push_back(1.0);
    }
  ASSERT_FALSE(outside.tets.empty());
  CubatureElastic handles(p, subspace, outside);  // outside the patch no node is local: the handles alone
  handles.set_prescribed_state(x_prescribed);
  LocalElasticTerm term(p, enriched, local);
  term.set_prescribed_state(x_prescribed);
  const Eigen::VectorXd x = testing::random_q(enriched.num_dofs(), 2e-3, 5);
  Eigen::VectorXd positions = x_prescribed;
  enriched.add_displacement(x, positions);
  const double full = model::evaluate_elastic(p, positions, false).energy;
  const double reduced = handles.energy(Eigen::VectorXd(x.head(subspace.num_dofs()))) + term.energy(x);
  EXPECT_NEAR(reduced, full, 1e-10 * std::abs(full));
}

TEST(NewtonFactor, SchurComplementOnAPatchSolvesLikeTheDenseCholesky) {
  // A positive definite H: dense "other" coordinates around a sparse, banded patch block in the middle.
  const Eigen::Index n = 40, begin = 12, size = 21;
  Eigen::MatrixXd a = testing::random_q(static_cast<int>(n * n), 1.0, 3).reshaped(n, n);
  Eigen::MatrixXd h = a * a.transpose() + n * Eigen::MatrixXd::Identity(n, n);
  for (Eigen::Index i = 0; i < size; ++i)
    for (Eigen::Index j = 0; j < size; ++j)
      if (std::abs(i - j) > 3) h(begin + i, begin + j) = 0.0;                            // the mesh's non-neighbours
  h.block(begin, begin, size, size) += 4.0 * n * Eigen::MatrixXd::Identity(size, size);  // keeps it definite
  const Eigen::VectorXd r = testing::random_q(static_cast<int>(n), 1.0, 4);
  NewtonFactor dense, schur;
  ASSERT_TRUE(dense.compute(h));
  ASSERT_TRUE(schur.compute(h, begin, size));
  const Eigen::VectorXd x = dense.solve(r), y = schur.solve(r);
  EXPECT_LE((x - y).cwiseAbs().maxCoeff(), 1e-12 * x.cwiseAbs().maxCoeff());
  EXPECT_LE((h * y - r).cwiseAbs().maxCoeff(), 1e-10 * r.cwiseAbs().maxCoeff());
  // Not definite: refused either way.
  h(0, 0) = -1e6;
  EXPECT_FALSE(dense.compute(h));
  EXPECT_FALSE(schur.compute(h, begin, size));
}

}  // namespace
}  // namespace sflsh::reduced
