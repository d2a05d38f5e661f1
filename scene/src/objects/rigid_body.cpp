// Mass properties and rotation algebra of free rigid objects (rigid_body.hpp).
#include <sflsh/core/error.hpp>
#include <sflsh/scene/rigid_body.hpp>

#include <cmath>
#include <numbers>

namespace sflsh::scene {

RigidProperties RigidProperties::with_mass(double m) const {
  require(std::isfinite(m) && m > 0.0 && mass > 0.0, "rigid object: mass must be positive (got {} kg)", m);
  RigidProperties p = *this;
  p.second_moment *= m / mass;
  p.mass = m;
  return p;
}

RigidProperties sphere_properties(double radius, double density) {
  require(std::isfinite(radius) && radius > 0.0, "sphere: radius must be positive (got {} m)", radius);
  require(std::isfinite(density) && density > 0.0, "sphere: density must be positive (got {} kg/m³)", density);
  RigidProperties p;
  p.volume = 4.0 / 3.0 * std::numbers::pi * radius * radius * radius;  // V = 4/3 π r³
  p.area = 4.0 * std::numbers::pi * radius * radius;
  p.mass = density * p.volume;
  p.second_moment = Eigen::Matrix3d::Identity() * (p.mass * radius * radius / 5.0);  // J = m r²/5 Id
  return p;
}

RigidProperties box_properties(const Eigen::Vector3d& half_extent, double density) {
  require(half_extent.allFinite() && half_extent.minCoeff() > 0.0, "box: half extents must be positive");
  require(std::isfinite(density) && density > 0.0, "box: density must be positive (got {} kg/m³)", density);
  RigidProperties p;
  const Eigen::Vector3d& a = half_extent;
  p.volume = 8.0 * a.x() * a.y() * a.z();
  p.area = 8.0 * (a.x() * a.y() + a.y() * a.z() + a.z() * a.x());
  p.mass = density * p.volume;
  p.second_moment = (p.mass / 3.0 * a.cwiseProduct(a)).asDiagonal();  // J_ii = m a_i²/3
  return p;
}

RigidProperties mesh_properties(const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& vertices,
                                const Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>& triangles, double density,
                                Eigen::Vector3d& centre) {
  require(std::isfinite(density) && density > 0.0, "mesh: density must be positive (got {} kg/m³)", density);
  double volume = 0.0, area = 0.0;
  Eigen::Vector3d first = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();  // ∫ q qᵀ dV about the mesh's origin
  for (Eigen::Index f = 0; f < triangles.rows(); ++f) {
    const Eigen::Vector3d a = vertices.row(triangles(f, 0)).transpose(), b = vertices.row(triangles(f, 1)).transpose(),
                          c = vertices.row(triangles(f, 2)).transpose();
    const double det = a.dot(b.cross(c));  // 6 × the signed volume of (origin, a, b, c)
    const Eigen::Vector3d sum = a + b + c;
    volume += det / 6.0;
    first += det / 24.0 * sum;
    second += det / 120.0 * (a * a.transpose() + b * b.transpose() + c * c.transpose() + sum * sum.transpose());
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  require(std::isfinite(volume) && volume > 0.0,
          "mesh: the enclosed volume is {} m³, expected a closed, outward-oriented surface", volume);
  RigidProperties p;
  p.volume = volume;
  p.area = area;
  p.mass = density * volume;
  centre = first / volume;
  p.second_moment = density * second - p.mass * centre * centre.transpose();  // parallel axes: J_c = J_o − m c cᵀ
  return p;
}

RigidProperties capsule_properties(double radius, double half_length, double density) {
  require(std::isfinite(radius) && radius > 0.0, "capsule: radius must be positive (got {} m)", radius);
  require(std::isfinite(half_length) && half_length >= 0.0, "capsule: length must be ≥ 0 (got {} m)", 2 * half_length);
  require(std::isfinite(density) && density > 0.0, "capsule: density must be positive (got {} kg/m³)", density);
  const double r = radius, L = half_length, pi = std::numbers::pi;
  const double cylinder = density * pi * r * r * 2.0 * L;    // m_c = ρ π r² 2L
  const double ball = density * 4.0 / 3.0 * pi * r * r * r;  // the two hemispheres together
  RigidProperties p;
  p.mass = cylinder + ball;
  p.volume = p.mass / density;
  p.area = 2.0 * pi * r * 2.0 * L + 4.0 * pi * r * r;
  const double transverse = cylinder * r * r / 4.0 + ball * r * r / 5.0;  // ∫ρ x² = ∫ρ y²
  // ∫ρ z²: cylinder m_c L²/3; hemispheres shifted by ±L: m_s (r²/5 + 3 L r / 4 + L²) (∫z over a half ball = 3r/8 m_h).
  const double axial = cylinder * L * L / 3.0 + ball * (r * r / 5.0 + 0.75 * L * r + L * L);
  p.second_moment = Eigen::Vector3d(transverse, transverse, axial).asDiagonal();
  return p;
}

Eigen::Matrix3d hat(const Eigen::Vector3d& a) {
  Eigen::Matrix3d m;
  m << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return m;
}

Eigen::Matrix3d rotation_exp(const Eigen::Vector3d& theta) {
  const double t = theta.norm();
  if (t < 1e-12) return Eigen::Matrix3d::Identity() + hat(theta);
  return Eigen::AngleAxisd(t, theta / t).toRotationMatrix();
}

Eigen::Vector3d rotation_log(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

Eigen::Matrix3d left_jacobian(const Eigen::Vector3d& theta) {
  const double t = theta.norm();
  const Eigen::Matrix3d K = hat(theta);
  if (t < 1e-6) return Eigen::Matrix3d::Identity() + 0.5 * K + K * K / 6.0;  // series to O(t²)
  return Eigen::Matrix3d::Identity() + (1.0 - std::cos(t)) / (t * t) * K + (t - std::sin(t)) / (t * t * t) * K * K;
}

double kinetic_energy(const RigidProperties& properties, const RigidState& state) {
  const Eigen::Matrix3d& R = state.placement.R;
  const Eigen::Vector3d& w = state.angular_velocity;
  // T = ½ m |v|² + ½ ωᵀ R I Rᵀ ω
  return 0.5 * properties.mass * state.velocity.squaredNorm() +
         0.5 * w.dot(R * properties.inertia() * R.transpose() * w);
}

}  // namespace sflsh::scene
