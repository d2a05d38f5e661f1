#pragma once
// The closed boundary of the soft-tissue layer: skin (outer), inner surface and side walls.
#include <sflsh/meshing/correspondence.hpp>
#include <sflsh/meshing/tet_backend.hpp>

#include <vector>

namespace sflsh::meshing {

struct LayerSurface {
  ClosedSurface surface;
  /// Per surface vertex: where it sits in layer terms (region vertex, depth).
  std::vector<SurfaceAnchor> anchors;
  int side_layers = 0;  ///< subdivisions of the side walls through the thickness
};

/// Builds the closed layer boundary for a geometry: vertices [0, R) are the skin (region vertex order),
/// [R, 2R) the inner surface s + h(c − s) with the same triangles reversed, then the side-wall
/// vertices; side walls join each boundary loop of the skin to its inner copy with `side_layers`
/// subdivisions in depth (0: chosen so that side edges are about `edge_length`). Features are the rims
/// (the boundary loops on the skin and on the inner surface).
LayerSurface build_layer_surface(const Region& region, const LayerGeometry& geometry, double edge_length,
                                 int side_layers = 0);

}  // namespace sflsh::meshing
