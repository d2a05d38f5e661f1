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

PosedModel::Linearization PosedModel::linearize(const PoseParameters& parameters) const {
  constexpr int J = body::kNumJoints;
  Linearization lin;
  const body::Pose theta = pose_of(parameters);
  lin.kinematics = body::forward_kinematics(model_, joints_, theta, trans_of(parameters));
  lin.unposed = shaped_ + body::pose_correctives(model_, theta);
  const Eigen::Index n = lin.unposed.rows();

  // Per joint: g_j = G_par(j) S(ω_j) (3×3) and, with pose correctives, ∂B_P/∂ω_j (3n×3) for j ≥ 1.
  std::array<Eigen::Matrix3d, J> rotation;
  for (int j = 0; j < J; ++j) {
    const int parent = model_.parents[static_cast<std::size_t>(j)];
    const Eigen::Vector3d omega = theta.segment<3>(3 * j);
    const Eigen::Matrix3d parent_linear =
        parent < 0 ? Eigen::Matrix3d(Eigen::Matrix3d::Identity())
                   : Eigen::Matrix3d(lin.kinematics.global[static_cast<std::size_t>(parent)].linear());
    lin.g[static_cast<std::size_t>(j)] = parent_linear * rotation_left_jacobian(omega);
    rotation[static_cast<std::size_t>(j)] = body::rodrigues(omega);
  }
  if (model_.has_pose_correctives()) {
    lin.corrective_jacobian.resize(3 * n, 3 * (J - 1));
    for (int j = 1; j < J; ++j) {
      const Eigen::Matrix3d s = rotation_left_jacobian(theta.segment<3>(3 * j));
      Eigen::Matrix<double, 9, 3> d_features;  // ∂ vec_rowmajor(R_j − I) / ∂ω_j; ∂R/∂ω_m = [S e_m]× R
      for (int m = 0; m < 3; ++m) {
        const Eigen::Matrix3d dr = skew(s.col(m)) * rotation[static_cast<std::size_t>(j)];
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) d_features(3 * a + b, m) = dr(a, b);
      }
      lin.corrective_jacobian.middleCols<3>(3 * (j - 1)).noalias() =
          model_.posedirs.middleCols<9>(9 * (j - 1)) * d_features;
    }
  }
  return lin;
}

std::uint32_t PosedModel::vertex_jacobian(const Linearization& lin, Eigen::Index i, Eigen::Vector3d& position,
                                          Eigen::Matrix<double, 3, kNumPoseParameters>& block) const {
  constexpr int J = body::kNumJoints;
  const Eigen::Vector3d x = lin.unposed.row(i).transpose();
  Eigen::Matrix<double, 3, 4> a = Eigen::Matrix<double, 3, 4>::Zero();
  std::array<Eigen::Vector3d, J> p_sum;  // P_ij
  std::array<double, J> w_sum{};         // W_ij
  for (auto& p : p_sum) p.setZero();
  std::uint32_t touched = 0;
  double total = 0.0;
  for (const auto& [k, w] : weights_[static_cast<std::size_t>(i)]) {
    const Eigen::Matrix<double, 3, 4> m = lin.kinematics.skinning[static_cast<std::size_t>(k)].matrix().topRows<3>();
    a.noalias() += w * m;
    total += w;
    const Eigen::Vector3d p = m.leftCols<3>() * x + m.col(3);
    const std::uint32_t mask = ancestors_[static_cast<std::size_t>(k)];
    touched |= mask;
    for (int j = 0; j < J; ++j)
      if (mask & (1u << j)) {
        p_sum[static_cast<std::size_t>(j)] += w * p;
        w_sum[static_cast<std::size_t>(j)] += w;
      }
  }
  position = world_from_body_ * (a.leftCols<3>() * x + a.col(3));
  const bool correctives = lin.corrective_jacobian.size() > 0;
  if (correctives) touched |= ~std::uint32_t{1} & ((std::uint32_t{1} << J) - 1);  // B_P depends on every joint ≥ 1
  block.setZero();
  for (int j = 0; j < J; ++j) {
    if (!(touched & (1u << j))) continue;
    Eigen::Matrix3d b = Eigen::Matrix3d::Zero();
    const auto sj = static_cast<std::size_t>(j);
    if (w_sum[sj] != 0.0) {
      const Eigen::Vector3d lever = p_sum[sj] - w_sum[sj] * lin.kinematics.joints_posed.row(j).transpose();
      b.noalias() -= skew(lever) * lin.g[sj];
    }
    if (correctives && j > 0) b.noalias() += a.leftCols<3>() * lin.corrective_jacobian.block<3, 3>(3 * i, 3 * (j - 1));
    block.block<3, 3>(0, 3 * j) = world_from_body_ * b;
  }
  block.block<3, 3>(0, 3 * J) = total * world_from_body_;
  return touched;
}

