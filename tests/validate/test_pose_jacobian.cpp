// The analytic Jacobian of the posed vertices against central differences, on a synthetic body with pose
// correctives, a rotated world frame and poses from small to large angles.
#include "synthetic_body.hpp"

#include <sflsh/validate/pose_jacobian.hpp>

#include <gtest/gtest.h>

#include <random>

namespace sflsh::validate {
namespace {

class PoseJacobian : public ::testing::TestWithParam<double> {};

TEST_P(PoseJacobian, MatchesCentralDifferences) {
  const double scale = GetParam();  // typical joint angle [rad]
  const body::BodyModel model = sflsh::testing::synthetic_body(6, true, 11);
  body::Betas beta = body::Betas::Zero();
  beta[0] = 0.7;
  const RowMatrixX3d shaped = body::shaped_template(model, beta);
  const Eigen::Matrix3d world = body::rodrigues(Eigen::Vector3d(0.3, -1.2, 0.5));
  const PosedModel posed_model(model, shaped, body::regress_joints(model, shaped), world);
  std::mt19937 rng(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  PoseParameters p;
  for (int k = 0; k < kNumPoseParameters; ++k) p[k] = scale * normal(rng);
  RowMatrixX3d v;
  Eigen::MatrixXd jacobian;
  posed_model.posed_and_jacobian(p, v, jacobian);
  EXPECT_LT((v - posed_model.posed(p)).cwiseAbs().maxCoeff(), 1e-15);
  ASSERT_EQ(jacobian.rows(), 3 * model.num_vertices());
  ASSERT_EQ(jacobian.cols(), kNumPoseParameters);
  const double h = 1e-6;
  double worst = 0.0;
  for (int k = 0; k < kNumPoseParameters; ++k) {
    PoseParameters plus = p, minus = p;
    plus[k] += h;
    minus[k] -= h;
    const RowMatrixX3d dv = (posed_model.posed(plus) - posed_model.posed(minus)) / (2 * h);
    const Eigen::Map<const Eigen::VectorXd> fd(dv.data(), dv.size());  // row-major n×3: entry 3i + c
    worst = std::max(worst, (fd - jacobian.col(k)).cwiseAbs().maxCoeff());
  }
  // Central differences err by O(h² ‖v'''‖) ≈ 1e-12 plus round-off ε‖v‖/h ≈ 1e-10 (positions ~1 m);
  // entries are O(1) m/rad, so 1e-7 separates a correct Jacobian from any wrong term by orders of magnitude.
  EXPECT_LT(worst, 1e-7) << "joint angle scale " << scale;
}

INSTANTIATE_TEST_SUITE_P(AngleScales, PoseJacobian, ::testing::Values(1e-9, 0.05, 0.6, 1.5));

TEST(PoseJacobian, LeftJacobianOfRodrigues) {
  for (const Eigen::Vector3d& omega :
       {Eigen::Vector3d(1e-9, -2e-9, 0.5e-9), Eigen::Vector3d(0.2, 0.1, -0.3), Eigen::Vector3d(2.0, -1.0, 1.5)}) {
    const Eigen::Matrix3d s = rotation_left_jacobian(omega);
    const Eigen::Matrix3d r = body::rodrigues(omega);
    for (int m = 0; m < 3; ++m) {
      const double h = 1e-6;
      const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(m);
      const Eigen::Matrix3d dr = (body::rodrigues(omega + e) - body::rodrigues(omega - e)) / (2 * h);
      const Eigen::Matrix3d skew = dr * r.transpose();  // [S e_m]×
      const Eigen::Vector3d axial(skew(2, 1), skew(0, 2), skew(1, 0));
      // Same error budget as above for O(1) entries.
      EXPECT_LT((axial - s.col(m)).norm(), 1e-8) << omega.transpose();
    }
  }
}

}  // namespace
}  // namespace sflsh::validate
