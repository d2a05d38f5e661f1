// Posed SMPL vertices and their analytic Jacobian with respect to pose and root translation (derivation in
// pose_jacobian.hpp).
#include <sflsh/core/error.hpp>
#include <sflsh/validate/pose_jacobian.hpp>

#include <cmath>

namespace sflsh::validate {

namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d k;
  k << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return k;
}

}  // namespace

// J_l(ω) = I + (1 − cos θ)/θ² K + (θ − sin θ)/θ³ K², K = [ω]×, θ = |ω|; below 1e-6 the series
// I + K/2 + K²/6 (next term O(θ³)).
Eigen::Matrix3d rotation_left_jacobian(const Eigen::Vector3d& omega) {
  const double angle = omega.norm();
  const Eigen::Matrix3d k = skew(omega);
  if (angle < 1e-6) return Eigen::Matrix3d::Identity() + 0.5 * k + (1.0 / 6.0) * k * k;
  const double a2 = angle * angle;
  return Eigen::Matrix3d::Identity() + ((1.0 - std::cos(angle)) / a2) * k +
         ((angle - std::sin(angle)) / (a2 * angle)) * k * k;
}

PoseParameters pack_pose(const body::Pose& theta, const Eigen::Vector3d& trans) {
  PoseParameters p;
  p << theta, trans;
  return p;
}
body::Pose pose_of(const PoseParameters& parameters) { return parameters.head<3 * body::kNumJoints>(); }
Eigen::Vector3d trans_of(const PoseParameters& parameters) { return parameters.tail<3>(); }

PosedModel::PosedModel(const body::BodyModel& model, RowMatrixX3d shaped, const body::JointPositions& joints,
                       const Eigen::Matrix3d& world_from_body)
    : model_(model), shaped_(std::move(shaped)), joints_(joints), world_from_body_(world_from_body) {
  require(shaped_.rows() == model.num_vertices(), "posed model: {} shaped vertices for a body of {}", shaped_.rows(),
          model.num_vertices());
  weights_.resize(static_cast<std::size_t>(model.num_vertices()));
  for (Eigen::Index i = 0; i < model.num_vertices(); ++i)
    for (int k = 0; k < body::kNumJoints; ++k)
      if (model.weights(i, k) != 0.0) weights_[static_cast<std::size_t>(i)].emplace_back(k, model.weights(i, k));
  for (int k = 0; k < body::kNumJoints; ++k) {
    std::uint32_t mask = 0;
    for (int j = k; j >= 0; j = model.parents[static_cast<std::size_t>(j)]) mask |= 1u << j;
    ancestors_[static_cast<std::size_t>(k)] = mask;
  }
}

RowMatrixX3d PosedModel::posed(const PoseParameters& parameters) const {
  const body::Kinematics kin = body::forward_kinematics(model_, joints_, pose_of(parameters), trans_of(parameters));
  const RowMatrixX3d unposed = shaped_ + body::pose_correctives(model_, pose_of(parameters));
  RowMatrixX3d out(unposed.rows(), 3);
  for (Eigen::Index i = 0; i < unposed.rows(); ++i) {
    Eigen::Matrix<double, 3, 4> a = Eigen::Matrix<double, 3, 4>::Zero();
    for (const auto& [k, w] : weights_[static_cast<std::size_t>(i)])
      a.noalias() += w * kin.skinning[static_cast<std::size_t>(k)].matrix().topRows<3>();
    out.row(i) = (world_from_body_ * (a.leftCols<3>() * unposed.row(i).transpose() + a.col(3))).transpose();
  }
  return out;
}

