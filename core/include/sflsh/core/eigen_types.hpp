#pragma once
// The row-major n×3 arrays every module passes around (positions, displacements, triangles), defined once here;
// body::, material:: and meshing:: name the same types.
#include <Eigen/Core>

namespace sflsh {

using RowMatrixX3d = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;  ///< n×3 values, one row per point
using RowMatrixX3i = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;     ///< n×3 indices (triangles)

}  // namespace sflsh
