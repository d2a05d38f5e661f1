#include <sflsh/core/error.hpp>
#include <sflsh/model/terms.hpp>
#include <sflsh/reduced/root_tracking.hpp>

#include <cmath>
#include <limits>

namespace sflsh::reduced {

namespace {

using model::kInfinity;

}  // namespace

double HeadTerm::value(const Eigen::VectorXd& x) const { return inner_.value(x.head(size_)); }

bool HeadTerm::add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const {
  Eigen::VectorXd head = Eigen::VectorXd::Zero(size_);
  const bool ok = inner_.add_gradient(x.head(size_), head);
  gradient.head(size_) += head;
  return ok;
}

bool HeadTerm::add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const {
  Eigen::MatrixXd head = Eigen::MatrixXd::Zero(size_, size_);
  const bool ok = inner_.add_hessian(x.head(size_), head);
  hessian.topLeftCorner(size_, size_) += head;
  return ok;
}

RootInertiaTerm::RootInertiaTerm(const ReducedInertia& inertia, const Subspace& subspace,
                                 const SkeletonDeviation& skeleton, std::vector<int> carried,
                                 std::vector<double> carried_mass, Eigen::Index offset)
    : inertia_(inertia),
      subspace_(subspace),
      skeleton_(skeleton),
      carried_(std::move(carried)),
      carried_mass_(std::move(carried_mass)),
      offset_(offset) {
  require(inertia.mass_kind() == model::MassKind::lumped,
          "reduced: a tracking skeleton needs the lumped mass (mass = \"lumped\")");
  require(carried_.size() == carried_mass_.size(), "reduced: root inertia: {} carried nodes, {} masses",
          carried_.size(), carried_mass_.size());
}

void RootInertiaTerm::set_step(const Eigen::VectorXd& p_tilde, const Eigen::VectorXd& carried_tilde,
                               const meshing::RowMatrixX3d& carried_posed, const DeviationPose& pose, double h_eff) {
  const auto inertia_nodes = static_cast<Eigen::Index>(inertia_.inertia_nodes().size());
  const auto carried = static_cast<Eigen::Index>(carried_mass_.size());
  require(p_tilde.size() == 3 * inertia_nodes && carried_tilde.size() == 3 * carried && carried_posed.rows() == carried,
          "reduced: root inertia: {} / {} targets for {} / {} nodes", p_tilde.size() / 3, carried_tilde.size() / 3,
          inertia_nodes, carried);
  inertia_.mass_hessian(h_eff, mass_hessian_);
  target_.resize(inertia_nodes + carried, 3);
  target_.topRows(inertia_nodes) = Eigen::Map<const meshing::RowMatrixX3d>(p_tilde.data(), inertia_nodes, 3);
  target_.bottomRows(carried) = Eigen::Map<const meshing::RowMatrixX3d>(carried_tilde.data(), carried, 3);
  carried_posed_ = carried_posed;
  mass_ = inertia_.lumped_mass();
  mass_.insert(mass_.end(), carried_mass_.begin(), carried_mass_.end());
  pose_ = pose;
  h_eff_ = h_eff;
}

void RootInertiaTerm::gather(const Eigen::VectorXd& x, meshing::RowMatrixX3d& p) const {
  meshing::RowMatrixX3d moved;
  inertia_.posed(Eigen::VectorXd(x.head(offset_)), moved);
  p.resize(moved.rows() + carried_posed_.rows(), 3);
  p.topRows(moved.rows()) = moved;
  p.bottomRows(carried_posed_.rows()) = carried_posed_;
}

int RootInertiaTerm::node(Eigen::Index i) const {
  const auto moved = static_cast<Eigen::Index>(inertia_.inertia_nodes().size());
  return i < moved ? inertia_.inertia_nodes()[static_cast<std::size_t>(i)]
                   : carried_[static_cast<std::size_t>(i - moved)];
}

// 1/(2ĥ²) Σ_i m_i |y_i|², y_i = D_i(p_i) − p̃_i.
double RootInertiaTerm::value(const Eigen::VectorXd& x) const {
  if (!x.allFinite()) return kInfinity;
  const DeviationFrame frame = skeleton_.frame(x, offset_, pose_.pivot, pose_.centres, false);
  meshing::RowMatrixX3d p;
  gather(x, p);
  double sum = 0.0;
  for (Eigen::Index i = 0; i < p.rows(); ++i)
    sum += mass_[static_cast<std::size_t>(i)] *
           (frame.apply(node(i), p.row(i).transpose()) - target_.row(i).transpose()).squaredNorm();
  return 0.5 * sum / (h_eff_ * h_eff_);
}

// Σ_i m (∂y/∂r)ᵀ y over the nodes is Σ_b Σ_k ∂D_b/∂r_k : W_b with the per-bone moments W_b = Σ_i m ω_ib y [p; 1]ᵀ.
bool RootInertiaTerm::add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const {
  const DeviationFrame frame = skeleton_.frame(x, offset_, pose_.pivot, pose_.centres, false);
  meshing::RowMatrixX3d p;
  gather(x, p);
  const double w = 1.0 / (h_eff_ * h_eff_);
  const auto moved = static_cast<Eigen::Index>(inertia_.inertia_nodes().size());
  Eigen::VectorXd pulled(3 * moved);  // Lᵀy on the inertia nodes; pull_back_mass multiplies by m_i
  std::vector<Matrix34d> weighted(frame.bones.size(), Matrix34d::Zero());
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    const int n = node(i);
    const Eigen::Vector3d pi = p.row(i).transpose();
    const Eigen::Vector3d y = frame.apply(n, pi) - target_.row(i).transpose();
    const Eigen::Vector4d ph(pi.x(), pi.y(), pi.z(), 1.0);
    const double m = mass_[static_cast<std::size_t>(i)];
    for (const auto& [b, wb] : frame.blend(n))
      weighted[static_cast<std::size_t>(b)].noalias() += (m * wb) * y * ph.transpose();
    if (i < moved) pulled.segment<3>(3 * i) = frame.linear(n).transpose() * y;
  }
  gradient.head(offset_) += w * inertia_.pull_back_mass(pulled);
  for (std::size_t b = 0; b < frame.bones.size(); ++b) {
    const BoneDeviation& bone = frame.bones[b];
    for (std::size_t k = 0; k < bone.coordinates.size(); ++k)
      gradient[offset_ + bone.coordinates[k]] += w * bone.first[k].cwiseProduct(weighted[b]).sum();
  }
  return gradient.allFinite();
}

