#include <sflsh/core/error.hpp>
#include <sflsh/material/surface_operators.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <queue>
#include <utility>

namespace sflsh::material {

namespace {

Eigen::Vector3d row(const RowMatrixX3d& V, int i) { return V.row(i).transpose(); }

// Twice the area of triangle f.
double double_area(const RowMatrixX3d& V, const RowMatrixX3i& F, Eigen::Index f) {
  const Eigen::Vector3d a = row(V, F(f, 0)), b = row(V, F(f, 1)), c = row(V, F(f, 2));
  return (b - a).cross(c - a).norm();
}

using Entry = std::pair<double, int>;  // (distance, vertex); min-heap ordered by distance, then vertex
using MinHeap = std::priority_queue<Entry, std::vector<Entry>, std::greater<>>;

double edge_weight(const RowMatrixX3d& V, const Eigen::VectorXd& scale, int a, int b) {
  const double length = (V.row(a) - V.row(b)).norm();
  return scale.size() == 0 ? length : length * 0.5 * (scale(a) + scale(b));
}

// Dijkstra from the heap's entries, lowering `distance`; returns the number of settled improvements.
int run_dijkstra(const RowMatrixX3d& V, const VertexAdjacency& adjacency, const Eigen::VectorXd& scale, MinHeap& heap,
                 Eigen::VectorXd& distance) {
  int updated = 0;
  while (!heap.empty()) {
    const auto [d, v] = heap.top();
    heap.pop();
    if (d > distance(v)) continue;  // stale entry
    ++updated;
    for (const int w : adjacency.of(v)) {
      const double candidate = d + edge_weight(V, scale, v, w);
      if (candidate < distance(w)) {
        distance(w) = candidate;
        heap.emplace(candidate, w);
      }
    }
  }
  return updated;
}

void check_scale(const Eigen::VectorXd& scale, Eigen::Index n) {
  if (scale.size() == 0) return;
  require(scale.size() == n, "distance scale has {} entries for {} vertices", scale.size(), n);
  for (Eigen::Index i = 0; i < n; ++i)
    require(std::isfinite(scale(i)) && scale(i) > 0.0, "distance scale at vertex {} is {} (must be finite and > 0)", i,
            scale(i));
}

}  // namespace

void validate_surface(const RowMatrixX3d& V, const RowMatrixX3i& F) {
  require(V.rows() > 0 && F.rows() > 0, "surface is empty ({} vertices, {} faces)", V.rows(), F.rows());
  for (Eigen::Index i = 0; i < V.rows(); ++i)
    require(V.row(i).allFinite(), "surface vertex {} has a non-finite position", i);
  const double diagonal = (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
  std::vector<char> referenced(static_cast<std::size_t>(V.rows()), 0);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    for (int c = 0; c < 3; ++c) {
      const int v = F(f, c);
      require(v >= 0 && v < V.rows(), "surface face {} has vertex index {} outside [0, {})", f, v, V.rows());
      referenced[static_cast<std::size_t>(v)] = 1;
    }
    require(F(f, 0) != F(f, 1) && F(f, 1) != F(f, 2) && F(f, 0) != F(f, 2),
            "surface face {} repeats a vertex ({} {} {})", f, F(f, 0), F(f, 1), F(f, 2));
    require(0.5 * double_area(V, F, f) > 1e-14 * diagonal * diagonal, "surface face {} has (near-)zero area", f);
  }
  for (std::size_t v = 0; v < referenced.size(); ++v)
    require(referenced[v] != 0, "surface vertex {} is not referenced by any face", v);
}

SparseMatrixd cotangent_laplacian(const RowMatrixX3d& V, const RowMatrixX3i& F) {
  validate_surface(V, F);
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<std::size_t>(F.rows()) * 12);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const double twice_area = double_area(V, F, f);
    for (int k = 0; k < 3; ++k) {
      // Corner k is opposite edge (i, j): cot = (e_ki · e_kj) / |e_ki × e_kj|, |e_ki × e_kj| = 2A.
      const int i = F(f, (k + 1) % 3), j = F(f, (k + 2) % 3), o = F(f, k);
      const double cot = (row(V, i) - row(V, o)).dot(row(V, j) - row(V, o)) / twice_area;
      const double w = 0.5 * cot;
      triplets.emplace_back(i, j, -w);
      triplets.emplace_back(j, i, -w);
      triplets.emplace_back(i, i, w);
      triplets.emplace_back(j, j, w);
    }
  }
  SparseMatrixd L(V.rows(), V.rows());
  L.setFromTriplets(triplets.begin(), triplets.end());
  return L;
}

