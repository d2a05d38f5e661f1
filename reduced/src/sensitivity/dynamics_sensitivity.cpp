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
      sum_u_du_(RowMatrix::Zero(normals_.rows(), parameters)),
      sum_un_dun_(RowMatrix::Zero(normals_.rows(), parameters)) {
  require(parameters >= 0, "dynamics sensitivity: parameter count must be ≥ 0, got {}", parameters);
}

void DynamicsAmplitudeSensitivity::add(const meshing::RowMatrixX3d& u, const Eigen::MatrixXd& du) {
  const Eigen::Index R = normals_.rows();
  require(u.rows() == R && du.rows() == 3 * R && du.cols() == sum_u_du_.cols(),
          "dynamics sensitivity: frame has {} displacements and a {}×{} derivative, expected {} and {}×{}", u.rows(),
          du.rows(), du.cols(), R, 3 * R, sum_u_du_.cols());
  require(skin_ == nullptr, "dynamics sensitivity: a stream takes one form of add() only");
  if (sum_du_.size() == 0) sum_du_ = Eigen::MatrixXd::Zero(3 * R, du.cols());
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

void DynamicsAmplitudeSensitivity::add(const meshing::RowMatrixX3d& u,
                                       const Eigen::SparseMatrix<double, Eigen::RowMajor>& skin, const RowMatrix& dq) {
  const Eigen::Index R = normals_.rows(), m = sum_u_du_.cols();
  require(u.rows() == R && skin.rows() == R && dq.rows() == 3 * skin.cols() && dq.cols() == m,
          "dynamics sensitivity: frame has {} displacements, a {}×{} skin map and a {}×{} dq/dp, expected {} rows, "
          "3 × {} and {} columns",
          u.rows(), skin.rows(), skin.cols(), dq.rows(), dq.cols(), R, skin.cols(), m);
  require(sum_du_.size() == 0 && (skin_ == nullptr || skin_ == &skin),
          "dynamics sensitivity: a stream takes one form of add() and one skin map only");
  if (skin_ == nullptr) {
    skin_ = &skin;
    sum_dq_ = RowMatrix::Zero(dq.rows(), m);
  }
  sum_u_ += u;
  sum_dq_ += dq;
  Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor> du(3, m);
  for (Eigen::Index r = 0; r < R; ++r) {
    du.setZero();  // du_r = Σ_k (K B)_rk dq_k (3 × m), rows of dq contiguous
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(skin, r); it; ++it)
      du.noalias() += it.value() * dq.middleRows<3>(3 * it.col());
    const Eigen::RowVector3d ur = u.row(r), n = normals_.row(r);
    const double un = ur.dot(n);
    sum_uu_[r] += ur.squaredNorm();
    sum_un_[r] += un;
    sum_unun_[r] += un * un;
    sum_u_du_.row(r).noalias() += ur * du;
    sum_un_dun_.row(r).noalias() += un * (n * du);
  }
  ++frames_;
}

Eigen::Matrix<double, 3, Eigen::Dynamic> DynamicsAmplitudeSensitivity::du_sum(Eigen::Index r) const {
  if (!skin_) return sum_du_.middleRows<3>(3 * r);
  Eigen::Matrix<double, 3, Eigen::Dynamic> out = Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, sum_dq_.cols());
  for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(*skin_, r); it; ++it)
    out.noalias() += it.value() * sum_dq_.middleRows<3>(3 * it.col());
  return out;
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
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(normals_.rows(), sum_u_du_.cols());
  if (frames_ == 0) return out;
  const double inv = 1.0 / frames_;
  const Eigen::VectorXd sn = sigma_normal();
  for (Eigen::Index r = 0; r < normals_.rows(); ++r) {
    if (sn[r] == 0.0) continue;
    const Eigen::RowVector3d n = normals_.row(r);
    // mean[(n·d̃)(n·du)] = mean[(n·u)(n·du)] − (n·ū)(n·mean du)
    const Eigen::RowVectorXd mixed = sum_un_dun_.row(r) * inv - (sum_un_[r] * inv) * (n * du_sum(r) * inv);
    out.row(r) = mixed / sn[r];
  }
  return out;
}

Eigen::MatrixXd DynamicsAmplitudeSensitivity::sigma_tangent_derivative() const {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(normals_.rows(), sum_u_du_.cols());
  if (frames_ == 0) return out;
  const double inv = 1.0 / frames_;
  const Eigen::VectorXd st = sigma_tangent();
  for (Eigen::Index r = 0; r < normals_.rows(); ++r) {
    if (st[r] == 0.0) continue;
    const Eigen::RowVector3d n = normals_.row(r), mean_u = sum_u_.row(r) * inv;
    const Eigen::MatrixXd mean_du = du_sum(r) * inv;
    const Eigen::RowVectorXd all = sum_u_du_.row(r) * inv - mean_u * mean_du;  // mean[d̃·du]
    const Eigen::RowVectorXd normal =
        sum_un_dun_.row(r) * inv - (sum_un_[r] * inv) * (n * mean_du);  // mean[(n·d̃)(n·du)]
    out.row(r) = (all - normal) / st[r];
  }
  return out;
}

}  // namespace sflsh::reduced
