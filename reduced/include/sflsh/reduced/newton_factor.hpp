#pragma once
// The Cholesky factor of the reduced Newton system H Δ = −g. Dense (Eigen::LLT) over all coordinates, or, when a
// contiguous block P of the coordinates is a local patch (local_basis.hpp: its Hessian block C = H_PP is a mesh's,
// sparse), by the Schur complement on the others O:
//   C = L_C L_Cᵀ (sparse),  X = C⁻¹ H_PO,  S = H_OO − H_POᵀ X = L_S L_Sᵀ (dense),
//   Δ_O = S⁻¹ (r_O − H_POᵀ C⁻¹ r_P),  Δ_P = C⁻¹ r_P − X Δ_O.
// For a patch of n nodes beside m other coordinates that costs a sparse factorization of 3n and m solves with it
// instead of a dense (3n + m)³/3; the solution is the same to round-off.
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <memory>
#include <vector>

namespace sflsh::reduced {

class NewtonFactor {
 public:
  /// Factors the symmetric H (lower and upper stored); the coordinates [patch_begin, patch_begin + patch_size) by the
  /// Schur complement when patch_size > 0. Returns false when H (or a block) is not positive definite.
  bool compute(const Eigen::MatrixXd& hessian, Eigen::Index patch_begin = 0, Eigen::Index patch_size = 0);
  /// H⁻¹ r (after a successful compute()).
  Eigen::VectorXd solve(const Eigen::VectorXd& r) const;
  bool ok() const { return ok_; }

 private:
  bool ok_ = false;
  Eigen::Index begin_ = 0, size_ = 0;
  std::vector<Eigen::Index> others_;   ///< the coordinates outside the patch, ascending
  Eigen::LLT<Eigen::MatrixXd> dense_;  ///< H itself without a patch, else the Schur complement S
  /// L_C, made anew by each compute() and never changed after: copies (the solver's checkpoints) share it.
  std::shared_ptr<const Eigen::SimplicialLLT<Eigen::SparseMatrix<double>>> patch_;
  Eigen::MatrixXd coupling_;  ///< H_PO (patch × others)
  Eigen::MatrixXd x_;         ///< X = C⁻¹ H_PO
};

}  // namespace sflsh::reduced
