#pragma once
// Discrete operators on a triangle surface given as plain arrays (V: #V×3 positions, F: #F×3 vertex
// indices), possibly open (with boundary loops): the cotangent Laplacian, a lumped mass matrix, the
// vertex adjacency and edge-graph (Dijkstra) distances. They carry the heterogeneous material fields
// (SFLSH §3–4): control points (control_points.hpp) and the biharmonic basis (biharmonic_basis.hpp).
#include <sflsh/core/eigen_types.hpp>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <cstdint>
#include <span>
#include <vector>

namespace sflsh::material {

using sflsh::RowMatrixX3d;  // core/eigen_types.hpp
using sflsh::RowMatrixX3i;
using SparseMatrixd = Eigen::SparseMatrix<double>;  ///< column-major, as Eigen's sparse solvers want

/// Throws sflsh::Error naming the first problem: empty arrays, non-finite positions, face indices out of
/// range or repeated within a face, zero-area faces (area ≤ 1e-14 × the squared bounding-box diagonal),
/// or a vertex that no face references (its mass would be zero).
void validate_surface(const RowMatrixX3d& V, const RowMatrixX3i& F);

/// The cotangent Laplacian in the positive semi-definite convention (Pinkall & Polthier 1993):
/// \f[ L_{ij} = -\tfrac12(\cot\alpha_{ij} + \cot\beta_{ij}),\quad L_{ii} = -\textstyle\sum_{j\ne i} L_{ij}, \f]
/// so that \f$ u^T L u = \int_S \|\nabla u\|^2 \f$ exactly for piecewise-linear u (the P1 stiffness
/// matrix): L is symmetric positive semi-definite with L·1 = 0 on any non-degenerate mesh. Off-diagonal
/// entries are ≤ 0 only on Delaunay meshes (obtuse opposite angles give positive ones). This is minus
/// libigl's `cotmatrix`. On a boundary edge only the one opposite angle contributes (natural boundary).
/// @param[in] V  #V by 3 vertex positions [m]
/// @param[in] F  #F by 3 vertex indices of the triangles
/// @return #V by #V sparse matrix [dimensionless]
SparseMatrixd cotangent_laplacian(const RowMatrixX3d& V, const RowMatrixX3i& F);

enum class MassLumping {
  kVoronoi,      ///< mixed Voronoi areas (Meyer et al. 2003): circumcentric cells, obtuse triangles split A/2, A/4, A/4
  kBarycentric,  ///< a third of each incident triangle's area
};

/// The lumped (diagonal) mass matrix as a vector: per-vertex area [m²]; it sums to the surface area.
/// @param[in] V, F  the surface
/// @return #V vector of vertex areas [m²], all positive for a valid surface
Eigen::VectorXd lumped_mass(const RowMatrixX3d& V, const RowMatrixX3i& F, MassLumping lumping = MassLumping::kVoronoi);

/// Vertex adjacency in compressed-row form: the neighbours of v are neighbors[offsets[v] .. offsets[v+1]),
/// sorted ascending, without duplicates or v itself.
struct VertexAdjacency {
  std::vector<int> offsets;    ///< #V + 1 entries
  std::vector<int> neighbors;  ///< 2 × #edges entries

  int num_vertices() const { return offsets.empty() ? 0 : static_cast<int>(offsets.size()) - 1; }
  std::span<const int> of(int v) const {
    return {neighbors.data() + offsets[static_cast<std::size_t>(v)],
            static_cast<std::size_t>(offsets[static_cast<std::size_t>(v) + 1] - offsets[static_cast<std::size_t>(v)])};
  }
};

/// The edge graph of F over `num_vertices` vertices.
VertexAdjacency vertex_adjacency(const RowMatrixX3i& F, int num_vertices);

/// Connected component id of every vertex (0, 1, …, in order of the smallest vertex of each component).
std::vector<int> connected_components(const VertexAdjacency& adjacency);

/// Edge-graph ("geodesic-ish") distances by Dijkstra: the shortest path along mesh edges, each edge (a, b)
/// weighted by |V_a − V_b| · ½(scale_a + scale_b). Edge paths overestimate the true geodesic distance by at
/// most ~8% on well-shaped meshes (zig-zag on a regular triangulation), which is enough for sampling.
/// @param[in] V          #V by 3 vertex positions [m]
/// @param[in] adjacency  vertex_adjacency(F, #V)
/// @param[in] sources    source vertices (distance 0); at least one
/// @param[in] scale      #V positive per-vertex factors, or empty for 1 (metric scaling, e.g. sampling density)
/// @return #V distances [m × scale]; +∞ for vertices not connected to any source
Eigen::VectorXd edge_distances(const RowMatrixX3d& V, const VertexAdjacency& adjacency, std::span<const int> sources,
                               const Eigen::VectorXd& scale = Eigen::VectorXd());

/// Lowers `distance` in place to min(distance, distance from `source`), visiting only the vertices whose
/// value decreases (pruned Dijkstra): the incremental update of farthest-point sampling. Same metric as
/// edge_distances. Returns the number of vertices updated.
int relax_edge_distances(const RowMatrixX3d& V, const VertexAdjacency& adjacency, int source,
                         const Eigen::VectorXd& scale, Eigen::VectorXd& distance);

}  // namespace sflsh::material
