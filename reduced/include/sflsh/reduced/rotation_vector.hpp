#pragma once
// The rotation of a rotation vector θ (Rodrigues) and its first and second derivatives:
//   R(θ) = I + a(s) K + b(s) K²,   K = [θ]×,   s = |θ|²,   a = sin|θ|/|θ|,   b = (1 − cos|θ|)/|θ|²,
// ∂R/∂θ_k and ∂²R/∂θ_k∂θ_l exactly (series in s near 0), for the root deviation of a tracking skeleton
// (root_tracking.hpp), whose Newton solve needs the Hessian of R(θ)(p − c).
#include <Eigen/Core>

#include <array>

namespace sflsh::reduced {

struct RotationVectorDerivatives {
  Eigen::Matrix3d R;
  std::array<Eigen::Matrix3d, 3> dR;                  ///< ∂R/∂θ_k
  std::array<std::array<Eigen::Matrix3d, 3>, 3> d2R;  ///< ∂²R/∂θ_k∂θ_l (symmetric in k, l)
};

/// R(θ) and its derivatives; exact to round-off for |θ| < π.
RotationVectorDerivatives rotation_vector_derivatives(const Eigen::Vector3d& theta);

/// R(θ) alone.
Eigen::Matrix3d rotation_of_vector(const Eigen::Vector3d& theta);

}  // namespace sflsh::reduced