void PosedModel::posed_and_jacobian(const PoseParameters& parameters, RowMatrixX3d& posed, Eigen::MatrixXd& jacobian,
                                    const std::vector<int>* rows) const {
  const Linearization lin = linearize(parameters);
  posed = this->posed(parameters);
  const Eigen::Index n = lin.unposed.rows();
  const Eigen::Index count = rows ? static_cast<Eigen::Index>(rows->size()) : n;
  jacobian.setZero(3 * count, kNumPoseParameters);
  Eigen::Vector3d position;
  Eigen::Matrix<double, 3, kNumPoseParameters> block;
  for (Eigen::Index s = 0; s < count; ++s) {
    const Eigen::Index i = rows ? (*rows)[static_cast<std::size_t>(s)] : s;
    vertex_jacobian(lin, i, position, block);
    jacobian.middleRows<3>(3 * s) = block;
  }
}

double PosedModel::rows_cost(const PoseParameters& parameters, const std::vector<int>& rows,
                             const Eigen::VectorXd& weights, const RowMatrixX3d& target) const {
  const body::Kinematics kin = body::forward_kinematics(model_, joints_, pose_of(parameters), trans_of(parameters));
  const bool correctives = model_.has_pose_correctives();
  const body::Pose theta = pose_of(parameters);
  const Eigen::Matrix<double, body::kNumPoseFeatures, 1> features =
      correctives ? body::pose_features(theta) : Eigen::Matrix<double, body::kNumPoseFeatures, 1>::Zero();
  double cost = 0.0;
  for (std::size_t s = 0; s < rows.size(); ++s) {
    const int i = rows[s];
    Eigen::Vector3d x = shaped_.row(i).transpose();
    if (correctives) x += model_.posedirs.middleRows<3>(3 * i) * features;
    Eigen::Matrix<double, 3, 4> a = Eigen::Matrix<double, 3, 4>::Zero();
    for (const auto& [k, w] : weights_[static_cast<std::size_t>(i)])
      a.noalias() += w * kin.skinning[static_cast<std::size_t>(k)].matrix().topRows<3>();
    const Eigen::Vector3d v = world_from_body_ * (a.leftCols<3>() * x + a.col(3));
    cost += weights[static_cast<Eigen::Index>(s)] * (v - target.row(i).transpose()).squaredNorm();
  }
  return cost;
}

double PosedModel::normal_equations(const PoseParameters& parameters, const std::vector<int>& rows,
                                    const Eigen::VectorXd& weights, const RowMatrixX3d& target,
                                    Eigen::Matrix<double, kNumPoseParameters, kNumPoseParameters>& hessian,
                                    PoseParameters& gradient) const {
  constexpr int J = body::kNumJoints;
  const Linearization lin = linearize(parameters);
  hessian.setZero();
  gradient.setZero();
  double cost = 0.0;
  Eigen::Vector3d position;
  Eigen::Matrix<double, 3, kNumPoseParameters> block;
  std::array<int, J + 1> active{};
  for (std::size_t s = 0; s < rows.size(); ++s) {
    const int i = rows[s];
    const double w = weights[static_cast<Eigen::Index>(s)];
    const std::uint32_t touched = vertex_jacobian(lin, i, position, block);
    const Eigen::Vector3d r = position - target.row(i).transpose();
    cost += w * r.squaredNorm();
    int k = 0;
    for (int j = 0; j < J; ++j)
      if (touched & (1u << j)) active[static_cast<std::size_t>(k++)] = j;
    active[static_cast<std::size_t>(k++)] = J;  // trans
    // Only the 3×3 blocks of the joints this vertex moves with are non-zero: H += w Bᵀ B, g += w Bᵀ r over them.
    for (int a = 0; a < k; ++a) {
      const int ja = active[static_cast<std::size_t>(a)];
      const Eigen::Matrix3d ba = block.block<3, 3>(0, 3 * ja);
      gradient.segment<3>(3 * ja).noalias() += w * ba.transpose() * r;
      for (int b = 0; b <= a; ++b) {
        const int jb = active[static_cast<std::size_t>(b)];
        hessian.block<3, 3>(3 * ja, 3 * jb).noalias() += w * ba.transpose() * block.block<3, 3>(0, 3 * jb);
      }
    }
  }
  // The loop filled the lower block triangle (ja ≥ jb since active is ascending); mirror it.
  for (int a = 0; a <= J; ++a)
    for (int b = 0; b < a; ++b) hessian.block<3, 3>(3 * b, 3 * a) = hessian.block<3, 3>(3 * a, 3 * b).transpose();
  return cost;
}

}  // namespace sflsh::validate
