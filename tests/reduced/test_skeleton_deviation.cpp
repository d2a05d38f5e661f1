// The tracking skeleton's deviation (skeleton_deviation.hpp, root_tracking.hpp): the rotation vector's derivatives;
// the deviation frame's value and first and second derivatives against central differences, on a small skeleton with
// a tracked chain, an untracked joint riding on its parent and blended nodes; and every term of a tracking skeleton
// (inertia over every node, springs, dampers and soft limits, node potential and a coupled system at the deviated
// positions) in the finite-difference harness, with the root alone (x = [q; θ; τ]) and with tracked joints
// (x = [q; θ; τ; φ_1; φ_2]).
#include "term_fixtures.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/reduced/coupled_term.hpp>
#include <sflsh/reduced/reduced_history.hpp>
#include <sflsh/reduced/root_tracking.hpp>
#include <sflsh/reduced/rotation_vector.hpp>
#include <sflsh/reduced/skeleton_deviation.hpp>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>

namespace sflsh::reduced {
namespace {

using namespace testing_terms;

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

TEST_F(RootTermsFixture, RootInertiaMatchesFiniteDifferencesAndTheInertiaAtZeroDeviation) {
  ReducedInertia inertia(box.problem, subspace);
  inertia.set_time(t, x_prescribed);
  const Eigen::VectorXd p_tilde = inertia_targets(inertia);
  const double h_eff = 1.0 / 240.0;
  const SkeletonDeviation root_only;
  RootInertiaTerm term(inertia, subspace, root_only, carried, carried_mass, offset);
  term.set_step(p_tilde, carried_tilde, carried_posed, DeviationPose{pivot, {}}, h_eff);
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
  RootInertiaTerm moved(inertia, subspace, root_only, carried, carried_mass, offset);
  moved.set_step(shifted_tilde, shifted_carried, carried_posed, DeviationPose{pivot, {}}, h_eff);
  Eigen::VectorXd translated = zero;
  translated.tail<3>() = shift;
  EXPECT_NEAR(moved.value(translated), term.value(zero), 1e-12 * term.value(zero));
}

TEST_F(RootTermsFixture, TrackingSpringAndDamperMatchFiniteDifferences) {
  RootTrackingTerm term(offset);
  Eigen::VectorXd stiffness(6), damping(6), previous(6);
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
  const SkeletonDeviation root_only;
  const DeviationFrame start = root_only.frame(Eigen::VectorXd::Zero(offset + 6), offset, pivot, {}, false);
  ASSERT_TRUE(potentials.begin(t - 0.01, 0.01, p_start, inertia, &start));
  RootPotentialTerm term(potentials, inertia, root_only, offset);
  term.set_pose(DeviationPose{pivot, {}});
  unsigned seed = 101;
  for (double amplitude : kAmplitudes) check_derivatives(term, x(amplitude, seed++));
  // Without deviation it is the plain potential term (R(p − c) + c = p up to the round-off of ~0.1 m coordinates).
  ReducedPotentialTerm plain(potentials, inertia);
  Eigen::VectorXd at = x(1e-3, 111);
  at.tail<6>().setZero();
  EXPECT_NEAR(term.value(at), plain.value(at.head(offset)), 1e-12 * std::abs(plain.value(at.head(offset))));
}

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
    const SkeletonDeviation root_only;
    CoupledTerm term(springs, subspace, inertia, offset + 6);
    term.set_root(offset, root_only);
    const DeviationFrame start = root_only.frame(Eigen::VectorXd::Zero(offset + 6), offset, pivot, {}, false);
    term.begin(t - 0.01, 0.01, p_start, &start, DeviationPose{pivot, {}});
    for (double amplitude : kAmplitudes) {
      Eigen::VectorXd v(offset + 9);
      v << x(amplitude, seed), testing::random_q(3, amplitude, seed + 50);
      ++seed;
      check_derivatives(term, v);
    }
  }
}

// ---------------------------------------------------------------------------------------------------------
// Tracked joints below the root.

/// A chain 0 → 1 → 2 with a branch 1 → 3; joints 1 and 3 tracked, joint 2 rides on joint 1's bone. The box's nodes
/// blend the four joints by their x (the root's share falls from 1 to 0 across the box), some without joint 3.
struct JointTermsFixture : RootTermsFixture {
  JointTrackingSetup setup;
  std::unique_ptr<SkeletonDeviation> skeleton;
  DeviationPose pose;

  void SetUp() override {
    RootTermsFixture::SetUp();
    setup.parents = {-1, 0, 1, 1};
    setup.joints = {1, 3};
    const model::Problem& p = box.problem;
    const double x_max = p.rest.col(0).maxCoeff(), x_min = p.rest.col(0).minCoeff();
    for (int i = 0; i < p.num_nodes(); ++i) {
      const double a = (p.rest(i, 0) - x_min) / (x_max - x_min);
      JointBlend w{{0, 1.0 - a}, {1, 0.5 * a}, {2, 0.25 * a}};
      if (i % 3 == 0)
        w[2].second += 0.25 * a;
      else
        w.emplace_back(3, 0.25 * a);
      setup.node_weights.push_back(w);
    }
    skeleton = std::make_unique<SkeletonDeviation>(setup);
    pose.pivot = pivot;
    pose.centres = {Eigen::Vector3d(0.03, 0.02, 0.01), Eigen::Vector3d(0.07, 0.06, 0.02)};
  }
  /// x = [q; θ; τ; φ_1; φ_3], the rotations up to 10·amplitude [rad].
  Eigen::VectorXd xj(double amplitude, unsigned seed) const {
    Eigen::VectorXd v(offset + 12);
    v << x(amplitude, seed), testing::random_q(6, 10.0 * amplitude, seed + 300);
    return v;
  }
};

