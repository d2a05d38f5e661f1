#pragma once
// The node order and ownership split of the distributed backward Euler solver. Meshes number their nodes
// as suits the mesher: the layered mesher numbers them layer by layer, so cutting that numbering into
// contiguous ranges put whole layers on one rank (the coarse layer's second rank owned only the attached
// inner layer; every tet straddled the cut). The solver therefore orders the nodes by reverse Cuthill–McKee
// on the tet graph, whose level sets cut across the layer's thickness, and splits that order into
// contiguous ranges of balanced element work.
#include <sflsh/meshing/types.hpp>

#include <vector>

namespace sflsh::fullspace {

/// Reverse Cuthill–McKee order of the node graph (two nodes are adjacent when they share a tet), each
/// connected component started from a pseudo-peripheral node (George & Liu). order[k] = node; nodes in no
/// tet come last.
std::vector<int> reverse_cuthill_mckee(int num_nodes, const meshing::RowMatrixX4i& tets);

struct NodePartition {
  std::vector<int> node_of;   ///< solver index → mesh node
  std::vector<int> index_of;  ///< mesh node → solver index
  std::vector<int> range;     ///< size + 1 entries: rank r owns solver indices [range[r], range[r + 1])
};

/// The RCM order split into `size` contiguous ranges with about equal numbers of incident tets (the cost of
/// the element kernels and, through the nonzeros, of the linear solver).
NodePartition partition_nodes(int num_nodes, const meshing::RowMatrixX4i& tets, int size);

}  // namespace sflsh::fullspace