Eigen::VectorXd lumped_mass(const RowMatrixX3d& V, const RowMatrixX3i& F, MassLumping lumping) {
  validate_surface(V, F);
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(V.rows());
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const double area = 0.5 * double_area(V, F, f);
    if (lumping == MassLumping::kBarycentric) {
      for (int c = 0; c < 3; ++c) mass(F(f, c)) += area / 3.0;
      continue;
    }
    // Mixed Voronoi (Meyer, Desbrun, Schröder, Barr 2003, Fig. 4): for a non-obtuse triangle vertex i gets
    // (|e_ij|² cot∠k + |e_ik|² cot∠j)/8; an obtuse triangle gives A/2 to the obtuse corner and A/4 to the others.
    std::array<double, 3> cot{};
    int obtuse = -1;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d a = row(V, F(f, (k + 1) % 3)) - row(V, F(f, k));
      const Eigen::Vector3d b = row(V, F(f, (k + 2) % 3)) - row(V, F(f, k));
      const double dot = a.dot(b);
      if (dot < 0.0) obtuse = k;
      cot[static_cast<std::size_t>(k)] = dot / (2.0 * area);
    }
    for (int k = 0; k < 3; ++k) {
      double share = 0.0;
      if (obtuse >= 0) {
        share = (k == obtuse) ? 0.5 * area : 0.25 * area;
      } else {
        const int j = (k + 1) % 3, l = (k + 2) % 3;  // edge k–j is opposite corner l, edge k–l opposite j
        const double e_kj = (V.row(F(f, j)) - V.row(F(f, k))).squaredNorm();
        const double e_kl = (V.row(F(f, l)) - V.row(F(f, k))).squaredNorm();
        share = (e_kj * cot[static_cast<std::size_t>(l)] + e_kl * cot[static_cast<std::size_t>(j)]) / 8.0;
      }
      mass(F(f, k)) += share;
    }
  }
  return mass;
}

VertexAdjacency vertex_adjacency(const RowMatrixX3i& F, int num_vertices) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(static_cast<std::size_t>(F.rows()) * 6);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    for (int c = 0; c < 3; ++c) {
      const int a = F(f, c), b = F(f, (c + 1) % 3);
      require(a >= 0 && a < num_vertices && b >= 0 && b < num_vertices,
              "surface face {} has a vertex index outside [0, {})", f, num_vertices);
      edges.emplace_back(a, b);
      edges.emplace_back(b, a);
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  VertexAdjacency adjacency;
  adjacency.offsets.assign(static_cast<std::size_t>(num_vertices) + 1, 0);
  adjacency.neighbors.reserve(edges.size());
  for (const auto& [a, b] : edges) {
    if (a == b) continue;
    ++adjacency.offsets[static_cast<std::size_t>(a) + 1];
    adjacency.neighbors.push_back(b);
  }
  for (std::size_t v = 0; v < static_cast<std::size_t>(num_vertices); ++v)
    adjacency.offsets[v + 1] += adjacency.offsets[v];
  return adjacency;
}

std::vector<int> connected_components(const VertexAdjacency& adjacency) {
  const int n = adjacency.num_vertices();
  std::vector<int> component(static_cast<std::size_t>(n), -1);
  int count = 0;
  std::vector<int> stack;
  for (int seed = 0; seed < n; ++seed) {
    if (component[static_cast<std::size_t>(seed)] >= 0) continue;
    component[static_cast<std::size_t>(seed)] = count;
    stack.push_back(seed);
    while (!stack.empty()) {
      const int v = stack.back();
      stack.pop_back();
      for (const int w : adjacency.of(v)) {
        if (component[static_cast<std::size_t>(w)] >= 0) continue;
        component[static_cast<std::size_t>(w)] = count;
        stack.push_back(w);
      }
    }
    ++count;
  }
  return component;
}

Eigen::VectorXd edge_distances(const RowMatrixX3d& V, const VertexAdjacency& adjacency, std::span<const int> sources,
                               const Eigen::VectorXd& scale) {
  require(adjacency.num_vertices() == V.rows(), "adjacency has {} vertices, positions {}", adjacency.num_vertices(),
          V.rows());
  require(!sources.empty(), "edge_distances needs at least one source vertex");
  check_scale(scale, V.rows());
  Eigen::VectorXd distance = Eigen::VectorXd::Constant(V.rows(), std::numeric_limits<double>::infinity());
  MinHeap heap;
  for (const int s : sources) {
    require(s >= 0 && s < V.rows(), "source vertex {} outside [0, {})", s, V.rows());
    distance(s) = 0.0;
    heap.emplace(0.0, s);
  }
  run_dijkstra(V, adjacency, scale, heap, distance);
  return distance;
}

int relax_edge_distances(const RowMatrixX3d& V, const VertexAdjacency& adjacency, int source,
                         const Eigen::VectorXd& scale, Eigen::VectorXd& distance) {
  require(distance.size() == V.rows() && adjacency.num_vertices() == V.rows(),
          "relax_edge_distances: {} distances, {} adjacency rows for {} vertices", distance.size(),
          adjacency.num_vertices(), V.rows());
  require(source >= 0 && source < V.rows(), "source vertex {} outside [0, {})", source, V.rows());
  check_scale(scale, V.rows());
  if (distance(source) <= 0.0) return 0;
  distance(source) = 0.0;
  MinHeap heap;
  heap.emplace(0.0, source);
  return run_dijkstra(V, adjacency, scale, heap, distance);
}

}  // namespace sflsh::material
