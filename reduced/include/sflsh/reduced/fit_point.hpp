#pragma once
// What a fit computed at its final point, kept so that the next fit of a λ continuation, warm-started there,
// does not simulate that point again: per target, σ of the plain run and the normal-equation terms of the
// differentiated run (a warm fit of 3 iterations evaluates 4 Jacobians; the first is this one).
// A reuse requires every input of the computation to match — the case, κ exactly, and for the terms also the
// parameterization, the thickness method, the residual weight and σ* — so it returns bit for bit what the
// simulation would; anything else is simulated as usual.
#include <sflsh/material/parameters.hpp>

#include <Eigen/Core>

#include <vector>

namespace sflsh::reduced {

class DynamicsCase;
class LayerParameterization;

struct FitPoint {
  struct Target {
    const DynamicsCase* simulation = nullptr;
    material::KappaMatrix kappa;  ///< the run's κ (N × 3: thickness [1], Y_t [Pa], Y_n [Pa])
    Eigen::VectorXd sigma;        ///< [σ_n; σ_t] of the plain run [mm]
    // The differentiated run's terms and what they depend on besides κ (empty terms: none recorded).
    const LayerParameterization* parameterization = nullptr;
    bool exact_thickness = false;
    double weight = 0.0;           ///< w of r_fit
    Eigen::VectorXd target_sigma;  ///< σ* the terms' residual used [mm]
    Eigen::VectorXd terms;         ///< w² G_tᵀG_t (Q × Q, column-major) then w G_tᵀ r_t (Q), Q = 3N
  };
  std::vector<Target> targets;

  /// σ of `simulation` at exactly κ, or null.
  const Eigen::VectorXd* sigma(const DynamicsCase* simulation, const material::KappaMatrix& kappa) const;
  /// The terms of `simulation` at exactly κ made with the same parameterization, thickness method, weight and σ*,
  /// or null.
  const Eigen::VectorXd* terms(const DynamicsCase* simulation, const material::KappaMatrix& kappa,
                               const LayerParameterization* parameterization, bool exact_thickness, double weight,
                               const Eigen::VectorXd& target_sigma) const;
};

}  // namespace sflsh::reduced
