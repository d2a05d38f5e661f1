#pragma once
// Free rigid objects with six degrees of freedom: mass properties from the shape and a density, the state
// (centre of mass x, rotation R, velocity v, angular velocity ω in the world) and the rotation algebra the
// implicit step needs. The object's local origin is its centre of mass; the rotation is updated on SO(3),
// R ← exp([θ]×) R, so it stays a proper rotation (docs/contact.md, "Free rigid objects").
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sflsh::scene {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Mass [kg], the second moment J = ∫ρ q qᵀ dV [kg·m²] (local frame, about the centre of mass), the
/// inertia tensor I = tr(J)·Id − J [kg·m²], volume [m³] and surface area [m²] of a shape.
struct RigidProperties {
  double mass = 0.0;
  Eigen::Matrix3d second_moment = Eigen::Matrix3d::Zero();
  double volume = 0.0;
  double area = 0.0;
  Eigen::Matrix3d inertia() const { return second_moment.trace() * Eigen::Matrix3d::Identity() - second_moment; }
  /// The same shape with mass m [kg] (density m / volume).
  RigidProperties with_mass(double m) const;
};

/// Ball of radius r [m], density ρ [kg/m³]: m = ρ 4/3 π r³, J = m r²/5 · Id.
RigidProperties sphere_properties(double radius, double density);
/// Box of half extents a [m]: m = 8ρ a_x a_y a_z, J = diag(m a_i²/3).
RigidProperties box_properties(const Eigen::Vector3d& half_extent, double density);
/// Capsule about the local z axis (segment ±half_length, radius r): a cylinder and two hemispheres.
RigidProperties capsule_properties(double radius, double half_length, double density);
/// A closed, outward-oriented triangle mesh (vertices V×3 [m], triangles F×3) of uniform density, by the
/// divergence theorem over the tetrahedra (origin, a, b, c) of its triangles: V = Σ det/6, the first moment
/// Σ det/24 (a + b + c), ∫ q qᵀ = Σ det/120 (a aᵀ + b bᵀ + c cᵀ + s sᵀ) with s = a + b + c. J is about the
/// centre of mass, which `centre` receives [m] (in the mesh's frame). Throws sflsh::Error when the enclosed
/// volume is not positive (an open or inward mesh).
RigidProperties mesh_properties(const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& vertices,
                                const Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>& triangles, double density,
                                Eigen::Vector3d& centre);

/// [a]× with [a]× b = a × b.
Eigen::Matrix3d hat(const Eigen::Vector3d& a);
/// exp([θ]×) (Rodrigues).
Eigen::Matrix3d rotation_exp(const Eigen::Vector3d& theta);
/// θ with exp([θ]×) = R, |θ| ≤ π.
Eigen::Vector3d rotation_log(const Eigen::Matrix3d& R);
/// The left Jacobian of SO(3): d/dε exp([θ + ε]×) = [J_l(θ) ε]× exp([θ]×) to first order.
///   J_l = Id + (1 − cos t)/t² [θ]× + (t − sin t)/t³ [θ]×²,  t = |θ|.
Eigen::Matrix3d left_jacobian(const Eigen::Vector3d& theta);

/// The placement of an object during a solve: centre of mass x [m] and rotation R (local → world).
struct RigidPlacement {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d to_world(const Eigen::Vector3d& q) const { return R * q + x; }
  /// The placement moved by z = (Δx, θ): x + Δx, exp([θ]×) R (the increment Newton solves for).
  RigidPlacement moved(const Vector6d& z) const { return {x + z.head<3>(), rotation_exp(z.tail<3>()) * R}; }
};

/// The state of a free object at a time: placement and velocities [m/s], [rad/s] (world frame).
struct RigidState {
  RigidPlacement placement;
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();
};

/// Kinetic energy [J]: ½ m |v|² + ½ ωᵀ R I Rᵀ ω.
double kinetic_energy(const RigidProperties& properties, const RigidState& state);

}  // namespace sflsh::scene
