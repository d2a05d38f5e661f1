// dσ/dp of the per-vertex dynamics amplitudes (dynamics_sensitivity.hpp has the formulas).
#include <sflsh/core/error.hpp>
#include <sflsh/reduced/dynamics_sensitivity.hpp>

namespace sflsh::reduced {

DynamicsAmplitudeSensitivity::DynamicsAmplitudeSensitivity(meshing::RowMatrixX3d normals, int parameters)
    : normals_(std::move(normals)),
      sum_u_(meshing::RowMatrixX3d::Zero(normals_.rows(), 3)),
      sum_uu_(Eigen::VectorXd::Zero(normals_.rows())),
      sum_un_(Eigen::VectorXd::Zero(normals_.rows())),
      sum_unun_(Eigen::VectorXd::Zero(normals_.rows())),
      sum_du_(Eigen::MatrixXd::Zero(3 * normals_.rows(), parameters)),
      sum_u_du_(Eigen::MatrixXd::Zero(normals_.rows(), parameters)),
      sum_un_dun_(Eigen::MatrixXd::Zero(normals_.rows(), parameters)) {
  require(parameters >= 0, "dynamics sensitivity: parameter count must be ≥ 0, got {}", parameters);
}

void DynamicsAmplitudeSensitivity::add(const meshing::RowMatrixX3d& u, const Eigen::MatrixXd& du) {
  const Eigen::Index R = normals_.rows();
  require(u.rows() == R && du.rows() == 3 * R && du.cols() == sum_du_.cols(),
          "dynamics sensitivity: frame has {} displacements and a {}×{} derivative, expected {} and {}×{}", u.rows(),
          du.rows(), du.cols(), R, 3 * R, sum_du_.cols());
  sum_u_ += u;
  sum_du_ += du;
  for (Eigen::Index r = 0; r < R; ++r) {
    const Eigen::RowVector3d ur = u.row(r), n = normals_.row(r);
    const double un = ur.dot(n);
    sum_uu_[r] += ur.squaredNorm();
    sum_un_[r] += un;
    sum_unun_[r] += un * un;
    const auto block = du.middleRows<3>(3 * r);
    sum_u_du_.row(r).noalias() += ur * block;
    sum_un_dun_.row(r).noalias() += un * (n * block);
  }
  ++frames_;
}

// Variances as in model::DynamicsAmplitude (mean of squares minus square of the mean, clamped at 0).
Eigen::VectorXd DynamicsAmplitudeSensitivity::sigma_normal() const {
  if (frames_ == 0) return Eigen::VectorXd::Zero(normals_.rows());
  const double inv = 1.0 / frames_;
  return (sum_unun_ * inv - (sum_un_ * inv).array().square().matrix()).cwiseMax(0.0).cwiseSqrt();
}

Eigen::VectorXd DynamicsAmplitudeSensitivity::sigma_tangent() const {
  if (frames_ == 0) return Eigen::VectorXd::Zero(normals_.rows());
  const double inv = 1.0 / frames_;
  const Eigen::VectorXd total = sum_uu_ * inv - (sum_u_ * inv).rowwise().squaredNorm();
  const Eigen::VectorXd normal = sum_unun_ * inv - (sum_un_ * inv).array().square().matrix();
  return (total - normal).cwiseMax(0.0).cwiseSqrt();
}

Eigen::MatrixXd DynamicsAmplitudeSensitivity::sigma_normal_derivative() const {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(normals_.rows(), sum_du_.cols());
  if (frames_ == 0) return out;
  const double inv = 1.0 / frames_;
  const Eigen::VectorXd sn = sigma_normal();
  for (Eigen::Index r = 0; r < normals_.rows(); ++r) {
    if (sn[r] == 0.0) continue;
    const Eigen::RowVector3d n = normals_.row(r);
    // mean[(n·d̃)(n·du)] = mean[(n·u)(n·du)] − (n·ū)(n·mean du)
    const Eigen::RowVectorXd mixed =
        sum_un_dun_.row(r) * inv - (sum_un_[r] * inv) * (n * sum_du_.middleRows<3>(3 * r) * inv);
    out.row(r) = mixed / sn[r];
  }
  return out;
}

Eigen::MatrixXd DynamicsAmplitudeSensitivity::sigma_tangent_derivative() const {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(normals_.rows(), sum_du_.cols());
  if (frames_ == 0) return out;
  const double inv = 1.0 / frames_;
  const Eigen::VectorXd st = sigma_tangent();
  for (Eigen::Index r = 0; r < normals_.rows(); ++r) {
    if (st[r] == 0.0) continue;
    const Eigen::RowVector3d n = normals_.row(r), mean_u = sum_u_.row(r) * inv;
    const Eigen::MatrixXd mean_du = sum_du_.middleRows<3>(3 * r) * inv;
    const Eigen::RowVectorXd all = sum_u_du_.row(r) * inv - mean_u * mean_du;  // mean[d̃·du]
    const Eigen::RowVectorXd normal =
        sum_un_dun_.row(r) * inv - (sum_un_[r] * inv) * (n * mean_du);  // mean[(n·d̃)(n·du)]
    out.row(r) = (all - normal) / st[r];
  }
  return out;
}

}  // namespace sflsh::reduced
