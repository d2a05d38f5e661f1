#pragma once
// Choosing the regularization weight λ from a leave-one-out sweep (SFLSH §6.2, Fig. 5). The paper takes the λ
// with the least cross-validation error (`sflsh validate` and `sflsh shapefit` share these rules); when the sweep is
// flat that picks a λ on noise. The one-standard-error rule (docs/fit.md, "Choosing λ") takes the largest λ whose mean
// error is within one standard error of the least.
#include <optional>
#include <string>
#include <vector>

namespace sflsh::reduced {

enum class LambdaRule {
  one_standard_error,  ///< largest λ with mean error ≤ least mean + its standard error (default)
  minimum,             ///< the λ with the least mean error (the paper's)
};

/// "one-se" / "one-standard-error" or "min" / "minimum"; throws naming `what` otherwise.
LambdaRule parse_lambda_rule(const std::string& text, const std::string& what);
std::string lambda_rule_name(LambdaRule rule);  ///< "one-se" or "min"

/// One λ of the sweep: the cross-validation error of each left-out subject (the unit of the caller's error: mm of σ in
/// validate, normalized κ in shapefit; NaN: missing).
struct LambdaScore {
  double lambda = 0.0;
  std::vector<double> fold_errors;
};

struct LambdaChoice {
  double lambda = 0.0;              ///< chosen
  double least_lambda = 0.0;        ///< λ with the least mean error
  double least_error = 0.0;         ///< its mean error over folds
  double standard_error = 0.0;      ///< of that mean: sample standard deviation / √folds (0 with one fold)
  double threshold = 0.0;           ///< the largest mean error the rule accepts
  std::vector<double> mean_errors;  ///< per score, in the order given (NaN: no finite fold)
};

/// Mean of the finite entries; NaN for none.
double mean_of_finite(const std::vector<double>& values);
/// Standard error of the mean of the finite entries: sample standard deviation / √n; 0 for one entry, NaN for none.
double standard_error_of_mean(const std::vector<double>& values);

/// Where an automatic λ grid may grow to (`shapefit --lambdas auto`, validate's --lambda-extensions).
inline constexpr double kLambdaGridFloor = 1e-12;
inline constexpr double kLambdaGridCeiling = 1e12;
inline constexpr double kHalfDecade = 3.1622776601683795;  // √10

/// The next λ of a sweep whose least mean error lies at an end of its grid (scores in ascending λ, ≥ 2 of them; a λ
/// without a finite mean is never the least): half a decade below the smallest or above the largest, within
/// [floor, ceiling]; nothing when the least error is inside the grid (the curve rises on both sides: bracketed), at
/// an end already at its bound, when no λ has a finite error, or when the grid has fewer than two λs (one λ is a
/// fixed choice, not a sweep).
std::optional<double> lambda_beyond_grid(const std::vector<LambdaScore>& ascending, double floor = kLambdaGridFloor,
                                         double ceiling = kLambdaGridCeiling);
/// Whether the least mean error is inside the grid (scores in ascending λ).
bool lambda_sweep_bracketed(const std::vector<LambdaScore>& ascending);

/// Applies `rule` to a sweep. Folds with a non-finite error are left out of a λ's mean; a λ with none is never
/// chosen. Throws when no λ has a finite error, naming `what` (e.g. the regularizer).
LambdaChoice choose_lambda(const std::vector<LambdaScore>& sweep, LambdaRule rule, const std::string& what);

}  // namespace sflsh::reduced
