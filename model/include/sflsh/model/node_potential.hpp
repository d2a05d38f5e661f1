#pragma once
// An extra energy on the posed (world) positions of some nodes, separable per node:
//   U(p) = Σ_k u_k(p_{n_k}),   p_i = A_i x_i + d_i   (problem.hpp)
// Contact with obstacles that are fixed during a solve (rigid objects, another body's surface from the last
// coupling iterate) has this form. Both integrators add it to the incremental potential Φ with
//   ∇_x = A_iᵀ ∇u,   ∇²_x = A_iᵀ ∇²u A_i   (a 3×3 diagonal block per node; B_iᵀ A_iᵀ ∇²u A_i B_i reduced).
// A scene that asks for no contact puts no potential into the problem, so no proximity structure exists.
#include <sflsh/meshing/types.hpp>

#include <Eigen/Core>

#include <string>
#include <vector>

namespace sflsh::model {

class NodePotential {
 public:
  virtual ~NodePotential() = default;

  /// The mesh nodes it may act on (ascending; none of them constrained).
  virtual const std::vector<int>& nodes() const = 0;

  /// Called before each substep solve from t0 to t0 + dt, with the posed positions at t0 (one row per entry
  /// of nodes()) and the skinned positions at t0 + dt (the rest shape carried by the end-of-step pose).
  /// The potential moves its obstacles to t0 + dt and picks the candidates: the entries that can touch an
  /// obstacle within this substep. Returns false when there are none, so the term is idle in this solve.
  virtual bool begin_substep(double t0, double dt, const meshing::RowMatrixX3d& p_start,
                             const meshing::RowMatrixX3d& p_skinned_end) = 0;

  /// Entries of nodes() that evaluate() may be non-zero on during this substep.
  virtual const std::vector<int>& candidates() const = 0;

  /// u of candidate k (an index into candidates()) at posed position p [J]; its gradient [N] and a positive
  /// semi-definite Hessian [N/m] when not null.
  virtual double evaluate(int k, const Eigen::Vector3d& p, Eigen::Vector3d* gradient,
                          Eigen::Matrix3d* hessian) const = 0;

  /// After a converged substep, with the posed positions of the candidates at its end (one row per entry of
  /// candidates()): true accepts it. False means the potential changed itself (e.g. raised a penalty
  /// stiffness because a node is deeper than the tolerance) and asks the integrator to solve the substep
  /// again from the same start; integrators do so at most `max_refinements()` times.
  virtual bool accept_substep(const meshing::RowMatrixX3d& p_end) = 0;
  virtual int max_refinements() const { return 4; }
  /// Why the last accept_substep refused a substep no refinement can fix any more (its refinements are used up and
  /// the result is still over its tolerance, or not finite), in one line naming the object and the time; empty when
  /// it accepted or asked for a refinement. The integrator then fails the substep with this reason: its ladder
  /// tries smaller substeps, and a step that still fails stops the run with it (never a silent, kept violation).
  virtual std::string unresolved() const { return {}; }
};

}  // namespace sflsh::model
