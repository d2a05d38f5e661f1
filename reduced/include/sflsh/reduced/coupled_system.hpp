#pragma once
// Unknowns outside the body solved in the body's own Newton solve (docs/contact.md "One solve for objects and
// body"): e.g. the six coordinates y = (Δx, θ) of each free rigid object touching the skin. The solver's unknowns
// become x = [q; y] and Φ gains
//   Φ_c(P(q), y)   P: the posed positions of the system's candidate nodes, p_i(q) = z_i + A_i Σ_s b_is t_s,
// whose derivatives the system gives per candidate (node × node 3×3 blocks only: Φ_c is separable over nodes
// given y) and against y (reduced/coupled_term.hpp chains them to q). y is the increment over the current
// substep from the system's own state at its start; the system advances itself when the solver commits.
#include <sflsh/meshing/types.hpp>

#include <Eigen/Core>

#include <vector>

namespace sflsh::reduced {

/// Φ_c's derivatives at (P, y): gradient [N] per candidate row and in y, Hessian blocks [N/m].
struct CoupledDerivatives {
  meshing::RowMatrixX3d node_gradient;        ///< C × 3: ∂Φ_c/∂p_c
  Eigen::VectorXd gradient;                   ///< ∂Φ_c/∂y
  std::vector<Eigen::Matrix3d> node_hessian;  ///< per candidate: ∂²Φ_c/∂p_c²
  Eigen::MatrixXd node_mixed;                 ///< 3C × size: ∂²Φ_c/∂p∂y
  Eigen::MatrixXd hessian;                    ///< size × size: ∂²Φ_c/∂y²
  void reset(Eigen::Index candidates, Eigen::Index size, bool with_hessian);
};

class CoupledSystem {
 public:
  virtual ~CoupledSystem() = default;
  /// Its coordinates y.
  virtual Eigen::Index size() const = 0;
  /// The mesh nodes it may act on (ascending; none constrained).
  virtual const std::vector<int>& nodes() const = 0;
  /// Before a substep from t0 over dt, with the posed positions at t0 and the skinned positions at t0 + dt of
  /// every entry of nodes(): picks the candidates and sets up the substep's energy (y = 0 is the system's state
  /// at t0).
  virtual void begin_substep(double t0, double dt, const meshing::RowMatrixX3d& p_start,
                             const meshing::RowMatrixX3d& p_skinned_end) = 0;
  /// Entries of nodes() that evaluate() may depend on in this substep.
  virtual const std::vector<int>& candidates() const = 0;
  /// Φ_c [J] at the candidates' posed positions P (one row per candidate) and y; derivatives when not null
  /// (Hessian blocks only when `with_hessian`), positive semi-definite as a whole.
  virtual double evaluate(const meshing::RowMatrixX3d& P, const Eigen::VectorXd& y, CoupledDerivatives* derivatives,
                          bool with_hessian) const = 0;
  /// After a converged substep: true accepts it; false means the system stiffened itself (penetration over its
  /// tolerance) and the substep is solved again from the same start (at most max_refinements() times).
  virtual bool accept_substep(const meshing::RowMatrixX3d& P_end, const Eigen::VectorXd& y) = 0;
  virtual int max_refinements() const { return 6; }
  /// The substep is final: the system moves its own state to y.
  virtual void commit_substep(const meshing::RowMatrixX3d& P_end, const Eigen::VectorXd& y) = 0;
  /// The solver's step ladder: save() at the start of a step, restore() before it is tried again smaller.
  virtual void save() = 0;
  virtual void restore() = 0;
};

}  // namespace sflsh::reduced
