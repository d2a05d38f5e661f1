#include "mesh_topology.hpp"

#include <algorithm>

namespace sflsh::body::detail {

VertexAdjacency vertex_adjacency(Eigen::Index num_vertices, const RowMatrixX3i& faces) {
  std::vector<std::vector<int>> rings(static_cast<std::size_t>(num_vertices));
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = faces(f, k), b = faces(f, (k + 1) % 3);
      rings[static_cast<std::size_t>(a)].push_back(b);
      rings[static_cast<std::size_t>(b)].push_back(a);
    }
  VertexAdjacency adjacency;
  adjacency.offsets.reserve(rings.size() + 1);
  adjacency.offsets.push_back(0);
  for (auto& ring : rings) {
    std::sort(ring.begin(), ring.end());
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    adjacency.indices.insert(adjacency.indices.end(), ring.begin(), ring.end());
    adjacency.offsets.push_back(static_cast<int>(adjacency.indices.size()));
  }
  return adjacency;
}

Eigen::MatrixXd laplacian_smooth_step(const VertexAdjacency& adjacency, const Eigen::MatrixXd& values, double alpha) {
  Eigen::MatrixXd out(values.rows(), values.cols());
  for (Eigen::Index v = 0; v < values.rows(); ++v) {
    const int begin = adjacency.offsets[static_cast<std::size_t>(v)];
    const int end = adjacency.offsets[static_cast<std::size_t>(v) + 1];
    if (begin == end) {
      out.row(v) = values.row(v);
      continue;
    }
    Eigen::RowVectorXd mean = Eigen::RowVectorXd::Zero(values.cols());
    for (int k = begin; k < end; ++k) mean += values.row(adjacency.indices[static_cast<std::size_t>(k)]);
    mean /= static_cast<double>(end - begin);
    out.row(v) = (1.0 - alpha) * values.row(v) + alpha * mean;
  }
  return out;
}

}  // namespace sflsh::body::detail
