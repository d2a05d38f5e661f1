#pragma once
// Laplacian (harmonic) interpolation on a tet mesh: boundary values prescribed, interior values
// minimize the discrete Dirichlet energy. One sparse SPD factorization per mesh, then a solve per use.
// Used to retarget node positions (docs/architecture.md §3) and to carry surface fields into the volume.
#include <sflsh/meshing/types.hpp>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <memory>
#include <vector>

namespace sflsh::meshing {

class HarmonicInterpolator {
 public:
  /// Assembles the P1 Laplacian of (nodes, tets) with per-tet weight V_e·(V̄/V_e)^stiffening — with
  /// stiffening > 0 small tets move more rigidly, which keeps them valid under large boundary motion
  /// (Jacobian-based stiffening of mesh-motion schemes) — and factorizes its interior block.
  /// `fixed[i]` marks nodes whose values are prescribed. Throws when the interior block is singular
  /// (an interior component without any fixed node).
  HarmonicInterpolator(const RowMatrixX3d& nodes, const RowMatrixX4i& tets, const std::vector<char>& fixed,
                       double stiffening = 1.0);

  /// Values at every node (rows = nodes, any number of columns): rows of `values` at fixed nodes are
  /// kept, the others are replaced by the harmonic interpolation.
  Eigen::MatrixXd extend(const Eigen::MatrixXd& values) const;

  int num_nodes() const { return static_cast<int>(fixed_.size()); }
  int num_free() const { return static_cast<int>(free_.size()); }

 private:
  std::vector<char> fixed_;
  std::vector<int> free_;                                                       ///< free node indices
  std::vector<int> fixed_list_;                                                 ///< fixed node indices
  Eigen::SparseMatrix<double> coupling_;                                        ///< L_FB (free × fixed)
  std::shared_ptr<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>> solver_;  ///< of L_FF
};

}  // namespace sflsh::meshing
