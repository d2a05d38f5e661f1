// One finite-difference harness over every term of the reduced incremental potential (reduced_terms.hpp): value,
// gradient and Hessian in q against central differences at several amplitudes, on the box under swinging node maps,
// for the cubature elasticity (exact; projected: PSD), the inertia (lumped, consistent), gravity and a node
// potential; the tracking root's terms (root inertia, tracking spring and damper, node potential at the deviated
// positions) on x = [q; θ; τ] and the rotation vector's derivatives; the inertia and gravity values against their
// node-by-node definitions; and the consistent joint-pair
// precompute and cross-time mass of a skinned body layer against node-by-node sums.
#include "integrator_fixtures.hpp"
#include "reduced_fixtures.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/reduced/coupled_term.hpp>
#include <sflsh/reduced/reduced_history.hpp>
#include <sflsh/reduced/reduced_model.hpp>
#include <sflsh/reduced/reduced_terms.hpp>
#include <sflsh/reduced/root_tracking.hpp>
#include <sflsh/reduced/rotation_vector.hpp>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <memory>
#include <random>

namespace sflsh::reduced {
namespace {

/// Gradient and Hessian of `term` at q against central differences of its value and gradient. The step is 1e-7 m
/// against coordinates of up to 1e-2 m on a 0.1 m box: truncation (h²|f'''|/6) and rounding (ε|f|/h) are both
/// ≲ 1e-8 relative here, so 1e-6 separates a correct derivative from a wrong one (a missing factor, block or
/// neighbour shows as O(1)).
void check_derivatives(const ReducedTerm& term, const Eigen::VectorXd& q, bool exact_hessian = true) {
  const Eigen::Index n = q.size();
  constexpr double h = 1e-7;
  constexpr double kTolerance = 1e-6;
  Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
  term.add_gradient(q, g);
  Eigen::VectorXd g_fd(n);
  Eigen::MatrixXd H_fd(n, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    Eigen::VectorXd qp = q, qm = q;
    qp[k] += h;
    qm[k] -= h;
    g_fd[k] = (term.value(qp) - term.value(qm)) / (2.0 * h);
    Eigen::VectorXd gp = Eigen::VectorXd::Zero(n), gm = Eigen::VectorXd::Zero(n);
    term.add_gradient(qp, gp);
    term.add_gradient(qm, gm);
    H_fd.col(k) = (gp - gm) / (2.0 * h);
  }
  const double g_scale = std::max(g.cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LE((g - g_fd).cwiseAbs().maxCoeff() / g_scale, kTolerance) << term.name() << ": gradient";
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  term.add_hessian(q, H);
  if (exact_hessian) {
    const double H_scale = std::max(H_fd.cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LE((H - H_fd).cwiseAbs().maxCoeff() / H_scale, kTolerance) << term.name() << ": Hessian";
  }
  EXPECT_LE((H - H.transpose()).cwiseAbs().maxCoeff(), 1e-12 * std::max(1.0, H.cwiseAbs().maxCoeff()))
      << term.name() << ": Hessian not symmetric";
}

/// A smooth penalty below the plane z = level on every listed node: u = k/3 (level − p_z)³ where p_z < level.
class CubicFloor final : public model::NodePotential {
 public:
  CubicFloor(std::vector<int> nodes, double level, double stiffness)
      : nodes_(std::move(nodes)), level_(level), k_(stiffness) {
    for (std::size_t c = 0; c < nodes_.size(); ++c) candidates_.push_back(static_cast<int>(c));
  }
  const std::vector<int>& nodes() const override { return nodes_; }
  bool begin_substep(double, double, const meshing::RowMatrixX3d&, const meshing::RowMatrixX3d&) override {
    return true;
  }
  const std::vector<int>& candidates() const override { return candidates_; }
  double evaluate(int, const Eigen::Vector3d& p, Eigen::Vector3d* gradient, Eigen::Matrix3d* hessian) const override {
    const double depth = std::max(0.0, level_ - p.z());
    if (gradient) *gradient = -k_ * depth * depth * Eigen::Vector3d::UnitZ();
    if (hessian) *hessian = 2.0 * k_ * depth * Eigen::Vector3d::UnitZ() * Eigen::Vector3d::UnitZ().transpose();
    return k_ / 3.0 * depth * depth * depth;
  }
  bool accept_substep(const meshing::RowMatrixX3d&) override { return true; }

 private:
  std::vector<int> nodes_, candidates_;
  double level_, k_;
};

// 0.1 mm (linear regime), 1 mm, 4 mm (several % strain on 2 cm cells, where the Fung factor bites).
constexpr double kAmplitudes[] = {1e-4, 1e-3, 4e-3};

struct ReducedTermsFixture : ::testing::Test {
  testing::BoxCase box = testing::box_case({4, 4, 3});
  Subspace subspace;
  Cubature cubature;
  Eigen::VectorXd x_prescribed;
  const double t = 0.13;

  void SetUp() override {
    model::Problem& p = box.problem;
    p.gravity = Eigen::Vector3d(0.3, -1.0, -9.81);
    p.trajectory = std::make_shared<testing::SwingTrajectory>(p.num_nodes(), Eigen::Vector3d(0.06, 0.05, 0.0),
                                                              Eigen::Vector3d(1.0, 0.3, 0.2), 0.5, 2.0,
                                                              Eigen::Vector3d(0.01, -0.02, 0.015), 5.0);
    p.validate();
    subspace = testing::box_subspace(box, true);  // affine handles: signed basis entries
    // Every third tet with uneven weights (the cubature's ω enters as a factor per point).
    for (int e = 0; e < p.num_tets(); e += 3) {
      cubature.tets.push_back(e);
      cubature.weights.push_back(1.0 + 0.37 * (e % 7));
    }
    cubature.method = "test";
    x_prescribed = Eigen::Map<const Eigen::VectorXd>(p.rest.data(), p.num_dofs());
  }
  Eigen::VectorXd q(double amplitude, unsigned seed) const {
    return testing::random_q(subspace.num_dofs(), amplitude, seed);
  }
};

TEST_F(ReducedTermsFixture, ElasticExactHessianMatchesFiniteDifferences) {
  const CubatureElastic elastic(box.problem, subspace, cubature);
  ReducedElasticTerm term(elastic);
  unsigned seed = 1;
  for (double amplitude : kAmplitudes) check_derivatives(term, q(amplitude, seed++));
}

TEST_F(ReducedTermsFixture, ElasticProjectedHessianIsPositiveSemiDefinite) {
  const CubatureElastic elastic(box.problem, subspace, cubature);
  ReducedElasticTerm term(elastic);
  term.set_projection(material::HessianProjection::kStressDerivative);
  unsigned seed = 11;
  for (double amplitude : kAmplitudes) {
    const Eigen::VectorXd at = q(2.0 * amplitude, seed++);
    check_derivatives(term, at, false);
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(at.size(), at.size());
    term.add_hessian(at, H);
    const Eigen::VectorXd eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H).eigenvalues();
    EXPECT_GE(eigenvalues.minCoeff(), -1e-9 * eigenvalues.cwiseAbs().maxCoeff());
  }
}

TEST_F(ReducedTermsFixture, ElasticValueIsInfiniteOutOfRange) {
  const CubatureElastic elastic(box.problem, subspace, cubature);
  ReducedElasticTerm term(elastic);
  EXPECT_EQ(term.value(q(1.0, 5)), std::numeric_limits<double>::infinity());  // metre-sized handle moves on a 0.1 m box
  Eigen::VectorXd g = Eigen::VectorXd::Zero(subspace.num_dofs());
  EXPECT_THROW(term.add_gradient(q(1.0, 5), g), Error);
}

TEST_F(ReducedTermsFixture, InertiaLumpedAndConsistentMatchFiniteDifferencesAndTheDefinition) {
  for (model::MassKind kind : {model::MassKind::lumped, model::MassKind::consistent}) {
    box.problem.mass_kind = kind;
    box.problem.validate();
    const model::Problem& p = box.problem;
    ReducedInertia inertia(p, subspace);
    inertia.set_time(t, x_prescribed);
    if (kind == model::MassKind::consistent) {
      EXPECT_GT(inertia.inertia_nodes().size(), inertia.active_nodes().size());
    }
    // p̃ near the skinned rest shape on every node (a few cm off).
    model::NodeFrame frame;
    p.frame(t, frame);
    const model::RowMatrixX3d skinned = model::posed_positions(frame, x_prescribed);
    const Eigen::VectorXd p_tilde_all =
        Eigen::Map<const Eigen::VectorXd>(skinned.data(), skinned.size()) + testing::random_q(p.num_dofs(), 0.02, 7);
    const double h_eff = 1.0 / 240.0;
    ReducedInertiaTerm term(inertia);
    term.set_step(gather_nodes(p_tilde_all, inertia.inertia_nodes()), h_eff);
    unsigned seed = 21;
    for (double amplitude : kAmplitudes) check_derivatives(term, q(amplitude, seed++));
    // The definition 1/(2ĥ²)(p − p̃)ᵀM(p − p̃) over every node, p = posed x_D + Bq, up to its value at q = 0.
    const Eigen::SparseMatrix<double, Eigen::RowMajor> M = p.mass_matrix();
    const auto definition = [&](const Eigen::VectorXd& coordinates) {
      Eigen::VectorXd x = x_prescribed;
      subspace.add_displacement(coordinates, x);
      const model::RowMatrixX3d posed = model::posed_positions(frame, x);
      const model::RowMatrixX3d r = posed - Eigen::Map<const model::RowMatrixX3d>(p_tilde_all.data(), p.num_nodes(), 3);
      return 0.5 / (h_eff * h_eff) * (r.transpose() * (M * r)).trace();
    };
    const Eigen::VectorXd at = q(1e-2, 31), zero = Eigen::VectorXd::Zero(at.size());
    const double expected = definition(at) - definition(zero), closed = term.value(at) - term.value(zero);
    // Exactly quadratic: the two differ by the round-off of sums over ~100 nodes of terms ~|M r²|/ĥ².
    EXPECT_NEAR(closed, expected, 1e-10 * std::abs(expected)) << model::to_string(kind);
  }
}

TEST_F(ReducedTermsFixture, GravityMatchesFiniteDifferencesAndTheDefinition) {
  const model::Problem& p = box.problem;
  ReducedInertia inertia(p, subspace);
  inertia.set_time(t, x_prescribed);
  ReducedGravityTerm term(inertia);
  term.update();
  unsigned seed = 41;
  for (double amplitude : kAmplitudes) check_derivatives(term, q(amplitude, seed++));
  model::NodeFrame frame;
  p.frame(t, frame);
  const auto definition = [&](const Eigen::VectorXd& coordinates) {  // −Σ_i m_i gᵀp_i
    Eigen::VectorXd x = x_prescribed;
    subspace.add_displacement(coordinates, x);
    const model::RowMatrixX3d posed = model::posed_positions(frame, x);
    double value = 0.0;
    for (int i = 0; i < p.num_nodes(); ++i) value -= p.mass[i] * p.gravity.dot(posed.row(i).transpose());
    return value;
  };
  const Eigen::VectorXd at = q(1e-2, 51), zero = Eigen::VectorXd::Zero(at.size());
  EXPECT_NEAR(term.value(at), definition(at) - definition(zero), 1e-12 * std::abs(definition(zero)));
}

TEST_F(ReducedTermsFixture, NodePotentialMatchesFiniteDifferences) {
  model::Problem& p = box.problem;
  const std::vector<int> active = subspace.active_nodes();
  p.potentials.push_back(std::make_shared<CubicFloor>(active, 0.5, 1e6));  // every moving node below z = 0.5 m
  ReducedInertia inertia(p, subspace);
  ReducedPotentials potentials(p, subspace, inertia.active_nodes());
  inertia.set_time(t, x_prescribed);
  meshing::RowMatrixX3d p_start;
  inertia.posed(Eigen::VectorXd::Zero(subspace.num_dofs()), p_start);
  ASSERT_TRUE(potentials.begin(t - 0.01, 0.01, p_start, inertia));
  ReducedPotentialTerm term(potentials, inertia);
  unsigned seed = 61;
  for (double amplitude : kAmplitudes) check_derivatives(term, q(amplitude, seed++));
}

// ---------------------------------------------------------------------------------------------------------
// The tracking root (root_tracking.hpp): x = [q; θ; τ].

/// R(θ)'s first and second derivatives against central differences, in the series range (|θ|² < 1e-2) and beyond.
/// Step 1e-6 rad on entries of order 1: truncation and rounding both ≲ 1e-10, so 1e-8 is far below any error in a
/// coefficient (O(1) wrong entries).
TEST(RotationVector, DerivativesMatchFiniteDifferencesAndRIsARotation) {
  const double h = 1e-6;
  for (const Eigen::Vector3d& theta : {Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(0.01, -0.03, 0.02),
                                       Eigen::Vector3d(0.04, 0.05, -0.07), Eigen::Vector3d(0.3, -0.5, 0.9)}) {
    const RotationVectorDerivatives d = rotation_vector_derivatives(theta);
    EXPECT_LE((d.R * d.R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_NEAR(d.R.determinant(), 1.0, 1e-14);
    EXPECT_LE((d.R - rotation_of_vector(theta)).cwiseAbs().maxCoeff(), 1e-15);
    if (theta.norm() > 0.0) {
      const Eigen::Matrix3d expected = Eigen::AngleAxisd(theta.norm(), theta.normalized()).toRotationMatrix();
      EXPECT_LE((d.R - expected).cwiseAbs().maxCoeff(), 1e-14);
    }
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d p = theta, m = theta;
      p[k] += h;
      m[k] -= h;
      const RotationVectorDerivatives dp = rotation_vector_derivatives(p), dm = rotation_vector_derivatives(m);
      EXPECT_LE((d.dR[k] - (dp.R - dm.R) / (2.0 * h)).cwiseAbs().maxCoeff(), 1e-8) << theta.transpose() << " k " << k;
      for (int l = 0; l < 3; ++l)
        EXPECT_LE((d.d2R[l][k] - (dp.dR[l] - dm.dR[l]) / (2.0 * h)).cwiseAbs().maxCoeff(), 1e-8)
            << theta.transpose() << " k " << k << " l " << l;
    }
  }
}

struct RootTermsFixture : ReducedTermsFixture {
  std::vector<int> carried;  ///< the attached nodes: only the root moves them
  std::vector<double> carried_mass;
  meshing::RowMatrixX3d carried_posed;
  Eigen::VectorXd carried_tilde;
  const Eigen::Vector3d pivot{0.06, 0.05, 0.01};
  Eigen::Index offset = 0;

  void SetUp() override {
    ReducedTermsFixture::SetUp();
    const model::Problem& p = box.problem;
    carried = box.attached;
    std::sort(carried.begin(), carried.end());
    model::NodeFrame frame;
    p.frame(t, frame);
    const model::RowMatrixX3d skinned = model::posed_positions(frame, x_prescribed);
    carried_posed.resize(static_cast<Eigen::Index>(carried.size()), 3);
    for (std::size_t k = 0; k < carried.size(); ++k) {
      carried_posed.row(static_cast<Eigen::Index>(k)) = skinned.row(carried[k]);
      carried_mass.push_back(p.mass[carried[k]]);
    }
    carried_tilde = Eigen::Map<const Eigen::VectorXd>(carried_posed.data(), carried_posed.size()) +
                    testing::random_q(static_cast<int>(carried_posed.size()), 0.02, 3);
    offset = subspace.num_dofs();
  }
  /// x = [q; θ; τ] with q of `amplitude` [m], θ up to 10·amplitude [rad] (0.001–0.04 rad), τ of `amplitude`.
  Eigen::VectorXd x(double amplitude, unsigned seed) const {
    Eigen::VectorXd v(offset + 6);
    v << q(amplitude, seed), testing::random_q(3, 10.0 * amplitude, seed + 100),
        testing::random_q(3, amplitude, seed + 200);
    return v;
  }
};

TEST_F(RootTermsFixture, RootInertiaMatchesFiniteDifferencesAndTheInertiaAtZeroDeviation) {
  const model::Problem& p = box.problem;
  ReducedInertia inertia(p, subspace);
  inertia.set_time(t, x_prescribed);
  model::NodeFrame frame;
  p.frame(t, frame);
  const model::RowMatrixX3d skinned = model::posed_positions(frame, x_prescribed);
  const Eigen::VectorXd p_tilde_all =
      Eigen::Map<const Eigen::VectorXd>(skinned.data(), skinned.size()) + testing::random_q(p.num_dofs(), 0.02, 7);
  const Eigen::VectorXd p_tilde = gather_nodes(p_tilde_all, inertia.inertia_nodes());
  const double h_eff = 1.0 / 240.0;
  RootInertiaTerm term(inertia, carried_mass, offset);
  term.set_step(p_tilde, carried_tilde, carried_posed, pivot, h_eff);
  unsigned seed = 71;
  for (double amplitude : kAmplitudes) check_derivatives(term, x(amplitude, seed++));
  // At zero deviation the root term is the soft tissue's inertia (plus the carried nodes' constant).
  ReducedInertiaTerm plain(inertia);
  plain.set_step(p_tilde, h_eff);
  Eigen::VectorXd at = x(1e-2, 81), zero = Eigen::VectorXd::Zero(offset + 6);
  at.tail<6>().setZero();
  const double expected = plain.value(at.head(offset)) - plain.value(zero.head(offset));
  EXPECT_NEAR(term.value(at) - term.value(zero), expected, 1e-9 * std::abs(expected));
  // A rigid deviation of everything that keeps each node's distance to its target leaves the value: a pure
  // translation of the targets by τ with q = 0 gives the value at zero with shifted targets.
  const Eigen::Vector3d shift(0.01, -0.02, 0.005);
  Eigen::VectorXd shifted_tilde = p_tilde, shifted_carried = carried_tilde;
  for (Eigen::Index i = 0; i < shifted_tilde.size() / 3; ++i) shifted_tilde.segment<3>(3 * i) += shift;
  for (Eigen::Index i = 0; i < shifted_carried.size() / 3; ++i) shifted_carried.segment<3>(3 * i) += shift;
  RootInertiaTerm moved(inertia, carried_mass, offset);
  moved.set_step(shifted_tilde, shifted_carried, carried_posed, pivot, h_eff);
  Eigen::VectorXd translated = zero;
  translated.tail<3>() = shift;
  EXPECT_NEAR(moved.value(translated), term.value(zero), 1e-12 * term.value(zero));
}

TEST_F(RootTermsFixture, TrackingSpringAndDamperMatchFiniteDifferences) {
  RootTrackingTerm term(offset);
  Vector6d stiffness, damping, previous;
  stiffness << 30.0, 40.0, 50.0, 600.0, 700.0, 0.0;  // a free horizontal translation has no spring
  damping << 3.0, 4.0, 5.0, 120.0, 130.0, 140.0;
  previous << 0.01, -0.02, 0.0, 0.005, 0.0, -0.01;
  term.set_step(stiffness, damping, previous, 1.0 / 60.0);
  unsigned seed = 91;
  for (double amplitude : kAmplitudes) check_derivatives(term, x(amplitude, seed++));
  Eigen::VectorXd at = Eigen::VectorXd::Zero(offset + 6);
  at.tail<6>() = previous;
  EXPECT_NEAR(term.value(at), 0.5 * previous.cwiseProduct(stiffness).dot(previous), 1e-15);  // no rate: no damping
}

TEST_F(RootTermsFixture, NodePotentialAtTheDeviatedPositionsMatchesFiniteDifferences) {
  model::Problem& p = box.problem;
  const std::vector<int> active = subspace.active_nodes();
  p.potentials.push_back(std::make_shared<CubicFloor>(active, 0.5, 1e6));  // every moving node below z = 0.5 m
  ReducedInertia inertia(p, subspace);
  ReducedPotentials potentials(p, subspace, inertia.active_nodes());
  inertia.set_time(t, x_prescribed);
  meshing::RowMatrixX3d p_start;
  inertia.posed(Eigen::VectorXd::Zero(subspace.num_dofs()), p_start);
  const RootFrame start = root_frame(Eigen::VectorXd::Zero(offset + 6), offset, pivot);
  ASSERT_TRUE(potentials.begin(t - 0.01, 0.01, p_start, inertia, &start));
  RootPotentialTerm term(potentials, inertia, offset);
  term.set_pivot(pivot);
  unsigned seed = 101;
  for (double amplitude : kAmplitudes) check_derivatives(term, x(amplitude, seed++));
  // Without deviation it is the plain potential term (R(p − c) + c = p up to the round-off of ~0.1 m coordinates).
  ReducedPotentialTerm plain(potentials, inertia);
  Eigen::VectorXd at = x(1e-3, 111);
  at.tail<6>().setZero();
  EXPECT_NEAR(term.value(at), plain.value(at.head(offset)), 1e-12 * std::abs(plain.value(at.head(offset))));
}

// ---------------------------------------------------------------------------------------------------------
// A coupled system (coupled_term.hpp): x = [q; y] and, with a tracking root, [q; θ; τ; y].

/// Springs with a rest length from every listed node to a free point y (3 coordinates):
/// u = k/4 (|d|² − ℓ²)², d = p − y − a_c, so the node, node × y and y blocks are all non-trivial.
class SpringsToAPoint final : public CoupledSystem {
 public:
  SpringsToAPoint(std::vector<int> nodes, double stiffness, double rest)
      : nodes_(std::move(nodes)), k_(stiffness), l_(rest) {
    for (std::size_t c = 0; c < nodes_.size(); ++c) {
      candidates_.push_back(static_cast<int>(c));
      offsets_.push_back(Eigen::Vector3d(0.01 * (c % 3), -0.02 * (c % 5), 0.015 * (c % 2)));
    }
  }
  Eigen::Index size() const override { return 3; }
  const std::vector<int>& nodes() const override { return nodes_; }
  void begin_substep(double, double, const meshing::RowMatrixX3d&, const meshing::RowMatrixX3d&) override {}
  const std::vector<int>& candidates() const override { return candidates_; }
  double evaluate(const meshing::RowMatrixX3d& P, const Eigen::VectorXd& y, CoupledDerivatives* d,
                  bool with_hessian) const override {
    if (d) d->reset(P.rows(), 3, with_hessian);
    double value = 0.0;
    for (Eigen::Index c = 0; c < P.rows(); ++c) {
      const Eigen::Vector3d r = P.row(c).transpose() - y - offsets_[static_cast<std::size_t>(c)] - origin_;
      const double e = r.squaredNorm() - l_ * l_;
      value += 0.25 * k_ * e * e;
      if (!d) continue;
      const Eigen::Vector3d g = k_ * e * r;  // ∂u/∂p = −∂u/∂y
      d->node_gradient.row(c) += g.transpose();
      d->gradient -= g;
      if (!with_hessian) continue;
      const Eigen::Matrix3d H = k_ * (e * Eigen::Matrix3d::Identity() + 2.0 * r * r.transpose());
      d->node_hessian[static_cast<std::size_t>(c)] += H;
      d->node_mixed.middleRows<3>(3 * c) -= H;
      d->hessian += H;
    }
    return value;
  }
  bool accept_substep(const meshing::RowMatrixX3d&, const Eigen::VectorXd&) override { return true; }
  void commit_substep(const meshing::RowMatrixX3d&, const Eigen::VectorXd&) override {}
  void save() override {}
  void restore() override {}
  Eigen::Vector3d origin_ = Eigen::Vector3d(0.05, 0.04, 0.02);

 private:
  std::vector<int> nodes_, candidates_;
  std::vector<Eigen::Vector3d> offsets_;
  double k_, l_;
};

TEST_F(RootTermsFixture, CoupledSystemMatchesFiniteDifferencesWithAndWithoutARoot) {
  const model::Problem& p = box.problem;
  ReducedInertia inertia(p, subspace);
  inertia.set_time(t, x_prescribed);
  meshing::RowMatrixX3d p_start;
  inertia.posed(Eigen::VectorXd::Zero(subspace.num_dofs()), p_start);
  std::vector<int> some;  // every other moving node
  const std::vector<int> active = subspace.active_nodes();
  for (std::size_t k = 0; k < active.size(); k += 2) some.push_back(active[k]);
  SpringsToAPoint springs(some, 1e5, 0.03);
  unsigned seed = 121;
  {  // x = [q; y]
    CoupledTerm term(springs, subspace, inertia, offset);
    term.begin(t - 0.01, 0.01, p_start);
    for (double amplitude : kAmplitudes) {
      Eigen::VectorXd v(offset + 3);
      v << q(amplitude, seed), testing::random_q(3, amplitude, seed + 50);
      ++seed;
      check_derivatives(term, v);
    }
  }
  {  // x = [q; θ; τ; y]: the springs pull the deviated nodes
    CoupledTerm term(springs, subspace, inertia, offset + 6);
    term.set_root(offset);
    const RootFrame start = root_frame(Eigen::VectorXd::Zero(offset + 6), offset, pivot);
    term.begin(t - 0.01, 0.01, p_start, &start, pivot);
    for (double amplitude : kAmplitudes) {
      Eigen::VectorXd v(offset + 9);
      v << x(amplitude, seed), testing::random_q(3, amplitude, seed + 50);
      ++seed;
      check_derivatives(term, v);
    }
  }
}

// ---------------------------------------------------------------------------------------------------------
// The consistent mass of a skinned layer by joint pairs.

const body::BodyModel& open_body() {
  static const body::BodyModel model = body::load_body(std::filesystem::path(SFLSH_DATA_DIR) / "open_body.npz");
  return model;
}

TEST(ReducedInertiaConsistent, JointPairsMatchTheNodeByNodeSumsOfASkinnedLayer) {
  model::BodyLayerOptions options;
  options.size = meshing::SizePreset::coarse;
  options.cache_dir = SFLSH_TEST_CACHE;
  const body::Motion motion = body::make_procedural_motion("shake_hips", 60.0, 30);
  const model::BodyLayer layer = model::build_body_layer(open_body(), body::Betas::Zero(), motion, nullptr, 6, options);
  ReducedModelOptions ro;
  ro.point_handles = 30;
  ro.cubature = 50;
  ro.cache_dir = SFLSH_TEST_CACHE;
  const ReducedModel model = build_reduced_model(layer, ro);
  model::Problem p = layer.problem;
  p.mass_kind = model::MassKind::consistent;
  p.validate();
  ReducedInertia inertia(p, model.subspace);
  ASSERT_EQ(inertia.mass_kind(), model::MassKind::consistent);
  EXPECT_GT(inertia.inertia_nodes().size(), inertia.active_nodes().size());  // attached neighbours of the moving nodes
  const double t1 = 0.37, t0 = 0.32, h = 1.0 / 60.0;                         // between frames, hips rotating
  const Eigen::VectorXd x_d = Eigen::Map<const Eigen::VectorXd>(p.rest.data(), p.num_dofs());
  inertia.set_time(t1, x_d);
  Eigen::MatrixXd H, cross;
  inertia.mass_hessian(h, H);
  inertia.cross_mass(t0, cross);
  // Node by node: Σ_ij M_ij b_is b_jr A_i(t1)ᵀA_j(t) over the active nodes (b vanishes elsewhere).
  model::NodeFrame f1, f0;
  p.frame(t1, f1);
  p.frame(t0, f0);
  const Eigen::SparseMatrix<double, Eigen::RowMajor> M = p.mass_matrix();
  const int n = model.subspace.num_dofs();
  Eigen::MatrixXd direct_h = Eigen::MatrixXd::Zero(n, n), direct_cross = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < p.num_nodes(); ++i) {
    if (model.subspace.basis.row(i).nonZeros() == 0) continue;
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator mi(M, i); mi; ++mi) {
      const auto j = static_cast<int>(mi.col());
      const Eigen::Matrix3d G1 =
          mi.value() * f1.A[static_cast<std::size_t>(i)].transpose() * f1.A[static_cast<std::size_t>(j)];
      const Eigen::Matrix3d G0 =
          mi.value() * f1.A[static_cast<std::size_t>(i)].transpose() * f0.A[static_cast<std::size_t>(j)];
      for (SparseRowMatrix::InnerIterator si(model.subspace.basis, i); si; ++si)
        for (SparseRowMatrix::InnerIterator rj(model.subspace.basis, j); rj; ++rj) {
          direct_h.block<3, 3>(3 * si.col(), 3 * rj.col()) += si.value() * rj.value() / (h * h) * G1;
          direct_cross.block<3, 3>(3 * si.col(), 3 * rj.col()) += si.value() * rj.value() * G0;
        }
    }
  }
  // Two summation orders of the same ~1e5 products: round-off ~1e-14 of the largest entry.
  ASSERT_GT(direct_h.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LE((H - direct_h).cwiseAbs().maxCoeff(), 1e-12 * direct_h.cwiseAbs().maxCoeff());
  EXPECT_LE((cross - direct_cross).cwiseAbs().maxCoeff(), 1e-12 * direct_cross.cwiseAbs().maxCoeff());
  EXPECT_LE((H - H.transpose()).cwiseAbs().maxCoeff(), 1e-13 * H.cwiseAbs().maxCoeff());
  // The consistent projection is not the lumped one (the off-diagonal M_ij couple the nodes of neighbouring tets).
  model::Problem lumped = layer.problem;
  ReducedInertia lumped_inertia(lumped, model.subspace);
  lumped_inertia.set_time(t1, x_d);
  Eigen::MatrixXd H_lumped;
  lumped_inertia.mass_hessian(h, H_lumped);
  EXPECT_GT((H - H_lumped).cwiseAbs().maxCoeff(), 1e-3 * H_lumped.cwiseAbs().maxCoeff());
}

}  // namespace
}  // namespace sflsh::reduced
