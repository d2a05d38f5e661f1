#pragma once
// Point location in a tet mesh (private to meshing): the tet that contains each query point, or the
// one it is least outside of, with barycentric coordinates (possibly slightly outside [0, 1]).
#include <sflsh/meshing/types.hpp>

#include <vector>

namespace sflsh::meshing::detail {

struct PointLocation {
  std::vector<int> tet;
  std::vector<Eigen::Vector4d> bary;
  double worst_outside = 0.0;  ///< most negative barycentric coordinate over all queries (≤ 0)
};

PointLocation locate_points(const RowMatrixX3d& nodes, const RowMatrixX4i& tets, const RowMatrixX3d& queries);

}  // namespace sflsh::meshing::detail
