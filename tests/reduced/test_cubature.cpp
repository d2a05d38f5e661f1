// Cubature: every tet with ω = 1 is exact integration; NNLS; farthest-point sampling; the data-oblivious fit.
#include "reduced_fixtures.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/reduced/cubature.hpp>
#include <sflsh/reduced/cubature_elastic.hpp>
#include <sflsh/reduced/nnls.hpp>

#include <gtest/gtest.h>

#include <random>
#include <set>

namespace sflsh::reduced {
namespace {

using testing::random_q;

TEST(Cubature, EveryTetEqualsExactIntegration) {
  const auto c = testing::box_case();
  const Subspace s = testing::box_subspace(c);
  const Cubature all = exact_cubature(c.problem.num_tets());
  const CubatureElastic elastic(c.problem, s, all);
  const Eigen::VectorXd q = random_q(s.num_dofs(), 0.004, 3);
  Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(c.problem.rest.data(), c.problem.num_dofs());
  s.add_displacement(q, x);
  const model::ElasticEvaluation full = model::evaluate_elastic(c.problem, x);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(s.num_dofs());
  const double e = elastic.add_gradient(q, g);
  // Same sums in a different order: round-off.
  EXPECT_NEAR(e, full.energy, 1e-12 * std::abs(full.energy));
  EXPECT_LT((g - s.project_gradient(full.gradient)).cwiseAbs().maxCoeff(), 1e-11 * full.gradient.cwiseAbs().maxCoeff());
  EXPECT_NEAR(elastic.energy(q), full.energy, 1e-12 * std::abs(full.energy));
}

TEST(Nnls, RecoversANonNegativeSolutionWithZeros) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd A(40, 12);
  for (Eigen::Index i = 0; i < A.size(); ++i) A.data()[i] = u(rng);
  Eigen::VectorXd x_true(12);
  for (int k = 0; k < 12; ++k) x_true[k] = k % 3 == 0 ? 0.0 : 0.5 + 0.1 * k;
  const Eigen::VectorXd b = A * x_true;
  const NnlsResult r = nnls_normal_equations(A.transpose() * A, A.transpose() * b);
  EXPECT_TRUE(r.converged);
  EXPECT_LT((r.x - x_true).cwiseAbs().maxCoeff(), 1e-9);
  // A target outside the cone: the solution is feasible and satisfies the KKT conditions.
  const Eigen::VectorXd b2 = -A.col(0) + 0.1 * A.col(1);
  const NnlsResult r2 = nnls_normal_equations(A.transpose() * A, A.transpose() * b2);
  EXPECT_TRUE(r2.converged);
  EXPECT_GE(r2.x.minCoeff(), 0.0);
  const Eigen::VectorXd dual = A.transpose() * (b2 - A * r2.x);
  for (int k = 0; k < 12; ++k) {
    if (r2.x[k] > 0) {
      EXPECT_NEAR(dual[k], 0.0, 1e-9);
    } else {
      EXPECT_LE(dual[k], 1e-9);
    }
  }
}

TEST(Cubature, FarthestPointTetsAreDistinctDeterministicAndNested) {
  const auto c = testing::box_case();
  const std::vector<int> a = farthest_point_tets(c.problem, 20, {});
  const std::vector<int> b = farthest_point_tets(c.problem, 20, {});
  EXPECT_EQ(a, b);
  EXPECT_EQ(std::set<int>(a.begin(), a.end()).size(), a.size());
  const std::vector<int> small = farthest_point_tets(c.problem, 8, {});
  EXPECT_TRUE(std::equal(small.begin(), small.end(), a.begin()));
  EXPECT_THROW(farthest_point_tets(c.problem, c.problem.num_tets() + 1, {}), Error);
}

TEST(Cubature, VoronoiWeightsIntegrateTheVolume) {
  const auto c = testing::box_case();
  const std::vector<int> tets = farthest_point_tets(c.problem, 15, {});
  const std::vector<double> w = voronoi_weights(c.problem, tets);
  double volume = 0.0, cubature = 0.0;
  for (const auto& r : c.problem.tet_rest) volume += r.volume;
  for (std::size_t k = 0; k < tets.size(); ++k)
    cubature += w[k] * c.problem.tet_rest[static_cast<std::size_t>(tets[k])].volume;
  EXPECT_NEAR(cubature, volume, 1e-12 * volume);
}

TEST(Cubature, DataObliviousFitReproducesForcesAtNewRandomDisplacements) {
  const auto c = testing::box_case({6, 5, 3});
  const Subspace s = testing::box_subspace(c);
  CubatureOptions options;
  options.count = 40;
  const Cubature fit = select_cubature(c.problem, s, options);
  ASSERT_EQ(fit.method, "nnls");
  options.weighting = CubatureWeighting::voronoi;
  const Cubature voronoi = select_cubature(c.problem, s, options);
  const CubatureElastic exact(c.problem, s, exact_cubature(c.problem.num_tets()));
  const CubatureElastic fitted(c.problem, s, fit), cells(c.problem, s, voronoi);
  // Fresh samples (another seed than the fit's), of the amplitudes the fit saw.
  double fit_error = 0.0, voronoi_error = 0.0;
  for (unsigned seed = 100; seed < 106; ++seed) {
    const Eigen::VectorXd q = random_q(s.num_dofs(), 0.004, seed);
    Eigen::VectorXd ge = Eigen::VectorXd::Zero(s.num_dofs()), gf = ge, gv = ge;
    exact.add_gradient(q, ge);
    fitted.add_gradient(q, gf);
    cells.add_gradient(q, gv);
    fit_error = std::max(fit_error, (gf - ge).norm() / ge.norm());
    voronoi_error = std::max(voronoi_error, (gv - ge).norm() / ge.norm());
  }
  // 40 of 450 tets: the fitted weights reproduce unseen forces to well within 30% and beat the Voronoi cells.
  EXPECT_LT(fit_error, 0.3);
  EXPECT_LT(fit_error, voronoi_error);
}

}  // namespace
}  // namespace sflsh::reduced
