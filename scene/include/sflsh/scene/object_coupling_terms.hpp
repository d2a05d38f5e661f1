#pragma once
// The energies of a free rigid object inside a body's Newton solve (docs/contact.md "One solve for objects and
// body"), with exact derivatives at any increment y = (Δx, θ) of the object's placement over the substep:
//   x(y) = x_0 + Δx,   R(y) = R(θ) R_0   (R(θ) = exp([θ]×), reduced/rotation_vector.hpp),
// because the body's solver does not re-base its unknowns between iterations as the object's own solver does
// (rigid_terms.hpp). Each has a finite-difference test (tests/scene/test_object_coupling_terms.cpp):
//   object_inertia    m/(2h²)|x − x̃|² − m g·x + 1/(2h²) tr((R − R̃) J (R − R̃)ᵀ)      (rigid_terms.hpp's Φ_I)
//   sample_penalty    ½ k (δ − φ_j(R s + x) + ρ)²: a sample of the object against an obstacle
//   point_penalty     ½ k (δ − φ(Rᵀ(p − x)))²: a point p of the skin against the object's shape, in (p, y)
//   point_friction    μ λ f0(|P u|), u = (R ℓ + x) − (R_0 ℓ + x_0) − (p − p_0): lagged smoothed Coulomb friction
//                     between the object's material point ℓ and the skin point p (IPC, Li et al. 2020)
// Gradients [N, N·m] and Hessians (exact; point_* project theirs to PSD with `project`) are added to, not set.
#include <sflsh/reduced/rotation_vector.hpp>
#include <sflsh/scene/obstacle.hpp>
#include <sflsh/scene/rigid_body.hpp>
#include <sflsh/scene/rigid_terms.hpp>

#include <Eigen/Core>

#include <array>

namespace sflsh::scene {

using Vector9d = Eigen::Matrix<double, 9, 1>;
using Matrix9d = Eigen::Matrix<double, 9, 9>;

/// The object's placement at y from `start`, with ∂R/∂θ_k and ∂²R/∂θ_k∂θ_l (R_0 applied).
struct ObjectFrame {
  ObjectFrame(const RigidPlacement& start, const Vector6d& y);
  RigidPlacement start;
  Eigen::Vector3d x;
  Eigen::Matrix3d R;
  std::array<Eigen::Matrix3d, 3> dR;
  std::array<std::array<Eigen::Matrix3d, 3>, 3> d2R;
  RigidPlacement placement() const { return {x, R}; }
  /// ∂(R ℓ + x)/∂y (3×6) of the material point ℓ.
  Eigen::Matrix<double, 3, 6> point_jacobian(const Eigen::Vector3d& l) const;
  /// Σ_m g_m ∂²(R ℓ + x)_m/∂θ∂θ (the θθ block; the rest is zero).
  Eigen::Matrix3d point_curvature(const Eigen::Vector3d& l, const Eigen::Vector3d& g) const;
};

/// The nearest positive semi-definite matrix (negative eigenvalues clamped to zero).
template <int N>
void project_psd(Eigen::Matrix<double, N, N>& H);

double object_inertia(const RigidProperties& properties, const RigidState& start, double h,
                      const Eigen::Vector3d& gravity, const ObjectFrame& frame, Vector6d* gradient, Matrix6d* hessian);

/// φ_j − ρ of the sample at the frame [m] (with the world normal when asked), and its penalty.
double sample_gap(const Obstacle& obstacle, const RigidSample& sample, const ObjectFrame& frame,
                  Eigen::Vector3d* normal = nullptr);
double sample_penalty(const Obstacle& obstacle, const RigidSample& sample, double margin, const ObjectFrame& frame,
                      Vector6d* gradient, Matrix6d* hessian);

/// What point_penalty measured: φ [m], the outward normal (world) and the closest point on the shape in the
/// object's frame [m].
struct PointGap {
  double phi = 0.0;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  Eigen::Vector3d local_closest = Eigen::Vector3d::Zero();
};
/// `shape` in its local frame (its own pose ignored); variables (p, Δx, θ).
PointGap point_gap(const Obstacle& shape, const Eigen::Vector3d& p, const ObjectFrame& frame);
double point_penalty(const Obstacle& shape, const Eigen::Vector3d& p, double stiffness, double margin,
                     const ObjectFrame& frame, Vector9d* gradient, Matrix9d* hessian, bool project = true);

/// Lagged friction contact: c.point = ℓ (object frame), c.normal, c.normal_force = λ; p_0 = the skin point at the
/// substep's start (c.other_displacement unused: the skin's motion is p − p_0). ε = ε_v h [m].
double point_friction(const FrictionContact& c, const Eigen::Vector3d& p, const Eigen::Vector3d& p_start,
                      double coefficient, double epsilon, const ObjectFrame& frame, Vector9d* gradient,
                      Matrix9d* hessian, bool project = true);

}  // namespace sflsh::scene
