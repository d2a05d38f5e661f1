#pragma once
// Non-negative least squares, min ‖A x − b‖² s.t. x ≥ 0, by the active-set method of Lawson & Hanson
// (1974, "Solving Least Squares Problems", ch. 23, algorithm NNLS), in normal-equation form: it works on
// G = AᵀA and h = Aᵀb, so tall systems (thousands of rows, hundreds of columns) cost one K × K Gram matrix.
// Hand-written: Debian's Eigen 3.4 has no NNLS module, and the bound-constrained solvers of PETSc TAO
// return interior approximations rather than the exact, sparse active set cubature needs.
#include <Eigen/Core>

namespace sflsh::reduced {

struct NnlsResult {
  Eigen::VectorXd x;       ///< the minimizer (≥ 0)
  int iterations = 0;      ///< outer iterations (variables released)
  bool converged = false;  ///< KKT conditions met within tolerance
};

/// @param[in] G  K × K symmetric positive semi-definite Gram matrix AᵀA
/// @param[in] h  K right-hand side Aᵀb
/// @param[in] tolerance  KKT tolerance on the gradient, relative to max |h|
NnlsResult nnls_normal_equations(const Eigen::MatrixXd& G, const Eigen::VectorXd& h, double tolerance = 1e-10,
                                 int max_iterations = 0);

}  // namespace sflsh::reduced
