#pragma once
// Smooth, linearly precise handle weights on a tet mesh (Wang, Jacobson, Barbič, Kavan 2015, "Linear
// Subspace Design for Real-Time Shape Deformation", §4; docs/physics.md §2.1):
// \f[ w_j = \arg\min_w\; w^T K^T M^{-1} K\, w \quad\text{s.t.}\quad w = \delta_{jk} \text{ on handle } k, \f]
// with K = L − N: L the linear-FEM stiffness (L_ab = Σ_e V_e ∇φ_a·∇φ_b, positive semi-definite), N the
// boundary normal-derivative term N_ab = ∮ φ_a ∇φ_b·n dA, and M the lumped volume. For every globally
// affine f, (L f)_a = ∮ φ_a ∇f·n dA = (N f)_a, so K f = 0: affine functions cost nothing ("linear
// precision"), and constants in particular, so the weights of all handles sum to one (partition of unity)
// whenever every constrained node belongs to exactly one handle. One sparse LDLᵀ factorization of the free
// block, then one back-substitution per handle.
#include <sflsh/meshing/types.hpp>
#include <sflsh/reduced/subspace.hpp>

#include <vector>

namespace sflsh::reduced {

using meshing::RowMatrixX3d;
using meshing::RowMatrixX4i;
using SparseMatrixd = Eigen::SparseMatrix<double>;

/// K = L − N (N × N, not symmetric); K·f = 0 for every affine f (to round-off).
/// @param[in] nodes  #N by 3 positions [m]
/// @param[in] tets   #T by 4 positively oriented tets
SparseMatrixd linearly_precise_laplacian(const RowMatrixX3d& nodes, const RowMatrixX4i& tets);

/// The energy matrix Q = Kᵀ M⁻¹ K (symmetric positive semi-definite, affine functions in its null space).
SparseMatrixd linearly_precise_biharmonic(const RowMatrixX3d& nodes, const RowMatrixX4i& tets);

/// Handles as sets of constrained nodes: handle k is 1 on `handle_nodes[k]` and 0 on every other handle's
/// nodes. The sets must be disjoint and non-empty.
struct HandleSets {
  std::vector<std::vector<int>> handle_nodes;
};

/// Weights of the first `columns` handles (all when −1) at every node (#N × columns, dense, not truncated).
/// Every handle constrains the solve; only the requested columns are back-substituted. Throws when a set is
/// empty, sets overlap, an index is out of range, or the factorization fails (a part touching no handle).
Eigen::MatrixXd handle_weights(const RowMatrixX3d& nodes, const RowMatrixX4i& tets, const HandleSets& handles,
                               int columns = -1);

/// Solves the same constrained minimization for arbitrary values on the constrained nodes (#N result):
/// `values` gives the prescribed value per entry of `constrained` (used by the linear-precision test).
Eigen::VectorXd biharmonic_interpolate(const RowMatrixX3d& nodes, const RowMatrixX4i& tets,
                                       const std::vector<int>& constrained, const Eigen::VectorXd& values);

/// How point-handle weights become the reduced basis B.
struct BasisOptions {
  double drop_below = 1e-3;    ///< |w| below this is dropped (relative to 1, the value at the handle)
  int max_influences = 8;      ///< at most this many point handles per node (the largest |w|)
  bool affine = false;         ///< affine point handles: 4 functions per handle, w_j·{1, (x̄ − c_j)/ℓ}
  double affine_length = 0.1;  ///< ℓ [m]: scales the linear functions so all coordinates are in metres
};

/// B from the point-handle columns of `weights` (#N × P), zero rows on `attached` nodes.
/// @param[in] nodes         #N by 3 template positions (centres c_j of affine handles) [m]
/// @param[in] handle_nodes  P node indices (c_j = nodes.row(handle_nodes[j]))
Subspace point_handle_subspace(const Eigen::MatrixXd& weights, const std::vector<char>& attached,
                               const RowMatrixX3d& nodes, const std::vector<int>& handle_nodes,
                               const BasisOptions& options);

}  // namespace sflsh::reduced
