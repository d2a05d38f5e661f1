// The shape regression of SFLSH eqs. 1, 4, 5 on its own and its leave-one-subject-out λ sweep (shape_regression.hpp).
#include <sflsh/core/error.hpp>
#include <sflsh/reduced/shape_regression.hpp>

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace sflsh::reduced {

namespace {

using BetaMatrix = Eigen::Matrix<double, Eigen::Dynamic, body::kNumBetas>;  // S × 10, one β per row

}  // namespace

void check_shape_regression(const ShapeRegressionData& data, const ShapeRegularizer& regularizer) {
  require(data.num_subjects() >= 2, "shape regression: {} subject(s); the fit and its cross-validation need ≥ 2",
          data.num_subjects());
  require(data.kappa.size() == data.betas.size(), "shape regression: {} β for {} κ", data.betas.size(),
          data.kappa.size());
  const int N = data.num_controls();
  require(N >= 1, "shape regression: no control points");
  for (std::size_t s = 0; s < data.kappa.size(); ++s) {
    require(data.kappa[s].rows() == N && data.kappa[s].cols() == material::kNumKappa,
            "shape regression: subject #{} has κ of {} × {}, expected {} × {}", s, data.kappa[s].rows(),
            data.kappa[s].cols(), N, material::kNumKappa);
    require(data.kappa[s].allFinite() && data.betas[s].allFinite(),
            "shape regression: subject #{} has non-finite β or κ", s);
  }
  require(regularizer.kind != Regularizer::local || static_cast<int>(regularizer.metric.size()) == N,
          "shape regression: the local regularizer has {} metrics for {} control points", regularizer.metric.size(), N);
}

ShapeElasticity fit_shape_regression(const ShapeRegressionData& data, const ShapeRegularizer& regularizer,
                                     double lambda, const std::vector<int>& subjects) {
  check_shape_regression(data, regularizer);
  require(std::isfinite(lambda) && lambda >= 0.0, "shape regression: λ = {} must be finite and ≥ 0", lambda);
  std::vector<int> used = subjects;
  if (used.empty()) {
    used.resize(static_cast<std::size_t>(data.num_subjects()));
    std::iota(used.begin(), used.end(), 0);
  }
  const auto S = static_cast<Eigen::Index>(used.size());
  const int N = data.num_controls();
  // Centred shapes: b_i is not regularized, so it absorbs the means exactly.
  BetaMatrix X(S, body::kNumBetas);
  for (Eigen::Index r = 0; r < S; ++r)
    X.row(r) = data.betas[static_cast<std::size_t>(used[static_cast<std::size_t>(r)])];
  const body::Betas beta_mean = X.colwise().mean().transpose();
  X.rowwise() -= beta_mean.transpose();
  const ShapeMetric G = X.transpose() * X / static_cast<double>(S);

  ShapeElasticity model;
  model.A.resize(static_cast<std::size_t>(N));
  model.b.resize(N, material::kNumKappa);
  Eigen::CompleteOrthogonalDecomposition<BetaMatrix> minimum_norm;
  if (regularizer.kind == Regularizer::none) minimum_norm.compute(X);
  const Eigen::LDLT<ShapeMetric> l2_factor(G + lambda * ShapeMetric::Identity());
  Eigen::Matrix<double, Eigen::Dynamic, material::kNumKappa> Y(S, material::kNumKappa);
  for (int i = 0; i < N; ++i) {
    for (Eigen::Index r = 0; r < S; ++r)
      Y.row(r) = data.kappa[static_cast<std::size_t>(used[static_cast<std::size_t>(r)])].row(i);
    const Eigen::RowVector3d kappa_mean = Y.colwise().mean();
    Y.rowwise() -= kappa_mean;
    ShapeMatrix& A = model.A[static_cast<std::size_t>(i)];
    switch (regularizer.kind) {
      case Regularizer::none:
        A = minimum_norm.solve(Y);
        break;
      case Regularizer::l2:
        A = l2_factor.solve(X.transpose() * Y / static_cast<double>(S));
        break;
      case Regularizer::local:
        A = Eigen::LDLT<ShapeMetric>(G + lambda * regularizer.metric[static_cast<std::size_t>(i)])
                .solve(X.transpose() * Y / static_cast<double>(S));  // (G + λ Q_i) A_i = (1/S) X̃ᵀ Ỹ_i
        break;
    }
    model.b.row(i) = kappa_mean - (A.transpose() * beta_mean).transpose();  // b_i = κ̄_i − A_iᵀ β̄
  }
  require(model.b.allFinite() &&
              std::all_of(model.A.begin(), model.A.end(), [](const ShapeMatrix& a) { return a.allFinite(); }),
          "shape regression: the fit at λ = {} gave non-finite coefficients", lambda);
  return model;
}

double shape_prediction_error(const ShapeElasticity& model, const body::Betas& beta,
                              const material::KappaMatrix& kappa) {
  const material::KappaMatrix predicted = model.kappa_normalized(beta);
  require(predicted.rows() == kappa.rows(), "shape regression: a model of {} control points for κ of {}",
          predicted.rows(), kappa.rows());
  return std::sqrt((predicted - kappa).squaredNorm() / static_cast<double>(kappa.size()));
}

std::vector<double> default_lambda_grid() {
  std::vector<double> grid;
  for (int k = -12; k <= 12; ++k) grid.push_back(std::pow(10.0, 0.5 * k));
  return grid;
}

LambdaScore cross_validate_shape_regression(const ShapeRegressionData& data, const ShapeRegularizer& regularizer,
                                            double lambda) {
  check_shape_regression(data, regularizer);
  LambdaScore score;
  score.lambda = lambda;
  const int S = data.num_subjects();
  for (int left_out = 0; left_out < S; ++left_out) {
    std::vector<int> rest;
    for (int s = 0; s < S; ++s)
      if (s != left_out) rest.push_back(s);
    const ShapeElasticity model = fit_shape_regression(data, regularizer, lambda, rest);
    score.fold_errors.push_back(shape_prediction_error(model, data.betas[static_cast<std::size_t>(left_out)],
                                                       data.kappa[static_cast<std::size_t>(left_out)]));
  }
  return score;
}

ShapeLambdaSweep sweep_shape_regression(const ShapeRegressionData& data, const ShapeRegularizer& regularizer,
                                        std::vector<double> lambdas, bool extend, LambdaRule rule) {
  ShapeLambdaSweep sweep;
  if (regularizer.kind == Regularizer::none) {
    sweep.scores.push_back(cross_validate_shape_regression(data, regularizer, 0.0));
    sweep.choice = choose_lambda(sweep.scores, LambdaRule::minimum, "shapefit");
    return sweep;
  }
  require(!lambdas.empty(), "shapefit: no λ to cross-validate");
  for (double lambda : lambdas)
    require(std::isfinite(lambda) && lambda >= 0.0, "shapefit: λ = {} must be finite and ≥ 0", lambda);
  std::sort(lambdas.begin(), lambdas.end());
  lambdas.erase(std::unique(lambdas.begin(), lambdas.end()), lambdas.end());
  for (double lambda : lambdas) sweep.scores.push_back(cross_validate_shape_regression(data, regularizer, lambda));

  while (extend) {
    const std::optional<double> lambda = lambda_beyond_grid(sweep.scores);
    if (!lambda) break;
    LambdaScore score = cross_validate_shape_regression(data, regularizer, *lambda);
    if (*lambda < sweep.scores.front().lambda) {
      sweep.scores.insert(sweep.scores.begin(), std::move(score));
    } else {
      sweep.scores.push_back(std::move(score));
    }
    ++sweep.extensions;
  }
  sweep.bracketed = lambda_sweep_bracketed(sweep.scores);
  sweep.choice = choose_lambda(sweep.scores, rule, fmt::format("shapefit ({})", regularizer_key(regularizer.kind)));
  return sweep;
}

}  // namespace sflsh::reduced