void PosedModel::posed_and_jacobian(const PoseParameters& parameters, RowMatrixX3d& posed, Eigen::MatrixXd& jacobian,
                                    const std::vector<int>* rows) const {
  constexpr int J = body::kNumJoints;
  const body::Pose theta = pose_of(parameters);
  const body::Kinematics kin = body::forward_kinematics(model_, joints_, theta, trans_of(parameters));
  const RowMatrixX3d unposed = shaped_ + body::pose_correctives(model_, theta);
  const Eigen::Index n = unposed.rows();

  // Per joint: g_j = G_par(j) S(ω_j) (3×3) and, with pose correctives, ∂B_P/∂ω_j (3n×3) for j ≥ 1.
  std::array<Eigen::Matrix3d, J> g;
  std::array<Eigen::Matrix3d, J> rotation;
  for (int j = 0; j < J; ++j) {
    const int parent = model_.parents[static_cast<std::size_t>(j)];
    const Eigen::Vector3d omega = theta.segment<3>(3 * j);
    const Eigen::Matrix3d parent_linear = parent < 0
                                              ? Eigen::Matrix3d(Eigen::Matrix3d::Identity())
                                              : Eigen::Matrix3d(kin.global[static_cast<std::size_t>(parent)].linear());
    g[static_cast<std::size_t>(j)] = parent_linear * rotation_left_jacobian(omega);
    rotation[static_cast<std::size_t>(j)] = body::rodrigues(omega);
  }
  const bool correctives = model_.has_pose_correctives();
  Eigen::MatrixXd corrective_jacobian;  // 3n × 69: columns 3(j−1)+m = ∂B_P/∂ω_{j,m}
  if (correctives) {
    corrective_jacobian.resize(3 * n, 3 * (J - 1));
    for (int j = 1; j < J; ++j) {
      const Eigen::Matrix3d s = rotation_left_jacobian(theta.segment<3>(3 * j));
      Eigen::Matrix<double, 9, 3> d_features;  // ∂ vec_rowmajor(R_j − I) / ∂ω_j; ∂R/∂ω_m = [S e_m]× R
      for (int m = 0; m < 3; ++m) {
        const Eigen::Matrix3d dr = skew(s.col(m)) * rotation[static_cast<std::size_t>(j)];
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) d_features(3 * a + b, m) = dr(a, b);
      }
      corrective_jacobian.middleCols<3>(3 * (j - 1)).noalias() =
          model_.posedirs.middleCols<9>(9 * (j - 1)) * d_features;
    }
  }

  posed = this->posed(parameters);
  const Eigen::Index count = rows ? static_cast<Eigen::Index>(rows->size()) : n;
  jacobian.setZero(3 * count, kNumPoseParameters);
  for (Eigen::Index s = 0; s < count; ++s) {
    const Eigen::Index i = rows ? (*rows)[static_cast<std::size_t>(s)] : s;
    const Eigen::Vector3d x = unposed.row(i).transpose();
    Eigen::Matrix<double, 3, 4> a = Eigen::Matrix<double, 3, 4>::Zero();
    std::array<Eigen::Vector3d, J> p_sum;  // P_ij
    std::array<double, J> w_sum{};         // W_ij
    for (auto& p : p_sum) p.setZero();
    std::uint32_t touched = 0;
    for (const auto& [k, w] : weights_[static_cast<std::size_t>(i)]) {
      const Eigen::Matrix<double, 3, 4> m = kin.skinning[static_cast<std::size_t>(k)].matrix().topRows<3>();
      a.noalias() += w * m;
      const Eigen::Vector3d p = m.leftCols<3>() * x + m.col(3);
      const std::uint32_t mask = ancestors_[static_cast<std::size_t>(k)];
      touched |= mask;
      for (int j = 0; j < J; ++j)
        if (mask & (1u << j)) {
          p_sum[static_cast<std::size_t>(j)] += w * p;
          w_sum[static_cast<std::size_t>(j)] += w;
        }
    }
    for (int j = 0; j < J; ++j) {
      Eigen::Matrix3d block = Eigen::Matrix3d::Zero();
      if (touched & (1u << j)) {
        const auto sj = static_cast<std::size_t>(j);
        const Eigen::Vector3d lever = p_sum[sj] - w_sum[sj] * kin.joints_posed.row(j).transpose();
        block.noalias() -= skew(lever) * g[sj];
      }
      if (correctives && j > 0)
        block.noalias() += a.leftCols<3>() * corrective_jacobian.block<3, 3>(3 * i, 3 * (j - 1));
      jacobian.block<3, 3>(3 * s, 3 * j) = world_from_body_ * block;
    }
    double total = 0.0;
    for (const auto& [k, w] : weights_[static_cast<std::size_t>(i)]) total += w;
    jacobian.block<3, 3>(3 * s, 3 * J) = total * world_from_body_;
  }
}

}  // namespace sflsh::validate
