#pragma once
// Principal components of the population's surfaces (SMPL-style shape space).
#include <sflsh/body/open_body.hpp>

#include <Eigen/Core>

#include <vector>

namespace sflsh::body::detail {

struct ShapePca {
  Eigen::VectorXd mean;        ///< 3n mean surface (row 3v + c) [m]
  Eigen::MatrixXd directions;  ///< 3n×B: column m = √λ_m e_m, so β ~ N(0, I) spans the population [m]
  Eigen::VectorXd variances;   ///< λ_m [m²], descending
  Eigen::VectorXd explained;   ///< λ_m / Σ_all λ (fraction of the total variance)
};

/// PCA of the columns of `samples` (3n×N) through the N×N Gram matrix (snapshot method):
/// G = XᵀX/(N − 1) with X the centred samples, G u = λ u, e = X u / √((N − 1) λ).
/// Sign convention: each component is oriented so that its scores correlate positively with the
/// anthropometric factor they correlate with most strongly (e.g. +β₁ is taller when component 1 is
/// mostly stature). `factors` holds the N samples' factors.
ShapePca shape_pca(const Eigen::MatrixXd& samples, int components, const std::vector<AnthroFactors>& factors);

/// β = Λ^{-1/2} Eᵀ (V − mean): the coordinates of a surface V (3n) in the PCA basis.
Eigen::VectorXd project_to_pca(const ShapePca& pca, const Eigen::VectorXd& surface);

}  // namespace sflsh::body::detail
