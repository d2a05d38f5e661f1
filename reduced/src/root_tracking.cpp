#include <sflsh/core/error.hpp>
#include <sflsh/reduced/root_tracking.hpp>

#include <cmath>
#include <limits>

namespace sflsh::reduced {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

}  // namespace

double HeadTerm::value(const Eigen::VectorXd& x) const { return inner_.value(x.head(size_)); }

void HeadTerm::add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const {
  Eigen::VectorXd head = Eigen::VectorXd::Zero(size_);
  inner_.add_gradient(x.head(size_), head);
  gradient.head(size_) += head;
}

void HeadTerm::add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const {
  Eigen::MatrixXd head = Eigen::MatrixXd::Zero(size_, size_);
  inner_.add_hessian(x.head(size_), head);
  hessian.topLeftCorner(size_, size_) += head;
}

RootInertiaTerm::RootInertiaTerm(const ReducedInertia& inertia, std::vector<double> carried_mass, Eigen::Index offset)
    : inertia_(inertia), carried_mass_(std::move(carried_mass)), offset_(offset) {
  require(inertia.mass_kind() == model::MassKind::lumped,
          "reduced: a tracking skeleton needs the lumped mass (mass = \"lumped\")");
}

void RootInertiaTerm::set_step(const Eigen::VectorXd& p_tilde, const Eigen::VectorXd& carried_tilde,
                               const meshing::RowMatrixX3d& carried_posed, const Eigen::Vector3d& pivot, double h_eff) {
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
  pivot_ = pivot;
  h_eff_ = h_eff;
}

void RootInertiaTerm::gather(const Eigen::VectorXd& x, meshing::RowMatrixX3d& p) const {
  meshing::RowMatrixX3d moved;
  inertia_.posed(Eigen::VectorXd(x.head(offset_)), moved);
  p.resize(moved.rows() + carried_posed_.rows(), 3);
  p.topRows(moved.rows()) = moved;
  p.bottomRows(carried_posed_.rows()) = carried_posed_;
}

// 1/(2ĥ²) Σ_i m_i |y_i|², y_i = R(p_i − c) + c + τ − p̃_i.
double RootInertiaTerm::value(const Eigen::VectorXd& x) const {
  if (!x.allFinite()) return kInfinity;
  const RootFrame frame = root_frame(x, offset_, pivot_);
  meshing::RowMatrixX3d p;
  gather(x, p);
  double sum = 0.0;
  for (Eigen::Index i = 0; i < p.rows(); ++i)
    sum += mass_[static_cast<std::size_t>(i)] *
           (frame.apply(p.row(i).transpose()) - target_.row(i).transpose()).squaredNorm();
  return 0.5 * sum / (h_eff_ * h_eff_);
}

void RootInertiaTerm::add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const {
  const RootFrame frame = root_frame(x, offset_, pivot_);
  meshing::RowMatrixX3d p;
  gather(x, p);
  const double w = 1.0 / (h_eff_ * h_eff_);
  const auto moved = static_cast<Eigen::Index>(inertia_.inertia_nodes().size());
  Eigen::VectorXd pulled(3 * moved);  // Rᵀy on the inertia nodes; pull_back_mass multiplies by m_i
  Vector6d root = Vector6d::Zero();
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    const Eigen::Vector3d d = p.row(i).transpose() - pivot_;
    const Eigen::Vector3d y = frame.apply(p.row(i).transpose()) - target_.row(i).transpose();
    const double m = mass_[static_cast<std::size_t>(i)];
    for (int k = 0; k < 3; ++k) root[k] += m * y.dot(frame.rotation.dR[static_cast<std::size_t>(k)] * d);
    root.tail<3>() += m * y;
    if (i < moved) pulled.segment<3>(3 * i) = frame.rotation.R.transpose() * y;
  }
  gradient.head(offset_) += w * inertia_.pull_back_mass(pulled);
  gradient.segment<6>(offset_) += w * root;
}

