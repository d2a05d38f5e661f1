#pragma once
// Internal to the fields code: the box-constrained convex QP of bounded biharmonic weights,
//   minimize ½ xᵀ Q x   subject to  x_k = b_k (k ∈ known),  0 ≤ x_j ≤ 1 (j ∉ known),
// with Q symmetric positive semi-definite and positive definite on the unknowns.
#include <sflsh/material/surface_operators.hpp>

#include <vector>

namespace sflsh::material::detail {

struct BoxQpSettings {
  int max_iterations = 200;            ///< primal-dual iterations, then as many primal ones at most
  double primal_tolerance = 1e-10;     ///< bound violation accepted before clamping
  double multiplier_tolerance = 1e-8;  ///< KKT multiplier sign tolerance, relative to max diag(Q)
};

struct BoxQpResult {
  Eigen::VectorXd x;                    ///< the minimizer, clamped exactly into [0, 1] on the unknowns
  int iterations = 0;                   ///< sparse factorizations spent (primal-dual + primal fallback)
  bool used_fallback = false;           ///< true when the primal-dual active-set iteration cycled
  double max_bound_violation = 0;       ///< before clamping
  double max_multiplier_violation = 0;  ///< wrong-sign multiplier magnitude at exit (relative), ≤ tolerance
};

/// Solves the QP from `start` (the unconstrained minimizer, #V entries, `known` entries already set).
/// Method: primal-dual active set (Hintermüller, Ito, Kunisch 2002, the iteration of libigl's
/// active_set used by igl::bbw): the sets of variables held at 0 and at 1 are updated from the
/// bound violations of the free variables and the signs of the multipliers (gradient entries) of the
/// held ones, with a sparse LDLᵀ re-solve of the free block per update, until the sets repeat. Equal
/// consecutive sets are exactly the KKT conditions, hence the global minimum (convex QP). Q = L M⁻¹ L
/// is not an M-matrix, so this iteration may cycle; a repeated earlier set (or max_iterations) switches
/// to a primal active-set method (Nocedal & Wright 2006, Alg. 16.3: feasible iterates, one constraint
/// added or dropped per step, monotone objective), which terminates. Throws sflsh::Error when a
/// factorization fails or the fallback exceeds its iteration budget.
BoxQpResult solve_box_qp(const SparseMatrixd& Q, const std::vector<int>& known, const Eigen::VectorXd& start,
                         const BoxQpSettings& settings);

/// The free-block solve shared with the unconstrained basis: Q restricted to rows/columns `free`.
SparseMatrixd principal_submatrix(const SparseMatrixd& Q, const std::vector<int>& free, const std::vector<int>& local);

}  // namespace sflsh::material::detail
