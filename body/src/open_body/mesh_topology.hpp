#pragma once
// Vertex adjacency of a triangle surface (for Laplacian smoothing on the surface).
#include <sflsh/body/body_model.hpp>

#include <vector>

namespace sflsh::body::detail {

/// The 1-ring of every vertex in compressed rows: neighbours of v are
/// indices[offsets[v] .. offsets[v + 1]), sorted ascending.
struct VertexAdjacency {
  std::vector<int> offsets;
  std::vector<int> indices;
  int degree(int v) const { return offsets[static_cast<std::size_t>(v) + 1] - offsets[static_cast<std::size_t>(v)]; }
};

/// Adjacency of `num_vertices` vertices through the edges of `faces` (m×3).
VertexAdjacency vertex_adjacency(Eigen::Index num_vertices, const RowMatrixX3i& faces);

/// One Jacobi step of uniform Laplacian smoothing of per-vertex rows:
/// out_v = (1 − α) in_v + α · mean_{u ∈ N(v)} in_u.
Eigen::MatrixXd laplacian_smooth_step(const VertexAdjacency& adjacency, const Eigen::MatrixXd& values, double alpha);

}  // namespace sflsh::body::detail
