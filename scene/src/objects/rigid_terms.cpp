// The energies of a free rigid object's implicit step (rigid_terms.hpp).
#include <sflsh/core/error.hpp>
#include <sflsh/scene/rigid_terms.hpp>

#include <cmath>

namespace sflsh::scene {

namespace {

/// ½ (r gᵀ + g rᵀ) − (gᵀ r) Id: Σ_c g_c ∂²p_c/∂θ∂θ for p = exp([θ]×) r (or exp(−[θ]×) r) at θ = 0, since
/// the second-order part of both is ½ [θ]×² r.
Eigen::Matrix3d rotation_curvature(const Eigen::Vector3d& g, const Eigen::Vector3d& r) {
  return 0.5 * (r * g.transpose() + g * r.transpose()) - g.dot(r) * Eigen::Matrix3d::Identity();
}

/// Adds the derivatives of f(p) for a point attached to the object, p = R q + x (r = R q), given ∇f, ∇²f at p:
/// ∂p/∂z = [Id, −[r]×].
void add_attached_point(const Eigen::Vector3d& r, const Eigen::Vector3d& gp, const Eigen::Matrix3d& Hp,
                        Vector6d* gradient, Matrix6d* hessian) {
  if (gradient) {
    gradient->head<3>() += gp;
    gradient->tail<3>() += r.cross(gp);
  }
  if (hessian) {
    const Eigen::Matrix3d A = -hat(r);
    hessian->topLeftCorner<3, 3>() += Hp;
    hessian->topRightCorner<3, 3>() += Hp * A;
    hessian->bottomLeftCorner<3, 3>() += A.transpose() * Hp;
    hessian->bottomRightCorner<3, 3>() += A.transpose() * Hp * A + rotation_curvature(gp, r);
  }
}

/// The same for a world point p seen from the object's frame: moving the object by z is moving the point by
/// the inverse motion, p' = x + exp(−[θ]×)(p − x − Δx) (d = p − x): ∂p'/∂z = [−Id, [d]×].
void add_relative_point(const Eigen::Vector3d& d, const Eigen::Vector3d& gp, const Eigen::Matrix3d& Hp,
                        Vector6d* gradient, Matrix6d* hessian) {
  if (gradient) {
    gradient->head<3>() -= gp;
    gradient->tail<3>() += gp.cross(d);
  }
  if (hessian) {
    const Eigen::Matrix3d A = hat(d);
    // ∂²p'/∂θ_a∂Δx_b = e_a × e_b, so Σ_c g_c (e_a × e_b)_c = −[g]×_ab.
    const Eigen::Matrix3d cross = -hat(gp);
    hessian->topLeftCorner<3, 3>() += Hp;
    hessian->topRightCorner<3, 3>() += -Hp * A + cross.transpose();
    hessian->bottomLeftCorner<3, 3>() += -A.transpose() * Hp + cross;
    hessian->bottomRightCorner<3, 3>() += A.transpose() * Hp * A + rotation_curvature(gp, d);
  }
}

/// ½ k (δ − φ)² with its derivatives in p, given φ, ∇φ, ∇²φ at p; zero for φ ≥ δ.
double penalty(double k, double margin, double phi, const Eigen::Vector3d& n, const Eigen::Matrix3d& Hphi,
               Eigen::Vector3d& gp, Eigen::Matrix3d& Hp) {
  const double s = margin - phi;
  gp = -k * s * n;                          // ∇u = −k (δ − φ) ∇φ
  Hp = k * (n * n.transpose() - s * Hphi);  // ∇²u = k (∇φ∇φᵀ − (δ − φ) ∇²φ)
  return 0.5 * k * s * s;
}

}  // namespace

// ===  Inertia and gravity  ==================================================================

RigidInertiaTerm::RigidInertiaTerm(const RigidProperties& properties, const RigidState& start, double h,
                                   const Eigen::Vector3d& gravity)
    : properties_(properties), h_(h), gravity_(gravity) {
  require(std::isfinite(h) && h > 0.0, "rigid inertia: step must be positive (got {} s)", h);
  x_tilde_ = start.placement.x + h * start.velocity;                        // x̃ = x_n + h v_n
  R_tilde_ = rotation_exp(h * start.angular_velocity) * start.placement.R;  // R̃ = exp(h [ω_n]×) R_n
}

double RigidInertiaTerm::evaluate(const RigidPlacement& at, Vector6d* gradient, Matrix6d* hessian) const {
  const double m = properties_.mass, c = 1.0 / (h_ * h_);
  const Eigen::Matrix3d& J = properties_.second_moment;
  const Eigen::Vector3d dx = at.x - x_tilde_;
  const Eigen::Matrix3d D = at.R - R_tilde_;
  const double value =
      0.5 * m * c * dx.squaredNorm() - m * gravity_.dot(at.x) + 0.5 * c * (D * J * D.transpose()).trace();
  if (gradient || hessian) {
    const Eigen::Matrix3d M = at.R * J * D.transpose();
    Eigen::Matrix3d E[3];
    for (int a = 0; a < 3; ++a) E[a] = hat(Eigen::Vector3d::Unit(a));
    if (gradient) {
      gradient->head<3>() += m * c * dx - m * gravity_;
      for (int a = 0; a < 3; ++a) (*gradient)(3 + a) += c * (E[a] * M).trace();  // tr(∂R/∂θ_a J Dᵀ)
    }
    if (hessian) {
      hessian->topLeftCorner<3, 3>() += m * c * Eigen::Matrix3d::Identity();
      const Eigen::Matrix3d RJR = at.R * J * at.R.transpose();
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          (*hessian)(3 + a, 3 + b) +=
              c * ((E[a] * RJR * E[b].transpose()).trace() + 0.5 * ((E[a] * E[b] + E[b] * E[a]) * M).trace());
    }
  }
  return value;
}

// ===  Object samples against obstacles  =====================================================

RigidObstacleContactTerm::RigidObstacleContactTerm(std::vector<RigidSample> samples,
                                                   std::vector<const Obstacle*> obstacles, double margin)
    : samples_(std::move(samples)), obstacles_(std::move(obstacles)), margin_(margin) {
  require(std::isfinite(margin) && margin >= 0.0, "rigid contact: margin must be ≥ 0 (got {} m)", margin);
}

double RigidObstacleContactTerm::gap(const RigidPlacement& at, std::size_t s, std::size_t j,
                                     Eigen::Vector3d* normal) const {
  const RigidSample& sample = samples_[s];
  return obstacles_[j]->distance(at.to_world(sample.point), normal) - sample.radius;
}

double RigidObstacleContactTerm::evaluate(const RigidPlacement& at, Vector6d* gradient, Matrix6d* hessian) const {
  double value = 0.0;
  for (const RigidSample& sample : samples_) {
    const Eigen::Vector3d r = at.R * sample.point;
    for (const Obstacle* obstacle : obstacles_) {
      Eigen::Vector3d n;
      Eigen::Matrix3d Hphi;
      const double phi = obstacle->distance(r + at.x, &n, &Hphi) - sample.radius;
      if (!(phi < margin_)) continue;
      Eigen::Vector3d gp;
      Eigen::Matrix3d Hp;
      value += penalty(sample.stiffness, margin_, phi, n, Hphi, gp, Hp);
      add_attached_point(r, gp, Hp, gradient, hessian);
    }
  }
  return value;
}

// ===  Other surfaces' points against the object  ===========================================

ObjectSurfaceContactTerm::ObjectSurfaceContactTerm(const Obstacle& shape, std::vector<Eigen::Vector3d> points,
                                                   std::vector<double> stiffness, double margin)
    : shape_(shape), points_(std::move(points)), stiffness_(std::move(stiffness)), margin_(margin) {
  require(points_.size() == stiffness_.size(), "object contact: {} points but {} stiffnesses", points_.size(),
          stiffness_.size());
}

double ObjectSurfaceContactTerm::gap(const RigidPlacement& at, std::size_t i, Eigen::Vector3d* normal) const {
  Eigen::Vector3d n;
  const double phi = shape_.local_distance(at.R.transpose() * (points_[i] - at.x), &n, nullptr);
  if (normal) *normal = at.R * n;
  return phi;
}

double ObjectSurfaceContactTerm::evaluate(const RigidPlacement& at, Vector6d* gradient, Matrix6d* hessian) const {
  double value = 0.0;
  for (std::size_t i = 0; i < points_.size(); ++i) {
    const Eigen::Vector3d d = points_[i] - at.x;
    Eigen::Vector3d n;
    Eigen::Matrix3d Hphi;
    const double phi = shape_.local_distance(at.R.transpose() * d, &n, &Hphi);
    if (!(phi < margin_)) continue;
    // World derivatives of φ at the point with the object at `at`: ∇φ = R n, ∇²φ = R H Rᵀ.
    Eigen::Vector3d gp;
    Eigen::Matrix3d Hp;
    value += penalty(stiffness_[i], margin_, phi, at.R * n, at.R * Hphi * at.R.transpose(), gp, Hp);
    add_relative_point(d, gp, Hp, gradient, hessian);
  }
  return value;
}

// ===  Friction  =============================================================================

RigidFrictionTerm::RigidFrictionTerm(std::vector<FrictionContact> contacts, const RigidPlacement& start,
                                     double coefficient, double smoothing_length)
    : contacts_(std::move(contacts)), start_(start), coefficient_(coefficient), epsilon_(smoothing_length) {
  require(std::isfinite(coefficient) && coefficient >= 0.0, "friction: coefficient must be ≥ 0 (got {})", coefficient);
  require(std::isfinite(smoothing_length) && smoothing_length > 0.0,
          "friction: smoothing length must be positive (got {} m)", smoothing_length);
}

double smoothed_slip(double scale, double epsilon, const Eigen::Vector3d& normal, const Eigen::Vector3d& u,
                     Eigen::Vector3d& w, double* value, Eigen::Matrix3d* hessian) {
  const double eps = epsilon;
  const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - normal * normal.transpose();
  w = P * u;  // tangential slip over the step
  const double y = w.norm();
  double f1_over_y;
  if (y < eps) {
    if (value) *value = scale * (-y * y * y / (3.0 * eps * eps) + y * y / eps + eps / 3.0);  // f0(y)
    f1_over_y = 2.0 / eps - y / eps / eps;                                                   // f0'(y)/y
    // ∇² = μλ [(f1/y) P + (f0'' − f1/y) ŵŵᵀ], f0'' − f1/y = −y/ε², so −w wᵀ/(ε² y).
    if (hessian) {
      *hessian = f1_over_y * P;
      if (y > 0.0) *hessian -= w * w.transpose() / (eps * eps * y);
    }
  } else {
    if (value) *value = scale * y;
    f1_over_y = 1.0 / y;
    if (hessian) *hessian = (P - w * w.transpose() / (y * y)) / y;
  }
  if (hessian) *hessian *= scale;
  return scale * f1_over_y;
}

double RigidFrictionTerm::slip(const FrictionContact& c, const RigidPlacement& at, Eigen::Vector3d& w, double* f0,
                               Eigen::Matrix3d* Hp) const {
  const double scale = coefficient_ * c.normal_force;  // μ λ [N]
  const Eigen::Vector3d u = (at.R * c.point + at.x) - start_.to_world(c.point) - c.other_displacement;
  const double g = smoothed_slip(scale, epsilon_, c.normal, u, w, f0, Hp);
  if (f0 && scale > 0.0) *f0 /= scale;
  return g;
}

double RigidFrictionTerm::evaluate(const RigidPlacement& at, Vector6d* gradient, Matrix6d* hessian) const {
  double value = 0.0;
  for (const FrictionContact& c : contacts_) {
    const double scale = coefficient_ * c.normal_force;  // μ λ [N]
    if (!(scale > 0.0)) continue;
    Eigen::Vector3d w;
    double f0 = 0.0;
    Eigen::Matrix3d Hp;
    const double g = slip(c, at, w, &f0, &Hp);
    value += scale * f0;
    add_attached_point(at.R * c.point, g * w, Hp, gradient, hessian);
  }
  return value;
}

std::vector<Eigen::Vector3d> RigidFrictionTerm::forces(const RigidPlacement& at) const {
  std::vector<Eigen::Vector3d> out(contacts_.size(), Eigen::Vector3d::Zero());
  for (std::size_t k = 0; k < contacts_.size(); ++k) {
    if (!(coefficient_ * contacts_[k].normal_force > 0.0)) continue;
    Eigen::Vector3d w;
    out[k] = -slip(contacts_[k], at, w, nullptr, nullptr) * w;  // F = −∂D/∂x at the contact
  }
  return out;
}

double evaluate_terms(const std::vector<const RigidTerm*>& terms, const RigidPlacement& at, Vector6d* gradient,
                      Matrix6d* hessian) {
  double value = 0.0;
  for (const RigidTerm* term : terms) value += term->evaluate(at, gradient, hessian);
  return value;
}

}  // namespace sflsh::scene
