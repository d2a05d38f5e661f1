#pragma once
// The extruded ("layered") layer mesh (private to meshing): prisms along the skeleton columns.
#include <sflsh/meshing/layer_mesh.hpp>

namespace sflsh::meshing::detail {

/// Number of prism layers through the thickness for a size preset (≈ 25 k, 50 k and 200 k tets on a
/// region of ~8.5 k skin triangles).
int layered_layers(SizePreset size);

/// Nodes at depths l/L on every region vertex's column, each prism (skin triangle × layer) split into
/// three tets with the vertex-index rule of Dompierre et al. 1999 (conforming across shared faces).
/// Fills nodes, tets, kind, anchor and skin of `mesh` from the template geometry; every node has an
/// anchor. Throws when a tet of the template is not positively oriented.
void build_layered(LayerMesh& mesh, const LayerGeometry& geometry, int layers);

}  // namespace sflsh::meshing::detail
