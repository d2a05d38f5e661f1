#pragma once
// The shape regression of SFLSH eqs. 1, 4 and 5 on its own, without simulation (`sflsh shapefit`): given the
// normalized material κ̂_s (N × 3, κ / κ_max) of S subjects of shape β_s at the same N control points, per control
// point i
//   min over A_i, b_i:  (1/S) Σ_s ‖A_iᵀ β_s + b_i − κ̂_si‖² + λ tr(A_iᵀ Q_i A_i)                  (eqs. 1, 5)
// with Q_i of eq. 4 (Regularizer::local), Q_i = I (l2) or no regularizer (none: the minimum-norm A_i where the
// subjects do not determine it). Averaged over the control points this is the loss
//   (1/N) Σ_i (1/S) Σ_s ‖κ̂_i(β_s) − κ̂_si‖² + λ (1/N) Σ_i tr(A_iᵀ Q_i A_i),
// whose regularizer is validate's ‖r_reg‖² (shape_elasticity.hpp, eq. 7), so λ means the same in both. b_i is not
// regularized: with centred shapes β̃_s = β_s − β̄ and κ̃_si = κ̂_si − κ̄_i, A_i = (G + λ Q_i)⁻¹ (1/S) Σ_s β̃_s κ̃_siᵀ
// with G = (1/S) Σ_s β̃_s β̃_sᵀ, and b_i = κ̄_i − A_iᵀ β̄ (docs/fit.md, "sflsh shapefit").
//
// λ comes from leave-one-subject-out cross-validation: per λ and left-out subject s, the model fitted on the
// others predicts κ̂_s(β_s); the fold's error is the RMS over the N × 3 entries (normalized units).
#include <sflsh/body/skinning.hpp>
#include <sflsh/material/parameters.hpp>
#include <sflsh/reduced/lambda_choice.hpp>
#include <sflsh/reduced/shape_elasticity.hpp>

#include <string>
#include <vector>

namespace sflsh::reduced {

/// The regression's data: S subjects at the same N control points.
struct ShapeRegressionData {
  std::vector<body::Betas> betas;            ///< β_s, one per subject
  std::vector<material::KappaMatrix> kappa;  ///< κ̂_s (N × 3, normalized: κ / κ_max), one per subject

  int num_subjects() const { return static_cast<int>(betas.size()); }
  int num_controls() const { return kappa.empty() ? 0 : static_cast<int>(kappa.front().rows()); }
};

/// The regularizer of the regression: its kind and, for `local`, Q_i per control point (layer_shape_metric).
struct ShapeRegularizer {
  Regularizer kind = Regularizer::local;
  std::vector<ShapeMetric> metric;  ///< Q_i (local only; N of them)
};

/// Throws unless the data hold ≥ 2 subjects, equal numbers of β and κ̂, the same N ≥ 1 for all, finite entries,
/// and the regularizer has N metrics when it is local.
void check_shape_regression(const ShapeRegressionData& data, const ShapeRegularizer& regularizer);

/// Fits (A_i, b_i) on the subjects `subjects` (indices into data; empty: all) with weight λ ≥ 0 (ignored for
/// Regularizer::none).
ShapeElasticity fit_shape_regression(const ShapeRegressionData& data, const ShapeRegularizer& regularizer,
                                     double lambda, const std::vector<int>& subjects = {});

/// RMS of κ̂(β) − κ̂ over the N × 3 entries (normalized units).
double shape_prediction_error(const ShapeElasticity& model, const body::Betas& beta,
                              const material::KappaMatrix& kappa);

/// λ = 10^(k/2), k = −12 … 12: half decades from 10⁻⁶ to 10⁶ (`--lambdas auto`).
std::vector<double> default_lambda_grid();

/// The leave-one-subject-out errors of one λ: fold s is the error on subject s of the fit on the others.
LambdaScore cross_validate_shape_regression(const ShapeRegressionData& data, const ShapeRegularizer& regularizer,
                                            double lambda);

struct ShapeLambdaSweep {
  std::vector<LambdaScore> scores;  ///< per λ, ascending
  LambdaChoice choice;              ///< the rule's λ (choice.mean_errors in the order of `scores`)
  bool bracketed = false;           ///< the mean error is higher at both ends of the grid than at its least λ
  int extensions = 0;               ///< half decades added to the grid to bracket the least error
};

/// Cross-validates every λ of `lambdas`. With `extend`, a grid whose least mean error lies at an end grows by half
/// decades on that side until the error rises on both sides of its least λ, or the grid reaches 10^±12 (then
/// `bracketed` stays false: the error keeps falling towards that end, e.g. data without shape signal as λ → ∞).
/// Regularizer::none has the one λ = 0. Throws when `lambdas` is empty or holds a negative or non-finite λ.
ShapeLambdaSweep sweep_shape_regression(const ShapeRegressionData& data, const ShapeRegularizer& regularizer,
                                        std::vector<double> lambdas, bool extend, LambdaRule rule);

}  // namespace sflsh::reduced
