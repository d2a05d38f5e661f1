#include <sflsh/core/error.hpp>
#include <sflsh/reduced/lambda_choice.hpp>

#include <cmath>
#include <limits>

namespace sflsh::reduced {

LambdaRule parse_lambda_rule(const std::string& text, const std::string& what) {
  if (text == "one-se" || text == "one-standard-error") return LambdaRule::one_standard_error;
  if (text == "min" || text == "minimum") return LambdaRule::minimum;
  throw_error("{}: unknown λ rule '{}' (expected one-se or min)", what, text);
}

std::string lambda_rule_name(LambdaRule rule) { return rule == LambdaRule::minimum ? "min" : "one-se"; }

double mean_of_finite(const std::vector<double>& values) {
  double sum = 0.0;
  int n = 0;
  for (double v : values)
    if (std::isfinite(v)) {
      sum += v;
      ++n;
    }
  return n ? sum / n : std::numeric_limits<double>::quiet_NaN();
}

double standard_error_of_mean(const std::vector<double>& values) {
  const double mean = mean_of_finite(values);
  if (!std::isfinite(mean)) return std::numeric_limits<double>::quiet_NaN();
  double squares = 0.0;
  int n = 0;
  for (double v : values)
    if (std::isfinite(v)) {
      squares += (v - mean) * (v - mean);
      ++n;
    }
  return n > 1 ? std::sqrt(squares / (n - 1)) / std::sqrt(static_cast<double>(n)) : 0.0;
}

LambdaChoice choose_lambda(const std::vector<LambdaScore>& sweep, LambdaRule rule, const std::string& what) {
  LambdaChoice choice;
  std::size_t least = sweep.size();
  for (std::size_t i = 0; i < sweep.size(); ++i) {
    const double mean = mean_of_finite(sweep[i].fold_errors);
    choice.mean_errors.push_back(mean);
    if (std::isfinite(mean) && (least == sweep.size() || mean < choice.mean_errors[least])) least = i;
  }
  require(least < sweep.size(), "{}: no λ of the sweep has a finite cross-validation error", what);
  choice.least_lambda = sweep[least].lambda;
  choice.least_error = choice.mean_errors[least];
  choice.standard_error = standard_error_of_mean(sweep[least].fold_errors);  // the folds' spread at the least error
  choice.lambda = choice.least_lambda;
  choice.threshold = choice.least_error;
  if (rule == LambdaRule::minimum) return choice;
  choice.threshold = choice.least_error + choice.standard_error;
  for (std::size_t i = 0; i < sweep.size(); ++i)
    if (std::isfinite(choice.mean_errors[i]) && choice.mean_errors[i] <= choice.threshold &&
        sweep[i].lambda > choice.lambda)
      choice.lambda = sweep[i].lambda;
  return choice;
}

namespace {

/// The index of the least finite mean error (the first of equals); nothing when no λ has one.
std::optional<std::size_t> least_mean(const std::vector<LambdaScore>& ascending) {
  std::optional<std::size_t> least;
  double least_error = 0.0;
  for (std::size_t k = 0; k < ascending.size(); ++k) {
    const double mean = mean_of_finite(ascending[k].fold_errors);
    if (std::isfinite(mean) && (!least || mean < least_error)) {
      least = k;
      least_error = mean;
    }
  }
  return least;
}

}  // namespace

std::optional<double> lambda_beyond_grid(const std::vector<LambdaScore>& ascending, double floor, double ceiling) {
  const std::optional<std::size_t> least = least_mean(ascending);
  if (ascending.size() < 2 || !least) return std::nullopt;
  if (*least == 0 && ascending.front().lambda > floor * 1.0001) return ascending.front().lambda / kHalfDecade;
  if (*least + 1 == ascending.size() && ascending.back().lambda < ceiling / 1.0001)
    return ascending.back().lambda * kHalfDecade;
  return std::nullopt;
}

bool lambda_sweep_bracketed(const std::vector<LambdaScore>& ascending) {
  const std::optional<std::size_t> least = least_mean(ascending);
  return least && *least > 0 && *least + 1 < ascending.size();
}

}  // namespace sflsh::reduced
