#pragma once
// Newton's method on a free rigid object's incremental potential Φ(x, R) = Σ terms (rigid_terms.hpp): the
// increment z = (Δx, θ) solves (∇²Φ)₊ z = −∇Φ with the Hessian projected to PSD, a backtracking line search
// keeps Φ decreasing, and the placement is re-based (R ← exp([θ]×) R) after every iteration.
#include <sflsh/scene/rigid_terms.hpp>

#include <string>
#include <vector>

namespace sflsh::scene {

struct RigidNewtonSettings {
  int max_iterations = 60;
  /// Converged when |Δx| + ℓ |θ| < tolerance [m] (ℓ: the object's radius of gyration).
  double tolerance = 1e-9;
  double length = 0.1;  ///< ℓ [m]
};

struct RigidNewtonResult {
  bool converged = false;
  int iterations = 0;
  double value = 0.0;   ///< Φ at the result [J]
  std::string failure;  ///< empty, or why it stopped (NaN/Inf, no descent, iteration limit)
};

/// Minimizes Σ terms from `placement` (updated in place; left at the last finite iterate on failure).
RigidNewtonResult minimize_rigid(const std::vector<const RigidTerm*>& terms, RigidPlacement& placement,
                                 const RigidNewtonSettings& settings = {});

}  // namespace sflsh::scene
