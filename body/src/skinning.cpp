#include <sflsh/body/skinning.hpp>
#include <sflsh/core/error.hpp>

#include <cmath>

namespace sflsh::body {

Eigen::Matrix3d rodrigues(const Eigen::Vector3d& omega) {
  const double angle = omega.norm();
  if (angle < 1e-8) {
    // Second-order expansion: R ≈ I + [ω]× + ½[ω]×², exact to O(|ω|³).
    Eigen::Matrix3d k;
    k << 0, -omega.z(), omega.y(), omega.z(), 0, -omega.x(), -omega.y(), omega.x(), 0;
    return Eigen::Matrix3d::Identity() + k + 0.5 * k * k;
  }
  return Eigen::AngleAxisd(angle, omega / angle).toRotationMatrix();
}

RowMatrixX3d shaped_template(const BodyModel& model, const Betas& beta) {
  const Eigen::Index n = model.num_vertices();
  const Eigen::VectorXd offsets = model.shapedirs.leftCols(kNumBetas) * beta;  // B_S(β), row 3v+c
  RowMatrixX3d shaped = model.v_template;
  shaped += Eigen::Map<const RowMatrixX3d>(offsets.data(), n, 3);
  return shaped;
}

JointPositions regress_joints(const BodyModel& model, const RowMatrixX3d& shaped) {
  JointPositions joints = model.joint_regressor * shaped;
  return joints;
}

Eigen::Matrix<double, kNumPoseFeatures, 1> pose_features(const Pose& theta) {
  Eigen::Matrix<double, kNumPoseFeatures, 1> f;
  for (int k = 1; k < kNumJoints; ++k) {
    const Eigen::Matrix3d r = rodrigues(theta.segment<3>(3 * k)) - Eigen::Matrix3d::Identity();
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) f(9 * (k - 1) + 3 * a + b) = r(a, b);  // row-major vec
  }
  return f;
}

RowMatrixX3d pose_correctives(const BodyModel& model, const Pose& theta) {
  const Eigen::Index n = model.num_vertices();
  if (!model.has_pose_correctives()) return RowMatrixX3d::Zero(n, 3);
  const Eigen::VectorXd offsets = model.posedirs * pose_features(theta);
  return Eigen::Map<const RowMatrixX3d>(offsets.data(), n, 3);
}

Kinematics forward_kinematics(const BodyModel& model, const JointPositions& joints, const Pose& theta,
                              const Eigen::Vector3d& trans) {
  Kinematics kin;
  for (int k = 0; k < kNumJoints; ++k) {
    const int parent = model.parents[static_cast<std::size_t>(k)];
    Eigen::Isometry3d local = Eigen::Isometry3d::Identity();
    local.linear() = rodrigues(theta.segment<3>(3 * k));
    const Eigen::Vector3d joint = joints.row(k).transpose();
    local.translation() = parent < 0 ? joint : Eigen::Vector3d(joint - joints.row(parent).transpose());
    kin.global[static_cast<std::size_t>(k)] = parent < 0 ? local : kin.global[static_cast<std::size_t>(parent)] * local;
  }
  for (int k = 0; k < kNumJoints; ++k) {
    const Eigen::Isometry3d& g = kin.global[static_cast<std::size_t>(k)];
    Eigen::Affine3d skin = Eigen::Affine3d::Identity();
    skin.linear() = g.linear();
    skin.translation() = g.translation() - g.linear() * joints.row(k).transpose() + trans;  // G_k [I | −J_k]
    kin.skinning[static_cast<std::size_t>(k)] = skin;
    kin.joints_posed.row(k) = (g.translation() + trans).transpose();
  }
  return kin;
}

std::vector<Eigen::Matrix<double, 3, 4>> blend_transforms(const BodyModel& model, const Kinematics& kin) {
  const Eigen::Index n = model.num_vertices();
  std::vector<Eigen::Matrix<double, 3, 4>> blended(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::Matrix<double, 3, 4> a = Eigen::Matrix<double, 3, 4>::Zero();
    for (int k = 0; k < kNumJoints; ++k) {
      const double w = model.weights(i, k);
      if (w != 0.0) a += w * kin.skinning[static_cast<std::size_t>(k)].matrix().topRows<3>();
    }
    blended[static_cast<std::size_t>(i)] = a;
  }
  return blended;
}

RowMatrixX3d linear_blend_skinning(const BodyModel& model, const Kinematics& kin, const RowMatrixX3d& unposed) {
  const Eigen::Index n = model.num_vertices();
  require(unposed.rows() == n, "linear_blend_skinning: {} points given for a body of {} vertices", unposed.rows(), n);
  RowMatrixX3d posed(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::Matrix<double, 3, 4> a = Eigen::Matrix<double, 3, 4>::Zero();
    for (int k = 0; k < kNumJoints; ++k) {
      const double w = model.weights(i, k);
      if (w != 0.0) a.noalias() += w * kin.skinning[static_cast<std::size_t>(k)].matrix().topRows<3>();
    }
    posed.row(i) = (a.leftCols<3>() * unposed.row(i).transpose() + a.col(3)).transpose();
  }
  return posed;
}

PosedBody evaluate(const BodyModel& model, const Betas& beta, const Pose& theta, const Eigen::Vector3d& trans) {
  PosedBody out;
  out.shaped = shaped_template(model, beta);
  out.joints_rest = regress_joints(model, out.shaped);
  out.unposed = out.shaped + pose_correctives(model, theta);
  out.kinematics = forward_kinematics(model, out.joints_rest, theta, trans);
  out.posed = linear_blend_skinning(model, out.kinematics, out.unposed);
  return out;
}

Poser::Poser(const BodyModel& model, const Betas& beta)
    : model_(model), shaped_(shaped_template(model, beta)), joints_(regress_joints(model, shaped_)) {}

RowMatrixX3d Poser::pose(const Pose& theta, const Eigen::Vector3d& trans) const {
  const Kinematics kin = forward_kinematics(model_, joints_, theta, trans);
  if (!model_.has_pose_correctives()) return linear_blend_skinning(model_, kin, shaped_);
  return linear_blend_skinning(model_, kin, shaped_ + pose_correctives(model_, theta));
}

JointPositions Poser::pose_joints(const Pose& theta, const Eigen::Vector3d& trans) const {
  return forward_kinematics(model_, joints_, theta, trans).joints_posed;
}

}  // namespace sflsh::body
