#pragma once
// Local basis functions for contact (docs/contact.md "Local resolution of contact"): the handles' functions span
// much of a body part, so the subspace x = x_D + (B ⊗ I₃) q cannot dent where an object presses. The free nodes
// within `depth` (along the mesh's edges) of the nodes an object may reach get functions of their own:
// - spacing h = 0 (the default): one per node, φ_k = 1 at node k and 0 elsewhere — the region is a full-space patch
//   inside the reduced body;
// - h > 0: fewer, smoother ones: centres c_k picked by farthest-point sampling at spacing h (along the edges), and
//   each a compactly supported bump
//   φ_k(i) = ψ(d(i, c_k) / ρ),   ψ(r) = (1 − r)⁴ (4r + 1) for r < 1, else 0      (Wendland's C² function),
// with d the shortest path along the layer's edges (rest lengths, so the bump does not jump a gap between body
// parts) and ρ = radius_factor · h; φ_k = 0 on attached nodes. The enriched subspace is [B  Φ] (local_subspace()),
// and the tets the bumps touch are where the elastic energy is integrated exactly (local_elastic.hpp).
#include <sflsh/model/problem.hpp>
#include <sflsh/reduced/subspace.hpp>

#include <vector>

namespace sflsh::reduced {

struct LocalBasisOptions {
  double spacing = 0.0;        ///< h: the distance between centres [m]; 0: one function per node
  double radius_factor = 2.0;  ///< ρ / h: the support radius of a bump in spacings
  double depth = 0.04;         ///< nodes up to this far (along the edges) from the given ones get functions [m]
};

struct LocalBasis {
  SparseRowMatrix functions;           ///< Φ (N × L): one column per centre
  std::vector<int> centres;            ///< the centre node of each column
  std::vector<int> tets;               ///< tets with a node in the support of any column, ascending
  double spacing = 0.0, radius = 0.0;  ///< h and ρ [m]
  int size() const { return static_cast<int>(centres.size()); }
};

/// Bumps around `nodes` (the skin nodes an object may reach; others are ignored when attached). Empty `nodes`, or
/// nodes that are all attached, give an empty basis.
LocalBasis local_basis(const model::Problem& problem, const std::vector<int>& nodes, const LocalBasisOptions& options);

/// The subspace [B  Φ]: the handles' functions first (so q = [t; e], e the bumps' displacements [m]).
Subspace local_subspace(const Subspace& base, const LocalBasis& local);

}  // namespace sflsh::reduced
