#pragma once
// Triangulation of the open body's zero level set (the only translation unit with CGAL's mesher).
#include "body_field.hpp"

#include <sflsh/body/body_model.hpp>

#include <vector>

namespace sflsh::body::detail {

/// A closed triangle surface, symmetric about x = 0: n×3 vertices [m], m×3 faces counter-clockwise
/// seen from outside, and the index of each vertex's mirror image (itself on the mid-plane).
struct TriangleSurface {
  RowMatrixX3d vertices;
  RowMatrixX3i faces;
  std::vector<int> mirror;
};

/// Meshes f = 0 of `field` (symmetric about x = 0) with CGAL's Delaunay surface mesher (Manifold_tag,
/// deterministic seeds shot from the skeleton's joints), clips it at the mid-plane, remeshes the right
/// half isotropically and joins it to its mirror image (about `target_vertices` vertices in all),
/// with the vertices projected back onto f = 0. Deterministic for a given field.
TriangleSurface mesh_body_surface(const BodyField& field, const Skeleton& skeleton, int target_vertices);

}  // namespace sflsh::body::detail
