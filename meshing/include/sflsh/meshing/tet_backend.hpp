#pragma once
// Tet meshing of a closed, outward-oriented triangulated surface: CGAL Mesh_3 or gmsh.
// Both backends sit behind this small non-template interface so that the one translation unit that
// instantiates Mesh_3 rarely recompiles (docs/build.md).
#include <sflsh/meshing/types.hpp>

#include <string>
#include <vector>

namespace sflsh::meshing {

/// cgal and gmsh mesh the closed layer boundary (tetrahedralize below). `layered` is the third
/// option of build_layer_mesh: prisms extruded from the skin triangles along the skeleton columns and
/// split into tets, so every node follows the layer map exactly (valid for any thickness, see
/// docs/meshing.md); tetrahedralize() does not take it.
enum class Mesher { cgal, gmsh, layered };
Mesher parse_mesher(const std::string& name);  ///< "cgal" | "gmsh" | "layered"; throws naming the value
const char* mesher_name(Mesher mesher);

/// A closed two-manifold triangle surface, counter-clockwise seen from outside, split into patches
/// (the NodeKind value of the layer part each triangle belongs to: outer, inner or side).
/// `features` are polylines (closed loops repeat their first point) along sharp creases that the
/// mesher must keep, e.g. the rims where the side wall meets the skin and the inner surface.
struct ClosedSurface {
  RowMatrixX3d vertices;
  RowMatrixX3i triangles;
  std::vector<NodeKind> patch;  ///< per triangle
  std::vector<std::vector<Eigen::Vector3d>> features;
};

/// Signed volume enclosed by a closed, outward-oriented surface [m³] (negative when oriented inward).
double enclosed_volume(const ClosedSurface& surface);

/// Target element size. `edge_length` is the target tet edge [m]; the surface approximation error
/// of resampling backends is bounded by `surface_distance` [m].
struct SizeControl {
  double edge_length = 0.02;
  double surface_distance = 0.002;
  int threads = 2;
};

/// The target size for a mesh of about `target_tets` tets filling `volume` [m³]. A regular tet of edge a
/// has volume a³/(6√2); meshers fill space with tets somewhat smaller than that, so
///   a = ( volume · 6√2 / (calibration · target_tets) )^(1/3)
/// with a per-backend calibration measured on layer-like shells (tetrahedralize.cpp). The surface
/// distance is a tenth of the edge. gmsh cannot coarsen its input surface: when the input triangles are
/// finer than `a`, it returns more tets than asked.
SizeControl size_for_target_tets(double volume, long target_tets, Mesher mesher, int threads);

struct TetMesh {
  RowMatrixX3d nodes;
  RowMatrixX4i tets;  ///< positively oriented: det[x1−x0, x2−x0, x3−x0] > 0
  /// For each node: the index of the input surface vertex it coincides with, or −1 (new node).
  /// gmsh keeps every input vertex as a node; CGAL resamples the surface and reports −1 throughout.
  std::vector<int> input_vertex;
};

/// Meshes the volume bounded by `surface`. Throws sflsh::Error when the backend fails or returns
/// an empty, inverted or degenerate mesh.
TetMesh tetrahedralize(const ClosedSurface& surface, Mesher mesher, const SizeControl& size);

/// For each node of `mesh` that lies on its boundary (a face used by one tet), the closest triangle of
/// `surface` and the barycentric coordinates of the closest point on it; triangle −1 for interior nodes.
struct BoundaryLocation {
  std::vector<int> triangle;
  std::vector<Eigen::Vector3d> bary;
  double max_distance = 0.0;  ///< largest node-to-surface distance found [m]
};
BoundaryLocation locate_boundary_nodes(const TetMesh& mesh, const ClosedSurface& surface);

}  // namespace sflsh::meshing
