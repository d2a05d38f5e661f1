// One finite-difference harness over every term of the reduced incremental potential (reduced_terms.hpp): value,
// gradient and Hessian in q against central differences at several amplitudes, on the box under swinging node maps,
// for the cubature elasticity (exact; projected: PSD), the inertia (lumped, consistent), gravity and a node
// potential (the tracking skeleton's terms are in test_skeleton_deviation.cpp); the inertia and gravity values against
// their node-by-node definitions; and the consistent joint-pair
// precompute and cross-time mass of a skinned body layer against node-by-node sums.
#include "open_body.hpp"
#include "term_fixtures.hpp"

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

using namespace testing_terms;

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
  EXPECT_FALSE(term.add_gradient(q(1.0, 5), g));  // reported as the full-space terms do (model/terms.hpp)
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(subspace.num_dofs(), subspace.num_dofs());
  EXPECT_FALSE(term.add_hessian(q(1.0, 5), H));
  EXPECT_TRUE(term.add_gradient(q(1e-4, 5), g.setZero()));
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
// ---------------------------------------------------------------------------------------------------------
// The consistent mass of a skinned layer by joint pairs.

using sflsh::testing::open_body;

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
