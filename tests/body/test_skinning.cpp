// SMPL model equations: FK/LBS identities on a synthetic body (docs/physics.md §3.1).
#include "synthetic_body.hpp"

#include <sflsh/body/skinning.hpp>

#include <gtest/gtest.h>

#include <random>

using namespace sflsh::body;

namespace {

Pose random_pose(unsigned seed, double scale = 0.5) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, scale);
  Pose theta;
  for (int i = 0; i < theta.size(); ++i) theta(i) = normal(rng);
  return theta;
}

Betas random_betas(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.5);
  Betas beta;
  for (int i = 0; i < kNumBetas; ++i) beta(i) = normal(rng);
  return beta;
}

}  // namespace

TEST(Rodrigues, OrthonormalAndMatchesKnownRotations) {
  const Eigen::Matrix3d r = rodrigues(Eigen::Vector3d(0, 0, M_PI / 2));
  EXPECT_TRUE((r * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  for (unsigned s = 0; s < 20; ++s) {
    const Eigen::Vector3d w = random_pose(s, 1.0).head<3>();
    const Eigen::Matrix3d q = rodrigues(w);
    EXPECT_TRUE((q.transpose() * q).isIdentity(1e-12));
    EXPECT_NEAR(q.determinant(), 1.0, 1e-12);
  }
  // The small-angle branch agrees with the exact formula at the switch-over.
  const Eigen::Vector3d tiny(3e-9, -2e-9, 1e-9);
  const Eigen::Matrix3d exact = Eigen::AngleAxisd(tiny.norm(), tiny.normalized()).toRotationMatrix();
  EXPECT_TRUE(rodrigues(tiny).isApprox(exact, 1e-15));
  EXPECT_TRUE(rodrigues(Eigen::Vector3d::Zero()).isIdentity(0.0));
}

TEST(Skinning, ZeroPoseReproducesTheShapedTemplate) {
  const BodyModel model = sflsh::testing::synthetic_body();
  model.validate();
  const Betas beta = random_betas(1);
  const PosedBody out = evaluate(model, beta, Pose::Zero(), Eigen::Vector3d::Zero());
  EXPECT_LT((out.posed - out.shaped).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((out.unposed - out.shaped).cwiseAbs().maxCoeff(), 1e-15);  // R − I = 0: no correctives
}

TEST(Skinning, TranslationAddsToEveryVertex) {
  const BodyModel model = sflsh::testing::synthetic_body();
  const Pose theta = random_pose(2);
  const Eigen::Vector3d trans(0.3, -1.2, 2.0);
  const PosedBody a = evaluate(model, Betas::Zero(), theta, Eigen::Vector3d::Zero());
  const PosedBody b = evaluate(model, Betas::Zero(), theta, trans);
  EXPECT_LT(((b.posed.rowwise() - trans.transpose()) - a.posed).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Skinning, GlobalRotationRotatesEverythingRigidly) {
  const BodyModel model = sflsh::testing::synthetic_body(6, /*with_posedirs=*/true);
  const Betas beta = random_betas(3);
  Pose theta = Pose::Zero();
  theta.head<3>() = Eigen::Vector3d(0.4, -1.1, 0.7);
  const Eigen::Vector3d trans(0.1, 0.2, 0.3);
  const PosedBody out = evaluate(model, beta, theta, trans);
  const Eigen::Matrix3d r = rodrigues(theta.head<3>());
  const Eigen::RowVector3d j0 = out.joints_rest.row(0);
  for (Eigen::Index i = 0; i < out.posed.rows(); ++i) {
    const Eigen::Vector3d expected = r * (out.shaped.row(i) - j0).transpose() + j0.transpose() + trans;
    EXPECT_LT((out.posed.row(i).transpose() - expected).norm(), 1e-12) << "vertex " << i;
  }
  // Pairwise distances are preserved.
  EXPECT_NEAR((out.posed.row(5) - out.posed.row(77)).norm(), (out.shaped.row(5) - out.shaped.row(77)).norm(), 1e-12);
}

TEST(Skinning, BlendShapesAndJointsAreLinearInBeta) {
  const BodyModel model = sflsh::testing::synthetic_body();
  const Betas b1 = random_betas(4), b2 = random_betas(5);
  const RowMatrixX3d t0 = shaped_template(model, Betas::Zero());
  const RowMatrixX3d t1 = shaped_template(model, b1), t2 = shaped_template(model, b2);
  const RowMatrixX3d t12 = shaped_template(model, 0.3 * b1 + 1.7 * b2);
  EXPECT_LT((t12 - t0 - 0.3 * (t1 - t0) - 1.7 * (t2 - t0)).cwiseAbs().maxCoeff(), 1e-12);
  const JointPositions j0 = regress_joints(model, t0), j1 = regress_joints(model, t1), j2 = regress_joints(model, t2);
  const JointPositions j12 = regress_joints(model, t12);
  EXPECT_LT((j12 - j0 - 0.3 * (j1 - j0) - 1.7 * (j2 - j0)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT((j1 - j0).norm(), 1e-4);  // shape really moves the joints
}

TEST(Skinning, ForwardKinematicsChainsParentTransforms) {
  const BodyModel model = sflsh::testing::synthetic_body();
  const JointPositions joints = regress_joints(model, model.v_template);
  const Pose theta = random_pose(6);
  const Kinematics kin = forward_kinematics(model, joints, theta, Eigen::Vector3d::Zero());
  for (int k = 1; k < kNumJoints; ++k) {
    const int p = model.parents[static_cast<std::size_t>(k)];
    const Eigen::Vector3d expected =
        kin.joints_posed.row(p).transpose() +
        kin.global[static_cast<std::size_t>(p)].linear() * (joints.row(k) - joints.row(p)).transpose();
    EXPECT_LT((kin.joints_posed.row(k).transpose() - expected).norm(), 1e-12)
        << kJointNames[static_cast<std::size_t>(k)];
    // Each G'_k maps the rest joint onto the posed joint.
    EXPECT_LT(
        (kin.skinning[static_cast<std::size_t>(k)] * joints.row(k).transpose() - kin.joints_posed.row(k).transpose())
            .norm(),
        1e-12);
  }
}

TEST(Skinning, RotatingOneJointMovesOnlyItsSubtree) {
  BodyModel model = sflsh::testing::synthetic_body(6, false);
  Pose theta = Pose::Zero();
  const int knee = joint_index("left_knee");
  theta.segment<3>(3 * knee) = Eigen::Vector3d(1.0, 0.0, 0.0);
  const PosedBody out = evaluate(model, Betas::Zero(), theta, Eigen::Vector3d::Zero());
  for (Eigen::Index i = 0; i < out.posed.rows(); ++i) {
    const double w = model.weights(i, knee) + model.weights(i, joint_index("left_ankle")) +
                     model.weights(i, joint_index("left_foot"));
    const double moved = (out.posed.row(i) - out.shaped.row(i)).norm();
    if (w == 0.0) {
      EXPECT_LT(moved, 1e-12) << "vertex " << i;
    }
  }
  EXPECT_GT((out.posed - out.shaped).rowwise().norm().maxCoeff(), 0.05);
}

TEST(Skinning, PoseCorrectivesEnterBeforeSkinning) {
  const BodyModel model = sflsh::testing::synthetic_body(6, true);
  const Pose theta = random_pose(8);
  const PosedBody out = evaluate(model, Betas::Zero(), theta, Eigen::Vector3d::Zero());
  const Eigen::VectorXd offsets = model.posedirs * pose_features(theta);
  const RowMatrixX3d expected =
      model.v_template + Eigen::Map<const RowMatrixX3d>(offsets.data(), model.num_vertices(), 3);
  EXPECT_LT((out.unposed - expected).cwiseAbs().maxCoeff(), 1e-12);
  // Poser gives the same posed vertices as the one-shot evaluation.
  const Poser poser(model, Betas::Zero());
  EXPECT_LT((poser.pose(theta, Eigen::Vector3d::Zero()) - out.posed).cwiseAbs().maxCoeff(), 1e-12);
  // Inverse skinning with the blended transforms recovers the unposed points.
  const auto blended = blend_transforms(model, out.kinematics);
  for (Eigen::Index i = 0; i < out.posed.rows(); i += 13) {
    const auto& a = blended[static_cast<std::size_t>(i)];
    const Eigen::Vector3d back = a.leftCols<3>().inverse() * (out.posed.row(i).transpose() - a.col(3));
    EXPECT_LT((back - out.unposed.row(i).transpose()).norm(), 1e-10);
  }
}

TEST(Skinning, PoseFeaturesAreRowMajorRMinusI) {
  Pose theta = Pose::Zero();
  theta.segment<3>(3) = Eigen::Vector3d(0.2, 0.0, 0.0);  // joint 1
  const auto f = pose_features(theta);
  const Eigen::Matrix3d r = rodrigues(Eigen::Vector3d(0.2, 0, 0)) - Eigen::Matrix3d::Identity();
  EXPECT_DOUBLE_EQ(f(1), r(0, 1));
  EXPECT_DOUBLE_EQ(f(5), r(1, 2));
  EXPECT_DOUBLE_EQ(f(7), r(2, 1));
  EXPECT_EQ(f.tail(kNumPoseFeatures - 9).cwiseAbs().maxCoeff(), 0.0);
}
