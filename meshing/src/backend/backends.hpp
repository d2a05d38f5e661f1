#pragma once
// The two tet-meshing backends behind tetrahedralize() (private to sflsh::meshing).
// Each returns the backend's raw output; tetrahedralize() checks the input before and orients,
// compacts and validates the output after. cgal_mesher.cpp is the only translation unit that
// instantiates CGAL Mesh_3 (docs/build.md: ~1.5 min and 3–4 GB to compile), so nothing else includes it.
#include <sflsh/meshing/tet_backend.hpp>

namespace sflsh::meshing::detail {

/// CGAL Mesh_3 on Polyhedral_mesh_domain_with_features_3: Delaunay refinement, the feature polylines
/// protected, then sliver perturbation and exudation. Resamples the surface: input_vertex is all −1.
TetMesh mesh_with_cgal(const ClosedSurface& surface, const SizeControl& size);

/// gmsh 4.8: one discrete surface per patch (subdivided 1→4 while its edges are much longer than
/// size.edge_length), a volume on their surface loop, HXT, gmsh's optimizer. Every input vertex is a
/// node; input_vertex maps nodes back to input vertices.
TetMesh mesh_with_gmsh(const ClosedSurface& surface, const SizeControl& size);

}  // namespace sflsh::meshing::detail
