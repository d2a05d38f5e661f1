#pragma once
// Plain array types shared by the meshing stage.
#include <sflsh/core/eigen_types.hpp>

#include <Eigen/Core>

#include <array>
#include <cstdint>

namespace sflsh::meshing {

using sflsh::RowMatrixX3d;  // core/eigen_types.hpp
using sflsh::RowMatrixX3i;
using RowMatrixX4i = Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>;

/// What a node of the layer mesh is attached to. Values are stored in files: do not renumber.
enum class NodeKind : std::uint8_t {
  interior = 0,  ///< inside the layer; follows by Laplacian interpolation (layered meshes: by its anchor)
  outer = 1,     ///< on the skin (depth 0)
  inner = 2,     ///< on the inner surface (depth 1), attached to the bones
  side = 3,      ///< on the side wall that closes the layer at the region's boundary curves
};

/// Which part of the body a skin vertex or tet belongs to. Values are stored in files.
enum class Part : std::uint8_t {
  torso = 0,
  left_upper_arm = 1,
  right_upper_arm = 2,
  left_thigh = 3,
  right_thigh = 4,
};
inline constexpr int kNumParts = 5;
const char* part_name(Part part);

/// Where a boundary point of the layer sits, in terms that follow any shape β and thickness field h:
/// a point on the region's skin (barycentric combination of up to three region vertices) and a depth
/// fraction along its column towards the skeleton (0 = skin, 1 = inner surface). Its position is
///   p = Σ_k weight_k · [ s_k + depth · h_k · (c_k − s_k) ]                       (docs/physics.md §1.4)
/// with s the shaped skin, c the skeleton correspondence and h the thickness fraction at vertex k.
/// Indices are local region-vertex indices (see Region::vertices).
struct SurfaceAnchor {
  std::array<int, 3> vertex{-1, -1, -1};
  Eigen::Vector3d weight = Eigen::Vector3d::Zero();
  double depth = 0.0;
  bool valid() const { return vertex[0] >= 0; }
};

}  // namespace sflsh::meshing