TEST_F(JointTermsFixture, BonesChainsAndBlendsFollowTheSkeleton) {
  ASSERT_EQ(skeleton->size(), 12);
  EXPECT_TRUE(skeleton->chain(0).empty());
  EXPECT_EQ(skeleton->chain(1), std::vector<int>({0}));
  EXPECT_EQ(skeleton->chain(2), std::vector<int>({0, 1}));
  // Joint 2 (untracked) rides on joint 1's bone: a node on joints 1 and 2 is on bone 1 alone.
  const JointBlend blend = skeleton->bone_blend({{1, 0.4}, {2, 0.6}});
  ASSERT_EQ(blend.size(), 1U);
  EXPECT_EQ(blend[0].first, 1);
  EXPECT_NEAR(blend[0].second, 1.0, 1e-15);
  EXPECT_THROW(SkeletonDeviation(JointTrackingSetup{{-1, 0}, {0}, {}}), Error);  // the root has its own coordinates
}

TEST_F(JointTermsFixture, FrameDerivativesMatchFiniteDifferences) {
  constexpr double h = 1e-6;
  for (unsigned seed : {1U, 2U, 3U}) {
    Eigen::VectorXd v = xj(4e-2, seed);  // rotations up to 0.4 rad
    const DeviationFrame frame = skeleton->frame(v, offset, pose.pivot, pose.centres, true);
    for (int node : {0, 5, 17, box.problem.num_nodes() - 1}) {
      const Eigen::Vector3d p = box.problem.rest.row(node).transpose() + Eigen::Vector3d(0.003, -0.002, 0.001);
      const Eigen::Vector3d g(0.3, -1.1, 0.7);
      Eigen::Matrix<double, 3, Eigen::Dynamic> J;
      frame.jacobian(node, p, J);
      std::vector<Eigen::Matrix3d> dL;
      frame.linear_derivatives(node, dL);
      Eigen::MatrixXd second = Eigen::MatrixXd::Zero(12, 12);
      frame.add_second(node, p, g, 1.0, second);
      for (int k = 0; k < 12; ++k) {
        Eigen::VectorXd vp = v, vm = v;
        vp[offset + k] += h;
        vm[offset + k] -= h;
        const DeviationFrame fp = skeleton->frame(vp, offset, pose.pivot, pose.centres, false);
        const DeviationFrame fm = skeleton->frame(vm, offset, pose.pivot, pose.centres, false);
        EXPECT_LE((J.col(k) - (fp.apply(node, p) - fm.apply(node, p)) / (2 * h)).norm(), 1e-8) << node << " " << k;
        EXPECT_LE((dL[static_cast<std::size_t>(k)] - (fp.linear(node) - fm.linear(node)) / (2 * h)).norm(), 1e-8);
        Eigen::Matrix<double, 3, Eigen::Dynamic> Jp, Jm;
        fp.jacobian(node, p, Jp);
        fm.jacobian(node, p, Jm);
        const Eigen::RowVectorXd fd = g.transpose() * (Jp - Jm) / (2 * h);
        EXPECT_LE((second.row(k) - fd).norm(), 1e-7) << node << " " << k;
      }
      // y is affine in p with linear part L.
      const Eigen::Vector3d e(0.01, 0.02, -0.03);
      EXPECT_LE((frame.apply(node, p + e) - frame.apply(node, p) - frame.linear(node) * e).norm(), 1e-15);
    }
  }
}

TEST_F(JointTermsFixture, ZeroJointRotationsGiveTheRootsRigidMotion) {
  Eigen::VectorXd v = xj(1e-2, 7);
  v.tail<6>().setZero();
  const DeviationFrame frame = skeleton->frame(v, offset, pose.pivot, pose.centres, false);
  const Eigen::Matrix3d R = rotation_of_vector(v.segment<3>(offset));
  for (int node = 0; node < box.problem.num_nodes(); ++node) {
    const Eigen::Vector3d p = box.problem.rest.row(node).transpose();
    const Eigen::Vector3d rigid = R * (p - pivot) + pivot + v.segment<3>(offset + 3);
    EXPECT_LE((frame.apply(node, p) - rigid).norm(), 1e-15);
  }
  // A node on joint 3's bone alone turns about c_3 inside the root's motion.
  v.segment<3>(offset + 9) = Eigen::Vector3d(0.0, 0.0, 0.2);
  const DeviationFrame turned = skeleton->frame(v, offset, pose.pivot, pose.centres, false);
  const Eigen::Vector3d p(0.09, 0.01, 0.0), c3 = pose.centres[1];
  const Eigen::Vector3d expected =
      R * (rotation_of_vector(v.segment<3>(offset + 9)) * (p - c3) + c3 - pivot) + pivot + v.segment<3>(offset + 3);
  EXPECT_LE((turned.apply_blend({{2, 1.0}}, p) - expected).norm(), 1e-15);
}

