// Through-thickness normals from the depth field (docs/physics.md §1.3).
#include <sflsh/core/error.hpp>
#include <sflsh/material/through_thickness.hpp>

#include <Eigen/Dense>

#include <cmath>
#include <vector>

namespace sflsh::material {

meshing::RowMatrixX3d through_thickness_normals(const meshing::RowMatrixX3d& nodes, const meshing::RowMatrixX4i& tets,
                                                const Eigen::VectorXd& depth) {
  require(depth.size() == nodes.rows(), "through-thickness normals: {} depth values for {} nodes", depth.size(),
          nodes.rows());
  require(depth.allFinite(), "through-thickness normals: the depth field has non-finite values");
  meshing::RowMatrixX3d normals(tets.rows(), 3);
  std::vector<char> valid(static_cast<std::size_t>(tets.rows()), 0);
  for (Eigen::Index e = 0; e < tets.rows(); ++e) {
    Eigen::Matrix3d dm;
    Eigen::Vector3d dd;
    for (int k = 0; k < 3; ++k) {
      dm.col(k) = (nodes.row(tets(e, k + 1)) - nodes.row(tets(e, 0))).transpose();
      dd(k) = depth(tets(e, k + 1)) - depth(tets(e, 0));
    }
    // ∇d solves Dmᵀ ∇d = [d1 − d0, d2 − d0, d3 − d0].
    const Eigen::Vector3d gradient = dm.transpose().partialPivLu().solve(dd);
    const double length = gradient.norm();
    const double edge = dm.colwise().norm().maxCoeff();
    // A tet whose four nodes share one depth (e.g. all on the skin) has no gradient of its own.
    if (std::isfinite(length) && length * edge > 1e-6) {
      normals.row(e) = -gradient.transpose() / length;
      valid[static_cast<std::size_t>(e)] = 1;
    }
  }
  // Tets without a gradient take the mean normal of the valid tets around their nodes.
  Eigen::MatrixXd node_normal = Eigen::MatrixXd::Zero(nodes.rows(), 3);
  for (Eigen::Index e = 0; e < tets.rows(); ++e)
    if (valid[static_cast<std::size_t>(e)])
      for (int k = 0; k < 4; ++k) node_normal.row(tets(e, k)) += normals.row(e);
  for (Eigen::Index e = 0; e < tets.rows(); ++e) {
    if (valid[static_cast<std::size_t>(e)]) continue;
    Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 4; ++k) mean += node_normal.row(tets(e, k));
    require(mean.norm() > 1e-12, "through-thickness normals: tet {} and all tets around it have no depth gradient", e);
    normals.row(e) = mean.normalized();
  }
  return normals;
}

}  // namespace sflsh::material
