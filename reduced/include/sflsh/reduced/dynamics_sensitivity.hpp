#pragma once
// The derivative of the per-vertex dynamics amplitudes σ_n, σ_t (docs/physics.md §4 steps 4–6; the fit's σ of
// SFLSH §5) with respect to parameters p, from a stream of skin displacements u_t and their derivatives du_t/dp
// (SkinDisplacementMap with the forward sensitivities of reduced_sensitivity.hpp). With d̃ = u − ū (mean zero):
//   σ_n² = mean_t (n·d̃)²,   σ² = mean_t |d̃|²,   σ_t² = σ² − σ_n²,
//   dσ_n = mean_t[(n·d̃)(n·du)] / σ_n,   dσ_t = (mean_t[d̃·du] − mean_t[(n·d̃)(n·du)]) / σ_t,
// where mean_t[d̃·du] = mean_t[u·du] − ū·mean_t[du] (the mean of du drops out against d̃). At a vertex with σ = 0
// the amplitude is not differentiable (|·| at 0); the derivative is reported as 0 there (a subgradient).
#include <sflsh/meshing/types.hpp>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace sflsh::reduced {

class DynamicsAmplitudeSensitivity {
 public:
  /// @param[in] normals     unit normals per vertex (R × 3)
  /// @param[in] parameters  number of parameters m (columns of du/dp)
  DynamicsAmplitudeSensitivity(meshing::RowMatrixX3d normals, int parameters);
  /// One frame: u (R × 3) [m] and du/dp (3R × m, row 3r + axis) [m per unit of p].
  void add(const meshing::RowMatrixX3d& displacement, const Eigen::MatrixXd& derivative);
  /// One frame in the reduced coordinates: u (R × 3) [m], the skin map K B (R × S, SkinDisplacementMap::
  /// skin_basis(); it must outlive this object) and dq/dp (3S × m) [per unit of p]. The same sums as add(u, du) with
  /// du = (K B ⊗ I₃) dq, without forming du: per vertex only its few skin functions' rows of dq are read (rows
  /// contiguous), and Σ du is kept as Σ dq. A stream takes one form of add() only.
  void add(const meshing::RowMatrixX3d& displacement, const Eigen::SparseMatrix<double, Eigen::RowMajor>& skin_basis,
           const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>& dq);
  int frames() const { return frames_; }
  Eigen::VectorXd sigma_normal() const;              ///< σ_n (R) [m]
  Eigen::VectorXd sigma_tangent() const;             ///< σ_t (R) [m]
  Eigen::MatrixXd sigma_normal_derivative() const;   ///< dσ_n/dp (R × m)
  Eigen::MatrixXd sigma_tangent_derivative() const;  ///< dσ_t/dp (R × m)

 private:
  using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  /// Σ du at vertex r (3 × m), from Σ du or from Σ dq through the skin map.
  Eigen::Matrix<double, 3, Eigen::Dynamic> du_sum(Eigen::Index r) const;

  meshing::RowMatrixX3d normals_, sum_u_;
  Eigen::VectorXd sum_uu_, sum_un_, sum_unun_;
  Eigen::MatrixXd sum_du_;                                              ///< Σ du (3R × m), add(u, du)
  RowMatrix sum_dq_;                                                    ///< Σ dq (3S × m), reduced add()
  const Eigen::SparseMatrix<double, Eigen::RowMajor>* skin_ = nullptr;  ///< the reduced add()'s skin map
  RowMatrix sum_u_du_, sum_un_dun_;                                     ///< Σ u·du, Σ (n·u)(n·du) (R × m)
  int frames_ = 0;
};

}  // namespace sflsh::reduced
