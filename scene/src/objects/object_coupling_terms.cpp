// The energies of a free rigid object inside a body's Newton solve (object_coupling_terms.hpp).
#include <sflsh/scene/object_coupling_terms.hpp>

#include <Eigen/Eigenvalues>

namespace sflsh::scene {

ObjectFrame::ObjectFrame(const RigidPlacement& start_placement, const Vector6d& y)
    : start(start_placement), x(start_placement.x + y.head<3>()) {
  const reduced::RotationVectorDerivatives r = reduced::rotation_vector_derivatives(y.tail<3>());
  R = r.R * start.R;
  for (std::size_t k = 0; k < 3; ++k) {
    dR[k] = r.dR[k] * start.R;
    for (std::size_t l = 0; l < 3; ++l) d2R[k][l] = r.d2R[k][l] * start.R;
  }
}

Eigen::Matrix<double, 3, 6> ObjectFrame::point_jacobian(const Eigen::Vector3d& l) const {
  Eigen::Matrix<double, 3, 6> J;
  J.leftCols<3>().setIdentity();
  for (int k = 0; k < 3; ++k) J.col(3 + k) = dR[static_cast<std::size_t>(k)] * l;
  return J;
}

Eigen::Matrix3d ObjectFrame::point_curvature(const Eigen::Vector3d& l, const Eigen::Vector3d& g) const {
  Eigen::Matrix3d C;
  for (int k = 0; k < 3; ++k)
    for (int m = 0; m < 3; ++m) C(k, m) = g.dot(d2R[static_cast<std::size_t>(k)][static_cast<std::size_t>(m)] * l);
  return C;
}

template <int N>
void project_psd(Eigen::Matrix<double, N, N>& H) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eig(0.5 * (H + H.transpose()));
  const Eigen::Matrix<double, N, 1> values = eig.eigenvalues().cwiseMax(0.0);
  H = eig.eigenvectors() * values.asDiagonal() * eig.eigenvectors().transpose();
}
template void project_psd<6>(Matrix6d&);
template void project_psd<9>(Matrix9d&);

double object_inertia(const RigidProperties& properties, const RigidState& start, double h,
                      const Eigen::Vector3d& gravity, const ObjectFrame& frame, Vector6d* gradient, Matrix6d* hessian) {
  const double m = properties.mass, inv_h2 = 1.0 / (h * h);
  const Eigen::Vector3d x_tilde = start.placement.x + h * start.velocity;
  const Eigen::Matrix3d R_tilde = rotation_exp(h * start.angular_velocity) * start.placement.R;
  const Eigen::Matrix3d& J = properties.second_moment;
  const Eigen::Vector3d dx = frame.x - x_tilde;
  const Eigen::Matrix3d dR = frame.R - R_tilde;
  // Φ_I = m/(2h²)|x − x̃|² − m g·x + 1/(2h²) tr(ΔR J ΔRᵀ)
  const double value =
      0.5 * m * inv_h2 * dx.squaredNorm() - m * gravity.dot(frame.x) + 0.5 * inv_h2 * (dR * J * dR.transpose()).trace();
  if (gradient) {
    gradient->head<3>() += m * inv_h2 * dx - m * gravity;
    const Eigen::Matrix3d JdRt = J * dR.transpose();
    for (int k = 0; k < 3; ++k) (*gradient)[3 + k] += inv_h2 * (frame.dR[static_cast<std::size_t>(k)] * JdRt).trace();
  }
  if (hessian) {
    hessian->topLeftCorner<3, 3>() += m * inv_h2 * Eigen::Matrix3d::Identity();
    const Eigen::Matrix3d JdRt = J * dR.transpose();
    for (std::size_t k = 0; k < 3; ++k)
      for (std::size_t l = 0; l < 3; ++l)
        (*hessian)(3 + static_cast<Eigen::Index>(k), 3 + static_cast<Eigen::Index>(l)) +=
            inv_h2 * ((frame.d2R[k][l] * JdRt).trace() + (frame.dR[k] * J * frame.dR[l].transpose()).trace());
  }
  return value;
}

double sample_gap(const Obstacle& obstacle, const RigidSample& sample, const ObjectFrame& frame,
                  Eigen::Vector3d* normal) {
  return obstacle.distance(frame.R * sample.point + frame.x, normal) - sample.radius;
}

double sample_penalty(const Obstacle& obstacle, const RigidSample& sample, double margin, const ObjectFrame& frame,
                      Vector6d* gradient, Matrix6d* hessian) {
  Eigen::Vector3d n;
  Eigen::Matrix3d H;
  const double phi = obstacle.distance(frame.R * sample.point + frame.x, &n, hessian ? &H : nullptr) - sample.radius;
  const double s = margin - phi;
  if (s <= 0.0) return 0.0;
  const double k = sample.stiffness;
  const Eigen::Vector3d gw = -k * s * n;  // ∇_w u = −k (δ − φ) ∇φ
  const Eigen::Matrix<double, 3, 6> J = frame.point_jacobian(sample.point);
  if (gradient) *gradient += J.transpose() * gw;
  if (hessian) {
    const Eigen::Matrix3d Hw = k * (n * n.transpose() - s * H);
    *hessian += J.transpose() * Hw * J;
    hessian->bottomRightCorner<3, 3>() += frame.point_curvature(sample.point, gw);
  }
  return 0.5 * k * s * s;
}

