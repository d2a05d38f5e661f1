#pragma once
// The reduced kinematics (docs/physics.md §2.1, Wang et al. 2015): the unposed elastic state is
//   x = x_D(t) + (B ⊗ I₃) q,
// with x_D the rest positions with the prescribed (attached or driven) components at their values, B an
// N × S sparse matrix of scalar basis functions b_s (one per point handle for translational handles,
// w_j·{1, (x̄ − c_j)/ℓ} for affine ones) and q = [t_0; …; t_{S−1}] ∈ R^{3S} the handle coordinates [m].
// Rows of B at attached nodes are zero: bone handles are bound to the prescribed skeleton, so in the
// unposed frame they do not move and carry no coordinates.
#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <vector>

namespace sflsh::reduced {

using SparseRowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

struct Subspace {
  SparseRowMatrix basis;  ///< B (N × S)

  int num_nodes() const { return static_cast<int>(basis.rows()); }
  int num_functions() const { return static_cast<int>(basis.cols()); }
  int num_dofs() const { return 3 * num_functions(); }
  /// x += (B ⊗ I₃) q  (x: 3N node-major, q: 3S).
  void add_displacement(const Eigen::VectorXd& q, Eigen::Ref<Eigen::VectorXd> x) const;
  /// Nodes with at least one non-zero entry in their row, ascending.
  std::vector<int> active_nodes() const;
  /// (B ⊗ I₃)ᵀ v for a 3N vector v (the reduced gradient of a full-space one).
  Eigen::VectorXd project_gradient(const Eigen::VectorXd& v) const;
};

}  // namespace sflsh::reduced
