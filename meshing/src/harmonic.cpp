// Harmonic interpolation on a tet mesh (P1 Laplacian, Dirichlet on fixed nodes).
#include <sflsh/core/error.hpp>
#include <sflsh/meshing/harmonic.hpp>

#include <Eigen/Dense>

#include <cmath>

namespace sflsh::meshing {

HarmonicInterpolator::HarmonicInterpolator(const RowMatrixX3d& nodes, const RowMatrixX4i& tets,
                                           const std::vector<char>& fixed, double stiffening)
    : fixed_(fixed) {
  const int n = static_cast<int>(nodes.rows());
  require(static_cast<int>(fixed.size()) == n, "harmonic interpolation: {} fixed flags for {} nodes", fixed.size(), n);
  std::vector<int> slot(n, -1);
  for (int i = 0; i < n; ++i) {
    if (fixed[i]) {
      slot[i] = static_cast<int>(fixed_list_.size());
      fixed_list_.push_back(i);
    } else {
      slot[i] = static_cast<int>(free_.size());
      free_.push_back(i);
    }
  }
  // Element volumes and their mean, for the stiffening weight.
  Eigen::VectorXd volume(tets.rows());
  for (Eigen::Index e = 0; e < tets.rows(); ++e) {
    Eigen::Matrix3d dm;
    for (int k = 0; k < 3; ++k) dm.col(k) = (nodes.row(tets(e, k + 1)) - nodes.row(tets(e, 0))).transpose();
    volume(e) = dm.determinant() / 6.0;
    require(volume(e) > 0.0, "harmonic interpolation: tet {} has non-positive volume {:.3e}", e, volume(e));
  }
  const double mean_volume = volume.mean();

  std::vector<Eigen::Triplet<double>> ff, fb;
  ff.reserve(static_cast<std::size_t>(tets.rows()) * 16);
  for (Eigen::Index e = 0; e < tets.rows(); ++e) {
    Eigen::Matrix3d dm;
    for (int k = 0; k < 3; ++k) dm.col(k) = (nodes.row(tets(e, k + 1)) - nodes.row(tets(e, 0))).transpose();
    // Gradients of the barycentric functions: rows of Dm⁻¹ for nodes 1..3, minus their sum for node 0.
    const Eigen::Matrix3d inv = dm.inverse();
    Eigen::Matrix<double, 4, 3> grad;
    grad.row(0) = -inv.colwise().sum();
    grad.bottomRows<3>() = inv;
    const double weight = volume(e) * std::pow(mean_volume / volume(e), stiffening);
    const Eigen::Matrix4d local = weight * grad * grad.transpose();
    for (int a = 0; a < 4; ++a) {
      const int i = tets(e, a);
      if (fixed[i]) continue;
      for (int b = 0; b < 4; ++b) {
        const int j = tets(e, b);
        (fixed[j] ? fb : ff).emplace_back(slot[i], slot[j], local(a, b));
      }
    }
  }
  Eigen::SparseMatrix<double> lff(static_cast<Eigen::Index>(free_.size()), static_cast<Eigen::Index>(free_.size()));
  lff.setFromTriplets(ff.begin(), ff.end());
  coupling_.resize(static_cast<Eigen::Index>(free_.size()), static_cast<Eigen::Index>(fixed_list_.size()));
  coupling_.setFromTriplets(fb.begin(), fb.end());
  solver_ = std::make_shared<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>>();
  if (!free_.empty()) {
    solver_->compute(lff);
    require(solver_->info() == Eigen::Success,
            "harmonic interpolation: the interior Laplacian ({} nodes) is singular; an interior part has no fixed node",
            free_.size());
  }
}

Eigen::MatrixXd HarmonicInterpolator::extend(const Eigen::MatrixXd& values) const {
  require(values.rows() == num_nodes(), "harmonic interpolation: {} rows of values for {} nodes", values.rows(),
          num_nodes());
  Eigen::MatrixXd result = values;
  if (free_.empty()) return result;
  Eigen::MatrixXd boundary(static_cast<Eigen::Index>(fixed_list_.size()), values.cols());
  for (std::size_t k = 0; k < fixed_list_.size(); ++k)
    boundary.row(static_cast<Eigen::Index>(k)) = values.row(fixed_list_[k]);
  const Eigen::MatrixXd interior = solver_->solve(-(coupling_ * boundary));
  require(interior.allFinite(), "harmonic interpolation: the solve produced non-finite values");
  for (std::size_t k = 0; k < free_.size(); ++k) result.row(free_[k]) = interior.row(static_cast<Eigen::Index>(k));
  return result;
}

}  // namespace sflsh::meshing
