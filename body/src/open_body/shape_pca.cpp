#include "shape_pca.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <string>

namespace sflsh::body::detail {
namespace {

/// "name (r = x.xx)" of the factor with the second largest |correlation|.
std::string second_factor(const Eigen::VectorXd& corr, Eigen::Index strongest) {
  Eigen::VectorXd rest = corr.cwiseAbs();
  rest(strongest) = -1.0;
  Eigen::Index second = 0;
  rest.maxCoeff(&second);
  return fmt::format("{} (r = {:.2f})", kAnthroFactorNames[static_cast<std::size_t>(second)], corr(second));
}

}  // namespace

ShapePca shape_pca(const Eigen::MatrixXd& samples, int components, const std::vector<AnthroFactors>& factors) {
  const Eigen::Index n = samples.cols();
  require(n > components && components > 0, "open body: PCA of {} samples cannot give {} components", n, components);
  require(static_cast<Eigen::Index>(factors.size()) == n, "open body: PCA needs one factor vector per sample");
  ShapePca pca;
  pca.mean = samples.rowwise().mean();
  const Eigen::MatrixXd centered = samples.colwise() - pca.mean;
  const Eigen::MatrixXd gram = (centered.transpose() * centered) / static_cast<double>(n - 1);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gram);
  require(eig.info() == Eigen::Success, "open body: eigen-decomposition of the population Gram matrix failed");
  // Eigen sorts ascending; take from the end.
  const Eigen::VectorXd all = eig.eigenvalues().cwiseMax(0.0);
  const double total = all.sum();
  pca.variances.resize(components);
  pca.explained.resize(components);
  pca.directions.resize(samples.rows(), components);
  for (int m = 0; m < components; ++m) {
    const Eigen::Index col = n - 1 - m;
    const double lambda = all(col);
    require(lambda > 0.0, "open body: PCA component {} has zero variance", m);
    Eigen::VectorXd u = eig.eigenvectors().col(col);
    // Scores of the samples on this component are √((N−1)λ) u; orient by the most correlated factor.
    Eigen::VectorXd corr(kNumAnthroFactors);
    for (int f = 0; f < kNumAnthroFactors; ++f) {
      Eigen::VectorXd z(n);
      for (Eigen::Index k = 0; k < n; ++k) z(k) = factors[static_cast<std::size_t>(k)](f);
      z.array() -= z.mean();
      corr(f) = u.dot(z) / (u.norm() * z.norm() + 1e-300);
    }
    Eigen::Index strongest = 0;
    corr.cwiseAbs().maxCoeff(&strongest);
    if (corr(strongest) < 0.0) {
      u = -u;
      corr = -corr;
    }
    logger()->info("open body: shape component {} explains {:.2f}% of the variance, mostly {} (r = {:.2f}), then {}",
                   m + 1, 100.0 * lambda / total, kAnthroFactorNames[static_cast<std::size_t>(strongest)],
                   corr(strongest), second_factor(corr, strongest));
    pca.variances(m) = lambda;
    pca.explained(m) = lambda / total;
    // √λ e = √λ X u / √((N−1)λ) = X u / √(N−1).
    pca.directions.col(m) = centered * u / std::sqrt(static_cast<double>(n - 1));
  }
  return pca;
}

Eigen::VectorXd project_to_pca(const ShapePca& pca, const Eigen::VectorXd& surface) {
  // With S = E Λ^{1/2}: β = Λ^{-1/2} Eᵀ (V − mean) = Λ^{-1} Sᵀ (V − mean).
  return (pca.directions.transpose() * (surface - pca.mean)).cwiseQuotient(pca.variances);
}

}  // namespace sflsh::body::detail
