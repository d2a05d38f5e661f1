// Sums over tets do not depend on the thread count (model/src/deterministic_reduce.hpp, docs/decisions.md
// "Deterministic sums"): the elastic term's value and gradient and evaluate_elastic are bit for bit the same on
// 1, 2 and 4 threads, run after run. Thread-local accumulators failed this: their partial sums follow the
// scheduling, and a one-ulp difference in the ground truth grew into different fits per MPI layout.
#include "model_fixtures.hpp"

#include <sflsh/model/terms.hpp>

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <random>

namespace sflsh::model {
namespace {

struct Sums {
  double value = 0.0;
  Eigen::VectorXd gradient;
  double evaluated_energy = 0.0;
  Eigen::VectorXd evaluated_gradient;
};

TEST(DeterministicSums, ElasticSumsAreTheSameOnAnyThreadCount) {
  // 12³ cells, 10 368 tets: a few hundred tets per block, so several threads get work.
  Problem problem =
      testing::box_problem({0.24, 0.24, 0.24}, {12, 12, 12}, 1000.0, MassKind::lumped, testing::box_material(5e3, 2e3));
  problem.validate();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(problem.rest.data(), problem.num_dofs());
  for (Eigen::Index k = 0; k < x.size(); ++k) x[k] += 2e-3 * u(rng);  // 10 % strain on 2 cm cells: Fung acts
  const ElasticTerm term(problem, TermSubset::whole(problem));
  auto sums_on = [&](int threads) {
    Sums s;
    tbb::task_arena arena(threads);
    arena.execute([&] {
      s.value = term.value(x);
      s.gradient = Eigen::VectorXd::Zero(x.size());
      EXPECT_TRUE(term.add_gradient(x, s.gradient));
      const ElasticEvaluation e = evaluate_elastic(problem, x, true);
      s.evaluated_energy = e.energy;
      s.evaluated_gradient = e.gradient;
    });
    return s;
  };
  const Sums one = sums_on(1);
  ASSERT_GT(one.value, 0.0);
  // The two code paths sum the same tets in different groupings: equal to rounding, not bit for bit.
  EXPECT_NEAR(one.evaluated_energy, one.value, 1e-12 * one.value);
  for (int threads : {2, 4, 2, 4}) {
    const Sums other = sums_on(threads);
    EXPECT_EQ(other.value, one.value) << threads << " threads";
    EXPECT_EQ(other.evaluated_energy, one.evaluated_energy) << threads << " threads";
    EXPECT_TRUE((other.gradient.array() == one.gradient.array()).all()) << threads << " threads";
    EXPECT_TRUE((other.evaluated_gradient.array() == one.evaluated_gradient.array()).all()) << threads << " threads";
  }
}

}  // namespace
}  // namespace sflsh::model
