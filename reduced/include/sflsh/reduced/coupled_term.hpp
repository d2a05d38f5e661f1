#pragma once
// A coupled system (coupled_system.hpp) as a term of the reduced incremental potential over x = [q; y]: its
// candidates' posed positions p_c(q) = z_c + A_c Σ_s b_cs t_s, and the chain rule
//   ∂Φ_c/∂t_s = Σ_c b_cs A_cᵀ ∂Φ_c/∂p_c,   ∂²Φ_c/∂t_s∂t_r = Σ_c b_cs b_cr A_cᵀ (∂²Φ_c/∂p_c²) A_c,
//   ∂²Φ_c/∂t_s∂y = Σ_c b_cs A_cᵀ ∂²Φ_c/∂p_c∂y,
// with y at x[offset, offset + size).
#include <sflsh/reduced/coupled_system.hpp>
#include <sflsh/reduced/reduced_inertia.hpp>
#include <sflsh/reduced/reduced_terms.hpp>
#include <sflsh/reduced/subspace.hpp>

namespace sflsh::reduced {

class CoupledTerm final : public ReducedTerm {
 public:
  /// Throws when the system acts on a node no basis function moves.
  CoupledTerm(CoupledSystem& system, const Subspace& subspace, const ReducedInertia& inertia, Eigen::Index offset);
  std::string_view name() const override { return "coupled"; }
  Eigen::Index offset() const { return offset_; }
  /// begin_substep of the system; `inertia` must be at the substep's end, p_start the active nodes' posed
  /// positions at t0.
  void begin(double t0, double dt, const meshing::RowMatrixX3d& p_start);
  double value(const Eigen::VectorXd& x) const override;
  void add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const override;
  void add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const override;
  /// The system's accept_substep and commit_substep at x.
  bool accept(const Eigen::VectorXd& x);
  void commit(const Eigen::VectorXd& x);
  CoupledSystem& system() { return system_; }

 private:
  meshing::RowMatrixX3d candidate_positions(const Eigen::VectorXd& x) const;

  CoupledSystem& system_;
  const Subspace& subspace_;
  const ReducedInertia& inertia_;
  Eigen::Index offset_;
  std::vector<int> active_of_;         ///< per entry of system.nodes(): its active index
  std::vector<int> candidate_active_;  ///< per candidate of the substep: its active index
};

}  // namespace sflsh::reduced