bool RootInertiaTerm::add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const {
  const DeviationFrame frame = skeleton_.frame(x, offset_, pose_.pivot, pose_.centres, true);
  meshing::RowMatrixX3d p;
  gather(x, p);
  const double w = 1.0 / (h_eff_ * h_eff_);
  const auto moved = static_cast<Eigen::Index>(inertia_.inertia_nodes().size());
  const Eigen::Index size = frame.size;
  const auto bones = frame.bones.size();
  hessian.topLeftCorner(offset_, offset_) += mass_hessian_;  // JᵀMJ/ĥ²; blended nodes add Jᵀ M (LᵀL − I) J below
  // The deviation block Σ m (∂y/∂r)ᵀ(∂y/∂r) + m yᵀ∂²y/∂r²: both affine in [p; 1] per bone, so they are summed as
  // moments per bone pair, S_bc = Σ m ω_b ω_c [p; 1][p; 1]ᵀ, and per bone, W_b = Σ m ω_b y [p; 1]ᵀ.
  std::vector<Eigen::Matrix4d> moments(bones * bones, Eigen::Matrix4d::Zero());
  std::vector<char> touched(bones * bones, 0);
  std::vector<Matrix34d> weighted(bones, Matrix34d::Zero());
  // The q × r block, Σ_i m B_iᵀ A_iᵀ ∂(Lᵀy)/∂r with ∂(Lᵀy)/∂r_k = ∂_kLᵀ y + Lᵀ ∂y/∂r_k, accumulated node by node over
  // the coordinates the node depends on (its bones' chains).
  Eigen::MatrixXd mixed = Eigen::MatrixXd::Zero(offset_, size);
  std::vector<int> slot(static_cast<std::size_t>(size), -1);
  std::vector<int> coordinates;
  Eigen::Matrix<double, 3, Eigen::Dynamic> field(3, size);
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    const int n = node(i);
    const double m = mass_[static_cast<std::size_t>(i)];
    const Eigen::Vector3d pi = p.row(i).transpose();
    const Eigen::Vector4d ph(pi.x(), pi.y(), pi.z(), 1.0);
    const Eigen::Vector3d y = frame.apply(n, pi) - target_.row(i).transpose();
    const JointBlend& blend = frame.blend(n);
    const Eigen::Matrix4d outer = m * ph * ph.transpose();
    for (const auto& [b, wb] : blend) {
      weighted[static_cast<std::size_t>(b)].noalias() += (m * wb) * y * ph.transpose();
      for (const auto& [c, wc] : blend) {
        const std::size_t bc = static_cast<std::size_t>(b) * bones + static_cast<std::size_t>(c);
        moments[bc] += (wb * wc) * outer;
        touched[bc] = 1;
      }
    }
    if (i >= moved || m == 0.0) continue;
    const Eigen::Matrix3d L = frame.linear(n);
    coordinates.clear();
    for (const auto& [b, wb] : blend) {
      const BoneDeviation& bone = frame.bones[static_cast<std::size_t>(b)];
      for (std::size_t k = 0; k < bone.coordinates.size(); ++k) {
        const int c = bone.coordinates[k];
        int& at = slot[static_cast<std::size_t>(c)];
        if (at < 0) {
          at = static_cast<int>(coordinates.size());
          coordinates.push_back(c);
          field.col(at).setZero();
        }
        const Matrix34d& d = bone.first[k];
        field.col(at).noalias() += wb * (d.leftCols<3>().transpose() * y + L.transpose() * (d * ph));
      }
    }
    const auto count = static_cast<Eigen::Index>(coordinates.size());
    const Eigen::Matrix3d& A = inertia_.frame().A[static_cast<std::size_t>(i)];
    const Eigen::Matrix<double, 3, Eigen::Dynamic> pulled = (w * m) * A.transpose() * field.leftCols(count);
    for (SparseRowMatrix::InnerIterator si(subspace_.basis, n); si; ++si)
      for (Eigen::Index j = 0; j < count; ++j)
        mixed.block<3, 1>(3 * si.col(), coordinates[static_cast<std::size_t>(j)]) += si.value() * pulled.col(j);
    for (int c : coordinates) slot[static_cast<std::size_t>(c)] = -1;
    // Jᵀ M (LᵀL − I) J on a blended node (the blend of rotations is not one).
    const Eigen::Matrix3d excess = L.transpose() * L - Eigen::Matrix3d::Identity();
    if (excess.cwiseAbs().maxCoeff() < 1e-15) continue;
    const Eigen::Matrix3d block = (w * m) * A.transpose() * excess * A;
    for (SparseRowMatrix::InnerIterator si(subspace_.basis, n); si; ++si)
      for (SparseRowMatrix::InnerIterator ri(subspace_.basis, n); ri; ++ri)
        hessian.block<3, 3>(3 * si.col(), 3 * ri.col()) += si.value() * ri.value() * block;
  }
  Eigen::MatrixXd deviation = Eigen::MatrixXd::Zero(size, size);
  for (std::size_t b = 0; b < bones; ++b) {
    const BoneDeviation& bone = frame.bones[b];
    const std::size_t nb = bone.coordinates.size();
    for (std::size_t c = 0; c < bones; ++c) {
      if (!touched[b * bones + c]) continue;
      const BoneDeviation& other = frame.bones[c];
      const Eigen::Matrix4d& S = moments[b * bones + c];
      for (std::size_t k = 0; k < nb; ++k) {
        const Matrix34d FS = bone.first[k] * S;
        for (std::size_t l = 0; l < other.coordinates.size(); ++l)
          deviation(bone.coordinates[k], other.coordinates[l]) += FS.cwiseProduct(other.first[l]).sum();
      }
    }
    for (std::size_t k = 0; k < nb; ++k)
      for (std::size_t l = 0; l < nb; ++l)
        deviation(bone.coordinates[k], bone.coordinates[l]) += bone.second[k * nb + l].cwiseProduct(weighted[b]).sum();
  }
  hessian.block(0, offset_, offset_, size) += mixed;
  hessian.block(offset_, 0, size, offset_) += mixed.transpose();
  hessian.block(offset_, offset_, size, size) += w * deviation;
  return true;
}

