#pragma once
// Placement of the N surface control points s_i of the heterogeneous material field
// κ(s) = Σ_i φ_i(s) κ_i (SFLSH §3, Fig. 2 right; N grows 1 → 12 → 24 → 84 during the fit, SFLSH §5).
//
// Method: farthest-point sampling (Eldar et al. 1997) on edge-graph distances scaled by a per-vertex
// density factor, started at the vertex nearest the density-weighted centroid. Properties:
//  - nested: the points for N are the first N of the points for any N' > N (the sequence does not
//    depend on N), so a fit can grow N and keep its earlier control points;
//  - deterministic: no randomness, no threads; ties go to the smallest vertex index;
//  - denser where `density` is larger: distances are multiplied by it, so the spacing scales as
//    1/density and the number of points per unit area as density² (1.5 on the torso vs 1.0 on the
//    limbs gives ~2.25× more points per m² on the torso);
//  - part coverage: with part ids, the first point lies in the part of largest density²-weighted area
//    (the torso), and while some part has no point, the next point is the farthest vertex of the parts
//    without one;
//  - symmetric: with a mirror map, points come in groups of two — a vertex and its mirror, or, when the
//    farthest vertex lies on (or next to) the symmetry plane, two plane vertices — so every even N gives
//    a mirror-symmetric set on a mirror-symmetric mesh, and N = 1 is a plane vertex. Groups of one occur
//    only when no plane vertex is left (then symmetry is kept "where possible").
// A plane vertex is one whose mirror is itself or one of its edge neighbours (approximate mirror maps
// built by nearest-vertex reflection map near-plane vertices that way).
#include <sflsh/material/surface_operators.hpp>

#include <vector>

namespace sflsh::material {

struct ControlPointOptions {
  /// #V finite positive sampling density factors (e.g. 1.5 on the torso, 1.0 on the limbs); empty = all 1.
  Eigen::VectorXd density;
  /// #V part ids ≥ 0 (e.g. meshing::Part as int); empty = one part.
  std::vector<int> part;
  /// #V mirror vertex of each vertex (its left/right counterpart), or −1 for none; empty = no symmetry.
  std::vector<int> mirror;
};

/// The first `count` control points, as vertex indices in insertion order.
/// Throws sflsh::Error for count ≤ 0 or > #V, an invalid surface (validate_surface) or options of the
/// wrong size or with bad values (naming the vertex).
/// @param[in] V      #V by 3 vertex positions [m]
/// @param[in] F      #F by 3 triangle vertex indices (the surface may be open or have several components;
///                   a component without any point is sampled first, as its distance is infinite)
/// @param[in] count  N ≥ 1
std::vector<int> place_control_points(const RowMatrixX3d& V, const RowMatrixX3i& F, int count,
                                      const ControlPointOptions& options = {});

/// True when mirror[v] is v or an edge neighbour of v (see above). `mirror` must have #V entries.
bool is_plane_vertex(const VertexAdjacency& adjacency, const std::vector<int>& mirror, int v);

}  // namespace sflsh::material