void RootInertiaTerm::add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const {
  const RootFrame frame = root_frame(x, offset_, pivot_);
  meshing::RowMatrixX3d p;
  gather(x, p);
  const double w = 1.0 / (h_eff_ * h_eff_);
  const auto moved = static_cast<Eigen::Index>(inertia_.inertia_nodes().size());
  hessian.topLeftCorner(offset_, offset_) += mass_hessian_;  // JᵀRᵀMRJ/ĥ² = JᵀMJ/ĥ² for a lumped M
  // Columns of the soft tissue × root block: ∂(Rᵀy_i)/∂r pulled back, per root coordinate.
  std::array<Eigen::VectorXd, 6> fields;
  for (auto& f : fields) f.resize(3 * moved);
  Eigen::Matrix<double, 6, 6> root = Eigen::Matrix<double, 6, 6>::Zero();
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    const Eigen::Vector3d d = p.row(i).transpose() - pivot_;
    const Eigen::Vector3d y = frame.apply(p.row(i).transpose()) - target_.row(i).transpose();
    const double m = mass_[static_cast<std::size_t>(i)];
    Eigen::Matrix<double, 3, 6> Jr;  // ∂y/∂(θ, τ)
    for (int k = 0; k < 3; ++k) Jr.col(k) = frame.rotation.dR[static_cast<std::size_t>(k)] * d;
    Jr.rightCols<3>().setIdentity();
    root.noalias() += m * Jr.transpose() * Jr;
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l)
        root(k, l) += m * y.dot(frame.rotation.d2R[static_cast<std::size_t>(k)][static_cast<std::size_t>(l)] * d);
    if (i < moved) {
      // ∂(Rᵀy)/∂θ_k = ∂_kRᵀ y + Rᵀ ∂_kR d,   ∂(Rᵀy)/∂τ = Rᵀ.
      for (int k = 0; k < 3; ++k) {
        const Eigen::Matrix3d& dR = frame.rotation.dR[static_cast<std::size_t>(k)];
        fields[static_cast<std::size_t>(k)].segment<3>(3 * i) =
            dR.transpose() * y + frame.rotation.R.transpose() * dR * d;
        fields[static_cast<std::size_t>(k + 3)].segment<3>(3 * i) = frame.rotation.R.row(k).transpose();
      }
    }
  }
  for (int c = 0; c < 6; ++c) {
    const Eigen::VectorXd column = w * inertia_.pull_back_mass(fields[static_cast<std::size_t>(c)]);
    hessian.col(offset_ + c).head(offset_) += column;
    hessian.row(offset_ + c).head(offset_) += column.transpose();
  }
  hessian.block<6, 6>(offset_, offset_) += w * root;
}

void RootTrackingTerm::set_step(const Vector6d& stiffness, const Vector6d& damping, const Vector6d& previous,
                                double h) {
  require(h > 0.0, "reduced: root tracking: step must be positive, got {}", h);
  stiffness_ = stiffness;
  damping_rate_ = damping / h;
  previous_ = previous;
}

// ½ rᵀK r + 1/(2h)(r − r_n)ᵀD(r − r_n).
double RootTrackingTerm::value(const Eigen::VectorXd& x) const {
  const Vector6d r = x.segment<6>(offset_), dr = r - previous_;
  return 0.5 * (r.cwiseProduct(stiffness_).dot(r) + dr.cwiseProduct(damping_rate_).dot(dr));
}

void RootTrackingTerm::add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const {
  const Vector6d r = x.segment<6>(offset_);
  gradient.segment<6>(offset_) += stiffness_.cwiseProduct(r) + damping_rate_.cwiseProduct(r - previous_);
}

void RootTrackingTerm::add_hessian(const Eigen::VectorXd&, Eigen::MatrixXd& hessian) const {
  hessian.block<6, 6>(offset_, offset_).diagonal() += stiffness_ + damping_rate_;
}

double RootPotentialTerm::value(const Eigen::VectorXd& x) const {
  const RootFrame frame = root_frame(x, offset_, pivot_);
  const double energy = potentials_.energy(x, inertia_, &frame);
  return std::isfinite(energy) ? energy : kInfinity;
}

void RootPotentialTerm::add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const {
  const RootFrame frame = root_frame(x, offset_, pivot_);
  potentials_.add_gradient(x, inertia_, gradient, &frame);
}

void RootPotentialTerm::add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const {
  const RootFrame frame = root_frame(x, offset_, pivot_);
  potentials_.add_hessian(x, inertia_, hessian, &frame);
}

}  // namespace sflsh::reduced
