// One finite-difference harness over every term of the incremental potential (model/terms.hpp): value,
// gradient and Hessian against central differences at several amplitudes, on a small box under random node
// maps, for the elastic (exact; projected: PSD), inertia (lumped, consistent), gravity and node-potential terms.
#include "model_fixtures.hpp"

#include <sflsh/model/terms.hpp>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <memory>
#include <random>

namespace sflsh::model {
namespace {

using testing::DenseHessian;

/// A smooth penalty below the plane y = level on every node: u = k/3 (level − p_y)³ where p_y < level.
class CubicFloor final : public NodePotential {
 public:
  CubicFloor(int nodes, double level, double stiffness) : level_(level), k_(stiffness) {
    for (int i = 0; i < nodes; ++i) nodes_.push_back(i);
  }
  const std::vector<int>& nodes() const override { return nodes_; }
  bool begin_substep(double, double, const RowMatrixX3d&, const RowMatrixX3d&) override { return true; }
  const std::vector<int>& candidates() const override { return nodes_; }
  double evaluate(int, const Eigen::Vector3d& p, Eigen::Vector3d* gradient, Eigen::Matrix3d* hessian) const override {
    const double depth = std::max(0.0, level_ - p.y());
    if (gradient) *gradient = -k_ * depth * depth * Eigen::Vector3d::UnitY();
    if (hessian) *hessian = 2.0 * k_ * depth * Eigen::Vector3d::UnitY() * Eigen::Vector3d::UnitY().transpose();
    return k_ / 3.0 * depth * depth * depth;
  }
  bool accept_substep(const RowMatrixX3d&) override { return true; }

