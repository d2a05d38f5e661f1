// Newton's method for a free rigid object's step (rigid_solver.hpp).
#include <sflsh/scene/rigid_solver.hpp>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include <cmath>

namespace sflsh::scene {

RigidNewtonResult minimize_rigid(const std::vector<const RigidTerm*>& terms, RigidPlacement& placement,
                                 const RigidNewtonSettings& settings) {
  RigidNewtonResult result;
  for (int it = 0; it < settings.max_iterations; ++it) {
    Vector6d g = Vector6d::Zero();
    Matrix6d H = Matrix6d::Zero();
    const double value = evaluate_terms(terms, placement, &g, &H);
    result.value = value;
    result.iterations = it + 1;
    if (!std::isfinite(value) || !g.allFinite() || !H.allFinite()) {
      result.failure = fmt::format("NaN/Inf in the rigid object's energy at Newton iteration {}", it);
      return result;
    }
    // (∇²Φ)₊: negative eigenvalues (curved obstacles, rotations away from R̃) clamped to a small positive.
    const Eigen::SelfAdjointEigenSolver<Matrix6d> eigen(0.5 * (H + H.transpose()));
    const double floor = 1e-12 * std::max(1.0, eigen.eigenvalues().cwiseAbs().maxCoeff());
    const Vector6d lambda = eigen.eigenvalues().cwiseMax(floor);
    const Vector6d z = -eigen.eigenvectors() * (eigen.eigenvectors().transpose() * g).cwiseQuotient(lambda);
    const double step_size = z.head<3>().norm() + settings.length * z.tail<3>().norm();
    if (step_size < settings.tolerance) {
      placement = placement.moved(z);  // the last, tiny Newton step (quadratic convergence: error ~ |z|²)
      result.converged = true;
      return result;
    }
    // Backtracking (Armijo) on Φ along z.
    const double slope = g.dot(z);
    double alpha = 1.0;
    bool accepted = false;
    for (int k = 0; k < 40; ++k, alpha *= 0.5) {
      const RigidPlacement trial = placement.moved(alpha * z);
      const double v = evaluate_terms(terms, trial, nullptr, nullptr);
      if (std::isfinite(v) && v <= value + 1e-4 * alpha * slope) {
        placement = trial;
        accepted = true;
        break;
      }
    }
    if (!accepted) {
      // No decrease at round-off level: converged when the step is already tiny, else a failure.
      result.converged = step_size < 1e3 * settings.tolerance;
      if (!result.converged)
        result.failure = fmt::format("no descent at Newton iteration {} (|z| = {:.3g} m)", it, step_size);
      return result;
    }
    if (alpha * step_size < settings.tolerance) {
      result.converged = true;
      return result;
    }
  }
  result.failure = fmt::format("no convergence in {} Newton iterations", settings.max_iterations);
  return result;
}

}  // namespace sflsh::scene