void RootTrackingTerm::set_step(const Eigen::VectorXd& stiffness, const Eigen::VectorXd& damping,
                                const Eigen::VectorXd& previous, double h, const Eigen::VectorXd& limit,
                                const Eigen::VectorXd& limit_stiffness) {
  require(h > 0.0, "reduced: root tracking: step must be positive, got {}", h);
  require(stiffness.size() == size_ && damping.size() == size_ && previous.size() == size_,
          "reduced: root tracking: {} / {} / {} values for {} coordinates", stiffness.size(), damping.size(),
          previous.size(), size_);
  require(limit.size() == limit_stiffness.size() && (limit.size() == 0 || 6 + 3 * limit.size() == size_),
          "reduced: root tracking: {} joint limits for {} coordinates", limit.size(), size_);
  stiffness_ = stiffness;
  damping_rate_ = damping / h;
  previous_ = previous;
  limit_ = limit;
  limit_stiffness_ = limit_stiffness;
}

// ½ rᵀK r + 1/(2h)(r − r_n)ᵀD(r − r_n) + Σ_j ½ k_j max(0, |φ_j| − a_j)².
double RootTrackingTerm::value(const Eigen::VectorXd& x) const {
  const Eigen::VectorXd r = x.segment(offset_, size_), dr = r - previous_;
  double value = 0.5 * (r.cwiseProduct(stiffness_).dot(r) + dr.cwiseProduct(damping_rate_).dot(dr));
  for (Eigen::Index j = 0; j < limit_.size(); ++j) {
    const double over = r.segment<3>(6 + 3 * j).norm() - limit_[j];
    if (over > 0.0) value += 0.5 * limit_stiffness_[j] * over * over;
  }
  return value;
}