 private:
  std::vector<int> nodes_;
  double level_, k_;
};

/// Gradient and Hessian of `term` at x against central differences of its value and gradient. The step is 1e-7
/// of the 0.1 m box: truncation (h²|f'''|/6) and rounding (ε|f|/h) are both ≲ 1e-8 relative here, so 1e-6
/// separates a correct derivative from a wrong one (a missing factor or block shows as O(1)).
void check_derivatives(const Term& term, const Problem& problem, const Eigen::VectorXd& x, bool exact_hessian = true) {
  const Eigen::Index n = x.size();
  constexpr double h = 1e-7;
  constexpr double kTolerance = 1e-6;
  Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
  ASSERT_TRUE(term.add_gradient(x, g)) << term.name();
  Eigen::VectorXd g_fd(n);
  Eigen::MatrixXd H_fd(n, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    Eigen::VectorXd xp = x, xm = x;
    xp[k] += h;
    xm[k] -= h;
    g_fd[k] = (term.value(xp) - term.value(xm)) / (2.0 * h);
    Eigen::VectorXd gp = Eigen::VectorXd::Zero(n), gm = Eigen::VectorXd::Zero(n);
    term.add_gradient(xp, gp);
    term.add_gradient(xm, gm);
    H_fd.col(k) = (gp - gm) / (2.0 * h);
  }
  const double g_scale = std::max(g.cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LE((g - g_fd).cwiseAbs().maxCoeff() / g_scale, kTolerance) << term.name() << ": gradient";
  DenseHessian sink(problem);
  ASSERT_TRUE(term.add_hessian(x, sink)) << term.name();
  if (exact_hessian) {
    const double H_scale = std::max(H_fd.cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LE((sink.H - H_fd).cwiseAbs().maxCoeff() / H_scale, kTolerance) << term.name() << ": Hessian";
  }
  EXPECT_LE((sink.H - sink.H.transpose()).cwiseAbs().maxCoeff(), 1e-12 * std::max(1.0, sink.H.cwiseAbs().maxCoeff()))
      << term.name() << ": Hessian not symmetric";
}

struct TermsFixture : ::testing::Test {
  std::mt19937 rng{1234};
  Problem problem =
      testing::box_problem({0.1, 0.06, 0.04}, {2, 2, 1}, 1000.0, MassKind::lumped, testing::box_material(5e3, 2e3));
  void SetUp() override { problem.validate(); }

  Eigen::VectorXd rest() const { return Eigen::Map<const Eigen::VectorXd>(problem.rest.data(), problem.num_dofs()); }
  /// Rest plus a random displacement of the given amplitude [m].
  Eigen::VectorXd perturbed(double amplitude) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::VectorXd x = rest();
    for (Eigen::Index k = 0; k < x.size(); ++k) x[k] += amplitude * u(rng);
    return x;
  }
};

// The amplitudes: 0.1 mm (linear regime), 1 mm, 4 mm (10 % strain on 0.04 m cells, where the Fung factor bites).
constexpr double kAmplitudes[] = {1e-4, 1e-3, 4e-3};

TEST_F(TermsFixture, ElasticExactHessianMatchesFiniteDifferences) {
  ElasticTerm term(problem, TermSubset::whole(problem));
  for (double amplitude : kAmplitudes) check_derivatives(term, problem, perturbed(amplitude));
}

TEST_F(TermsFixture, ElasticProjectedHessianIsPositiveSemiDefinite) {
  ElasticTerm term(problem, TermSubset::whole(problem));
  term.set_projection(material::HessianProjection::kStressDerivative);
  for (double amplitude : kAmplitudes) {
    const Eigen::VectorXd x = perturbed(4.0 * amplitude);
    check_derivatives(term, problem, x, false);
    DenseHessian sink(problem);
    ASSERT_TRUE(term.add_hessian(x, sink));
    const Eigen::VectorXd eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(sink.H).eigenvalues();
    EXPECT_GE(eigenvalues.minCoeff(), -1e-9 * eigenvalues.cwiseAbs().maxCoeff());
  }
}

TEST_F(TermsFixture, ElasticValueOfASubsetIsThePartialSum) {
  auto first = std::make_shared<TermSubset>(), second = std::make_shared<TermSubset>();
  for (int e = 0; e < problem.num_tets(); ++e) (e % 3 == 0 ? first : second)->value_tets.push_back(e);
  const Eigen::VectorXd x = perturbed(1e-3);
  const double whole = ElasticTerm(problem, TermSubset::whole(problem)).value(x);
  EXPECT_NEAR(ElasticTerm(problem, first).value(x) + ElasticTerm(problem, second).value(x), whole, 1e-12 * whole);
}

TEST_F(TermsFixture, InertiaLumpedAndConsistentMatchFiniteDifferences) {
  const NodeFrame frame = testing::random_frame(problem.num_nodes(), rng);
  for (MassKind kind : {MassKind::lumped, MassKind::consistent}) {
    problem.mass_kind = kind;
    problem.validate();
    InertiaTerm term(problem, TermSubset::whole(problem));
    InertiaTarget target;
    target.h = 1.0 / 60.0;
    target.h_eff = target.h / 2.0;
    target.p_tilde = posed_positions(frame, perturbed(1e-2)).reshaped<Eigen::RowMajor>();
    term.set_step(frame, target);
    for (double amplitude : kAmplitudes) check_derivatives(term, problem, perturbed(amplitude));
  }
}

TEST_F(TermsFixture, InertiaOfATranslationIsTheTotalMassForBothKinds) {
  // A rigid offset r of every node from p̃: ½ Σ_ij M_ij r·r / ĥ² = ½ m_total |r|² / ĥ² (the row sums are the lumped
  // masses).
  NodeFrame identity;
  identity.A.assign(static_cast<std::size_t>(problem.num_nodes()), Eigen::Matrix3d::Identity());
  identity.d = RowMatrixX3d::Zero(problem.num_nodes(), 3);
  const Eigen::Vector3d r(0.01, -0.02, 0.005);
  InertiaTarget target;
  target.h = target.h_eff = 0.01;
  target.p_tilde = rest();
  for (int i = 0; i < problem.num_nodes(); ++i) target.p_tilde.segment<3>(3 * i) -= r;
  const double total = 1000.0 * 0.1 * 0.06 * 0.04;
  for (MassKind kind : {MassKind::lumped, MassKind::consistent}) {
    problem.mass_kind = kind;
    InertiaTerm term(problem, TermSubset::whole(problem));
    term.set_step(identity, target);
    EXPECT_NEAR(term.value(rest()), 0.5 * total * r.squaredNorm() / (target.h_eff * target.h_eff), 1e-10)
        << to_string(kind);
  }
}

TEST_F(TermsFixture, GravityMatchesFiniteDifferences) {
  problem.gravity = Eigen::Vector3d(0.0, -9.81, 0.0);
  const NodeFrame frame = testing::random_frame(problem.num_nodes(), rng);
  GravityTerm term(problem, TermSubset::whole(problem));
  term.set_frame(frame);
  for (double amplitude : kAmplitudes) check_derivatives(term, problem, perturbed(amplitude));
}

TEST_F(TermsFixture, NodePotentialMatchesFiniteDifferences) {
  const NodeFrame frame = testing::random_frame(problem.num_nodes(), rng);
  problem.potentials.push_back(
      std::make_shared<CubicFloor>(problem.num_nodes(), 1.0, 1e6));  // every node below y = 1 m
  PotentialTerm term(problem);
  const RowMatrixX3d p_n = posed_positions(frame, rest());
  ASSERT_TRUE(term.begin(p_n, 0.0, 0.01, frame, rest(), nullptr));
  for (double amplitude : kAmplitudes) check_derivatives(term, problem, perturbed(amplitude));
}

TEST_F(TermsFixture, OutOfRangeStatesAreInfiniteNotNaN) {
  ElasticTerm term(problem, TermSubset::whole(problem));
  Eigen::VectorXd x = rest();
  x *= 3.0;  // 200 % stretch: the Fung exponent exceeds its cap
  EXPECT_EQ(term.value(x), std::numeric_limits<double>::infinity());
  Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
  EXPECT_FALSE(term.add_gradient(x, g));
}

}  // namespace
}  // namespace sflsh::model