TEST_F(JointTermsFixture, InertiaOverTheDeviatedNodesMatchesFiniteDifferences) {
  ReducedInertia inertia(box.problem, subspace);
  inertia.set_time(t, x_prescribed);
  const Eigen::VectorXd p_tilde = inertia_targets(inertia);
  RootInertiaTerm term(inertia, subspace, *skeleton, carried, carried_mass, offset);
  term.set_step(p_tilde, carried_tilde, carried_posed, pose, 1.0 / 240.0);
  unsigned seed = 401;
  for (double amplitude : kAmplitudes) check_derivatives(term, xj(amplitude, seed++));
}

TEST_F(JointTermsFixture, SpringsDampersAndLimitsMatchFiniteDifferences) {
  RootTrackingTerm term(offset, 12);
  Eigen::VectorXd stiffness(12), damping(12), previous = testing::random_q(12, 0.01, 5);
  stiffness << 30.0, 40.0, 50.0, 600.0, 0.0, 700.0, 8.0, 8.0, 8.0, 3.0, 3.0, 3.0;
  damping << 3.0, 4.0, 5.0, 120.0, 130.0, 140.0, 1.0, 1.0, 1.0, 0.5, 0.5, 0.5;
  const Eigen::Vector2d limit(0.005, 0.03), limit_stiffness(800.0, 300.0);
  term.set_step(stiffness, damping, previous, 1.0 / 60.0, limit, limit_stiffness);
  unsigned seed = 411;
  for (double amplitude : kAmplitudes) check_derivatives(term, xj(amplitude, seed++));
  // Over the limit by δ along φ: the limit adds ½ k δ².
  Eigen::VectorXd at = Eigen::VectorXd::Zero(offset + 12);
  at.segment(offset, 12) = previous;
  at.segment<3>(offset + 6) = (limit[0] + 0.01) * Eigen::Vector3d(0.6, 0.0, 0.8);
  at.segment<3>(offset + 9).setZero();
  RootTrackingTerm free(offset, 12);
  free.set_step(stiffness, damping, previous, 1.0 / 60.0);
  EXPECT_NEAR(term.value(at) - free.value(at), 0.5 * 800.0 * 0.01 * 0.01, 1e-12);
}

TEST_F(JointTermsFixture, NodePotentialAtTheDeviatedPositionsMatchesFiniteDifferences) {
  model::Problem& p = box.problem;
  const std::vector<int> active = subspace.active_nodes();
  p.potentials.push_back(std::make_shared<CubicFloor>(active, 0.5, 1e6));
  ReducedInertia inertia(p, subspace);
  ReducedPotentials potentials(p, subspace, inertia.active_nodes());
  inertia.set_time(t, x_prescribed);
  meshing::RowMatrixX3d p_start;
  inertia.posed(Eigen::VectorXd::Zero(subspace.num_dofs()), p_start);
  const DeviationFrame start =
      skeleton->frame(Eigen::VectorXd::Zero(offset + 12), offset, pose.pivot, pose.centres, false);
  ASSERT_TRUE(potentials.begin(t - 0.01, 0.01, p_start, inertia, &start));
  RootPotentialTerm term(potentials, inertia, *skeleton, offset);
  term.set_pose(pose);
  unsigned seed = 421;
  for (double amplitude : kAmplitudes) check_derivatives(term, xj(amplitude, seed++));
}

TEST_F(JointTermsFixture, CoupledSystemAtTheDeviatedPositionsMatchesFiniteDifferences) {
  const model::Problem& p = box.problem;
  ReducedInertia inertia(p, subspace);
  inertia.set_time(t, x_prescribed);
  meshing::RowMatrixX3d p_start;
  inertia.posed(Eigen::VectorXd::Zero(subspace.num_dofs()), p_start);
  std::vector<int> some;
  const std::vector<int> active = subspace.active_nodes();
  for (std::size_t k = 0; k < active.size(); k += 2) some.push_back(active[k]);
  SpringsToAPoint springs(some, 1e5, 0.03);
  CoupledTerm term(springs, subspace, inertia, offset + 12);
  term.set_root(offset, *skeleton);
  const DeviationFrame start =
      skeleton->frame(Eigen::VectorXd::Zero(offset + 12), offset, pose.pivot, pose.centres, false);
  term.begin(t - 0.01, 0.01, p_start, &start, pose);
  unsigned seed = 431;
  for (double amplitude : kAmplitudes) {
    Eigen::VectorXd v(offset + 15);
    v << xj(amplitude, seed), testing::random_q(3, amplitude, seed + 50);
    ++seed;
    check_derivatives(term, v);
  }
}

}  // namespace
}  // namespace sflsh::reduced
