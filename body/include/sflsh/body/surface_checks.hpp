#pragma once
// Topological and geometric checks of a closed triangle surface.
#include <sflsh/body/body_model.hpp>

#include <string>

namespace sflsh::body {

struct SurfaceReport {
  bool closed = false;           ///< every edge has exactly two incident faces
  bool edge_manifold = false;    ///< no edge with more than two faces
  bool vertex_manifold = false;  ///< every vertex's link is one cycle (one path on a boundary)
  bool consistently_oriented = false;
  bool outward = false;  ///< signed volume positive
  int connected_components = 0;
  int euler_characteristic = 0;  ///< V − E + F (2 for a sphere)
  int degenerate_faces = 0;      ///< faces with (near-)zero area
  int self_intersections = -1;   ///< intersecting non-adjacent face pairs (-1: not checked)
  double volume = 0.0;           ///< enclosed volume [m³]
  double area = 0.0;             ///< [m²]
  double min_angle_deg = 0.0;
  bool ok() const {
    return closed && edge_manifold && vertex_manifold && consistently_oriented && outward &&
           connected_components == 1 && degenerate_faces == 0 && self_intersections == 0;
  }
  std::string summary() const;
};

/// Checks `faces` over `vertices`; self-intersections are tested when `check_intersections`.
SurfaceReport check_surface(const RowMatrixX3d& vertices, const RowMatrixX3i& faces, bool check_intersections = true);

}  // namespace sflsh::body
