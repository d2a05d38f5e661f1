#pragma once
// The inertia and gravity terms of the incremental potential restricted to the subspace (docs/physics.md §5,
// model/time_integrator.hpp): for every node i the basis moves (the "active" nodes), p_i(q) = z_i + A_i u_i(q)
// with z_i = A_i x_D,i + d_i (the skinned prescribed state) and u_i = Σ_s b_is t_s; every other node sits at
// p_j = z_j. With the node-level mass M (lumped m_i or consistent M_ij, model/mass.hpp),
//   1/(2ĥ²)(p(q) − p̃)ᵀM(p(q) − p̃) − gᵀMp(q) = const + cᵀq + ½ qᵀ H q,
//   c_s = Σ_{i active} b_is A_iᵀ (Σ_j M_ij (z_j − p̃_j)/ĥ² − m_i g),   H_(s,r) = Σ_{i,j active} M_ij b_is b_jr A_iᵀA_j /
//   ĥ²,
// (gᵀMp = Σ_i m_i gᵀp_i: the row sums of the consistent matrix are the lumped masses). The j of the linear term
// run over the "inertia nodes": the active nodes and, for a consistent mass, their mass neighbours that no
// basis function moves (attached nodes next to free ones), whose targets p̃_j reach q through M_ij.
// The potential is exactly quadratic in q within a step. With skinned node maps A_i = Σ_k w_ik R_k(t),
// H = Σ_kl T_kl(s, r) R_kᵀR_l / ĥ² with T_kl precomputed once (joint_pair_mass.hpp): a step costs one 3×3
// product per joint pair and entry of T, not a pass over the nodes.
#include <sflsh/model/problem.hpp>
#include <sflsh/model/skinned_trajectory.hpp>
#include <sflsh/reduced/joint_pair_mass.hpp>
#include <sflsh/reduced/subspace.hpp>

#include <vector>

namespace sflsh::reduced {

class ReducedInertia {
 public:
  ReducedInertia(const model::Problem& problem, const Subspace& subspace);

  /// The nodes the basis moves, ascending; they are the first entries of inertia_nodes().
  const std::vector<int>& active_nodes() const { return active_; }
  /// The nodes the inertia sees: the active nodes, then (consistent mass) their mass neighbours without basis
  /// functions, ascending. Posed positions, targets and histories of the reduced model are over these nodes.
  const std::vector<int>& inertia_nodes() const { return nodes_; }
  int num_active() const { return static_cast<int>(active_.size()); }
  model::MassKind mass_kind() const { return kind_; }

  /// Node maps of the inertia nodes at t and z_i from the prescribed state x_D (3N).
  void set_time(double t, const Eigen::VectorXd& x_prescribed);
  double time() const { return t_; }

  /// Jᵀ M v = Σ_{i active} b_i ⊗ A_iᵀ Σ_j M_ij v_j for a posed field v on the inertia nodes (3 per node): the
  /// reduced pull-back of M v, with J = ∂p/∂q the posed Jacobian at the current time.
  Eigen::VectorXd pull_back_mass(const Eigen::VectorXd& v) const;
  /// c of the inertia alone for the target p̃ (3 per inertia node) and ĥ [s]: Jᵀ M (z − p̃)/ĥ².
  Eigen::VectorXd inertia_linear_term(const Eigen::VectorXd& p_tilde, double h_eff) const;
  /// c of gravity: −Σ_i b_i ⊗ m_i A_iᵀ g.
  Eigen::VectorXd gravity_linear_term() const;
  /// Both: c for the step to the current time with target p̃ (inertia nodes × 3) and ĥ = h; inertia off → gravity only.
  Eigen::VectorXd linear_term(const meshing::RowMatrixX3d& p_tilde, double h, bool inertia) const;
  /// H = JᵀMJ/ĥ² (3S × 3S) at the current time.
  void mass_hessian(double h_eff, Eigen::MatrixXd& H) const;
  /// The cross-time mass M(t, t') = Σ_ij M_ij b_is b_jr A_i(t)ᵀ A_j(t') (3S × 3S, not symmetric) between the current
  /// time t and `t_other`: ∂p_j(t')/∂q = A_j(t') b_j, so M(t, t') dq' is the reduced inertia pull-back of a posed
  /// displacement made at t'. M(t, t)/ĥ² = mass_hessian(ĥ). Used by forward sensitivities (reduced_sensitivity.hpp).
  void cross_mass(double t_other, Eigen::MatrixXd& M) const;

  /// Posed positions of the inertia nodes at the current time for coordinates q (z_i + A_i u_i; z_j off the basis),
  /// one row per node, or node-major (3 entries per node, the layout of the posed history).
  void posed(const Eigen::VectorXd& q, meshing::RowMatrixX3d& p) const;
  void posed(const Eigen::VectorXd& q, Eigen::VectorXd& p) const;
  /// J v: the posed rate of the inertia nodes for a coordinate rate v at frozen maps (3 per node, 0 off the basis).
  Eigen::VectorXd posed_rate(const Eigen::VectorXd& v) const;
  /// The node maps (A_i, d_i) of the inertia nodes at the current time, and their posed positions at q = 0.
  const model::NodeFrame& frame() const { return frame_; }
  const meshing::RowMatrixX3d& posed_prescribed() const { return z_; }
  /// u_i = Σ_s b_is t_s at the active nodes (active × 3).
  void displacement(const Eigen::VectorXd& q, meshing::RowMatrixX3d& u) const;
  /// Lumped mass per inertia node [kg].
  const std::vector<double>& lumped_mass() const { return mass_; }

 private:
  void build_consistent(const model::Problem& problem);
  void posed_into(const Eigen::VectorXd& q, double* out) const;  ///< node-major, 3 per inertia node

  const model::Problem& problem_;
  const Subspace& subspace_;
  model::MassKind kind_ = model::MassKind::lumped;
  std::vector<int> active_;
  std::vector<int> nodes_;    ///< inertia nodes: active_, then mass neighbours
  std::vector<double> mass_;  ///< lumped mass per inertia node
  // Consistent M over the active rows (CSR): row a holds (inertia-node index, M_ij) for every j with M_ij ≠ 0.
  std::vector<int> row_offset_, row_column_;
  std::vector<double> row_value_;
  double t_ = 0.0;
  model::NodeFrame frame_;   ///< per inertia node
  meshing::RowMatrixX3d z_;  ///< per inertia node
  const model::SkinnedTrajectory* skinned_ = nullptr;
  JointPairMass pairs_;
  model::JointTransforms joints_;
};

}  // namespace sflsh::reduced
