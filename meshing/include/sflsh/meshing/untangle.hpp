#pragma once
// Local untangling of a tet mesh whose boundary nodes are fixed: after a retarget moved the boundary, free nodes
// of inverted tets and their free neighbours are relocated one at a time to the minimum of the untangling
// functional Σ_e √(V_e² + δ²) − V_e over the tets around them (Escobar et al. 2003, "Simultaneous untangling and
// smoothing of tetrahedral meshes"; docs/meshing.md §6), until no tet is inverted or `sweeps` passes are done.
#include <sflsh/meshing/types.hpp>

#include <vector>

namespace sflsh::meshing {

/// Untangles `nodes` in place; `fixed[i]` ≠ 0 keeps node i where it is, `tets_of[i]` lists the tets around node i.
/// Returns the number of node moves (0 when no tet was inverted). Tets whose four nodes are fixed cannot be
/// repaired: the caller checks the result.
int untangle(RowMatrixX3d& nodes, const RowMatrixX4i& tets, const std::vector<char>& fixed,
             const std::vector<std::vector<int>>& tets_of, int sweeps = 20);
/// The same, with the node-to-tet lists built here.
int untangle(RowMatrixX3d& nodes, const RowMatrixX4i& tets, const std::vector<char>& fixed, int sweeps = 20);

}  // namespace sflsh::meshing