bool RootTrackingTerm::add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const {
  const Eigen::VectorXd r = x.segment(offset_, size_);
  gradient.segment(offset_, size_) += stiffness_.cwiseProduct(r) + damping_rate_.cwiseProduct(r - previous_);
  for (Eigen::Index j = 0; j < limit_.size(); ++j) {
    const Eigen::Vector3d phi = r.segment<3>(6 + 3 * j);
    const double n = phi.norm(), over = n - limit_[j];
    if (over > 0.0) gradient.segment<3>(offset_ + 6 + 3 * j) += limit_stiffness_[j] * over / n * phi;
  }
  return gradient.allFinite();
}

// The limit's Hessian k[(1 − a/n) I + (a/n) φφᵀ/n²] for n = |φ| > a.
bool RootTrackingTerm::add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const {
  hessian.block(offset_, offset_, size_, size_).diagonal() += stiffness_ + damping_rate_;
  for (Eigen::Index j = 0; j < limit_.size(); ++j) {
    const Eigen::Vector3d phi = x.segment<3>(offset_ + 6 + 3 * j);
    const double n = phi.norm();
    if (n <= limit_[j]) continue;
    const double ratio = limit_[j] / n;
    hessian.block<3, 3>(offset_ + 6 + 3 * j, offset_ + 6 + 3 * j) +=
        limit_stiffness_[j] * ((1.0 - ratio) * Eigen::Matrix3d::Identity() + ratio * phi * phi.transpose() / (n * n));
  }
  return true;
}

double RootPotentialTerm::value(const Eigen::VectorXd& x) const {
  const DeviationFrame frame = skeleton_.frame(x, offset_, pose_.pivot, pose_.centres, false);
  const double energy = potentials_.energy(x, inertia_, &frame);
  return std::isfinite(energy) ? energy : kInfinity;
}

bool RootPotentialTerm::add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const {
  const DeviationFrame frame = skeleton_.frame(x, offset_, pose_.pivot, pose_.centres, false);
  potentials_.add_gradient(x, inertia_, gradient, &frame);
  return gradient.allFinite();
}

bool RootPotentialTerm::add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const {
  const DeviationFrame frame = skeleton_.frame(x, offset_, pose_.pivot, pose_.centres, true);
  potentials_.add_hessian(x, inertia_, hessian, &frame);
  return true;
}

}  // namespace sflsh::reduced