namespace {

/// φ of p in the object and its derivatives in v = (p, Δx, θ): ℓ = Rᵀ(p − x),
/// ∂ℓ/∂p = Rᵀ, ∂ℓ/∂Δx = −Rᵀ, ∂ℓ/∂θ_k = (∂_kR)ᵀ d (d = p − x); ∇²φ = J_ℓᵀ ∇²φ_ℓ J_ℓ + Σ_m (∇φ_ℓ)_m ∇²ℓ_m.
double point_phi(const Obstacle& shape, const Eigen::Vector3d& p, const ObjectFrame& frame, Vector9d& grad,
                 Matrix9d* hess, Eigen::Vector3d* local = nullptr, Eigen::Vector3d* local_gradient = nullptr) {
  const Eigen::Vector3d d = p - frame.x;
  const Eigen::Vector3d l = frame.R.transpose() * d;
  Eigen::Vector3d gl;
  Eigen::Matrix3d Hl;
  const double phi = shape.local_distance(l, &gl, hess ? &Hl : nullptr);
  Eigen::Matrix<double, 3, 9> J;
  J.leftCols<3>() = frame.R.transpose();
  J.middleCols<3>(3) = -frame.R.transpose();
  for (int k = 0; k < 3; ++k) J.col(6 + k) = frame.dR[static_cast<std::size_t>(k)].transpose() * d;
  grad = J.transpose() * gl;
  if (hess) {
    *hess = J.transpose() * Hl * J;
    // Σ_m gl_m ∂²ℓ_m: (θ_k, θ_l): glᵀ (∂²_klR)ᵀ d; (p, θ_k): ∂_kR gl; (Δx, θ_k): −∂_kR gl.
    for (std::size_t k = 0; k < 3; ++k) {
      const Eigen::Vector3d a = frame.dR[k] * gl;
      const auto col = static_cast<Eigen::Index>(6 + k);
      hess->block<3, 1>(0, col) += a;
      hess->block<1, 3>(col, 0) += a.transpose();
      hess->block<3, 1>(3, col) -= a;
      hess->block<1, 3>(col, 3) -= a.transpose();
      for (std::size_t m = 0; m < 3; ++m)
        (*hess)(col, static_cast<Eigen::Index>(6 + m)) += gl.dot(frame.d2R[k][m].transpose() * d);
    }
  }
  if (local) *local = l;
  if (local_gradient) *local_gradient = gl;
  return phi;
}

}  // namespace

PointGap point_gap(const Obstacle& shape, const Eigen::Vector3d& p, const ObjectFrame& frame) {
  PointGap out;
  Vector9d grad;
  Eigen::Vector3d l, gl;
  out.phi = point_phi(shape, p, frame, grad, nullptr, &l, &gl);
  out.normal = frame.R * gl;             // outward from the object (world)
  out.local_closest = l - out.phi * gl;  // the foot point on the shape (exact distance, |∇φ| = 1)
  return out;
}

double point_penalty(const Obstacle& shape, const Eigen::Vector3d& p, double stiffness, double margin,
                     const ObjectFrame& frame, Vector9d* gradient, Matrix9d* hessian, bool project) {
  Vector9d grad;
  Matrix9d hess;
  const double phi = point_phi(shape, p, frame, grad, hessian ? &hess : nullptr);
  const double s = margin - phi;
  if (s <= 0.0) return 0.0;
  if (gradient) *gradient += -stiffness * s * grad;  // ∇u = −k (δ − φ) ∇φ
  if (hessian) {
    Matrix9d H = stiffness * (grad * grad.transpose() - s * hess);  // ∇²u = k (∇φ∇φᵀ − (δ − φ) ∇²φ)
    if (project) project_psd<9>(H);
    *hessian += H;
  }
  return 0.5 * stiffness * s * s;
}

double point_friction(const FrictionContact& c, const Eigen::Vector3d& p, const Eigen::Vector3d& p_start,
                      double coefficient, double epsilon, const ObjectFrame& frame, Vector9d* gradient,
                      Matrix9d* hessian, bool project) {
  const double scale = coefficient * c.normal_force;  // μ λ [N]
  if (!(scale > 0.0)) return 0.0;
  // u = (R ℓ + x) − (R_0 ℓ + x_0) − (p − p_0): ∂u/∂p = −Id, ∂u/∂y = the material point's Jacobian.
  const Eigen::Vector3d u = (frame.R * c.point + frame.x) - frame.start.to_world(c.point) - (p - p_start);
  Eigen::Vector3d w;
  double value = 0.0;
  Eigen::Matrix3d Hu;
  const double g = smoothed_slip(scale, epsilon, c.normal, u, w, &value, hessian ? &Hu : nullptr);
  const Eigen::Vector3d gu = g * w;  // ∇_u D
  Eigen::Matrix<double, 3, 9> J;
  J.leftCols<3>() = -Eigen::Matrix3d::Identity();
  J.rightCols<6>() = frame.point_jacobian(c.point);
  if (gradient) *gradient += J.transpose() * gu;
  if (hessian) {
    Matrix9d H = J.transpose() * Hu * J;
    H.bottomRightCorner<3, 3>() += frame.point_curvature(c.point, gu);
    if (project) project_psd<9>(H);
    *hessian += H;
  }
  return value;
}

}  // namespace sflsh::scene
