#pragma once
// A coupled system (coupled_system.hpp) as a term of the reduced incremental potential over x = [q; y]: its
// candidates' posed positions p_c(q) = z_c + A_c Σ_s b_cs t_s, and the chain rule
//   ∂Φ_c/∂t_s = Σ_c b_cs A_cᵀ ∂Φ_c/∂p_c,   ∂²Φ_c/∂t_s∂t_r = Σ_c b_cs b_cr A_cᵀ (∂²Φ_c/∂p_c²) A_c,
//   ∂²Φ_c/∂t_s∂y = Σ_c b_cs A_cᵀ ∂²Φ_c/∂p_c∂y,
// with y at x[offset, offset + size). With a tracking root (root_tracking.hpp) at x[root, root + 6) the candidates
// sit at the deviated positions R(θ)(p_c(q) − c) + c + τ, and the root's rows and columns follow by the chain rule
// (add_root_node_blocks; the node × y blocks through ∂p/∂θ_k = ∂_kR (p − c), ∂p/∂τ = I, ∂p/∂t_s = b_s R A).
#include <sflsh/reduced/coupled_system.hpp>
#include <sflsh/reduced/reduced_inertia.hpp>
#include <sflsh/reduced/reduced_terms.hpp>
#include <sflsh/reduced/rotation_vector.hpp>
#include <sflsh/reduced/subspace.hpp>

namespace sflsh::reduced {

class CoupledTerm final : public ReducedTerm {
 public:
  /// Throws when the system acts on a node no basis function moves.
  CoupledTerm(CoupledSystem& system, const Subspace& subspace, const ReducedInertia& inertia, Eigen::Index offset);
  std::string_view name() const override { return "coupled"; }
  Eigen::Index offset() const { return offset_; }
  /// A tracking root's coordinates at x[offset, offset + 6) (before this term's y), deviating the positions about
  /// the pivot set by begin().
  void set_root(Eigen::Index offset) { root_offset_ = offset; }
  /// begin_substep of the system; `inertia` must be at the substep's end, p_start the active nodes' posed
  /// positions at t0 (deviated by the root at t0 when there is one); `start` the root's frame at t0 and `pivot`
  /// the pivot at the substep's end (with a root).
  void begin(double t0, double dt, const meshing::RowMatrixX3d& p_start, const RootFrame* start = nullptr,
             const Eigen::Vector3d& pivot = Eigen::Vector3d::Zero());
  double value(const Eigen::VectorXd& x) const override;
  void add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const override;
  void add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const override;
  /// The system's accept_substep and commit_substep at x.
  bool accept(const Eigen::VectorXd& x);
  void commit(const Eigen::VectorXd& x);
  CoupledSystem& system() { return system_; }

 private:
  /// The candidates' positions at x (deviated by the root when there is one); the undeviated ones in `posed`.
  meshing::RowMatrixX3d candidate_positions(const Eigen::VectorXd& x, meshing::RowMatrixX3d* posed = nullptr) const;

  CoupledSystem& system_;
  const Subspace& subspace_;
  const ReducedInertia& inertia_;
  Eigen::Index offset_;
  std::vector<int> active_of_;         ///< per entry of system.nodes(): its active index
  std::vector<int> candidate_active_;  ///< per candidate of the substep: its active index
  Eigen::Index root_offset_ = -1;      ///< the root's coordinates in x, or −1 (prescribed skeleton)
  Eigen::Vector3d pivot_ = Eigen::Vector3d::Zero();
};

}  // namespace sflsh::reduced
