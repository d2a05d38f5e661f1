#pragma once
// The inertia and gravity terms of the incremental potential restricted to the subspace (physics.md §5):
// for every node i the basis moves (the "active" nodes), p_i(q) = z_i + A_i u_i(q) with z_i = A_i x_D,i + d_i
// (the skinned prescribed state) and u_i = Σ_s b_is t_s, so
//   Σ_i m_i/(2h²) |p_i(q) − p̃_i|² − Σ_i m_i gᵀ p_i(q) = const + cᵀq + ½ qᵀ H q,
//   c_s = Σ_i b_is m_i A_iᵀ((z_i − p̃_i)/h² − g),   H_(s,r) = Σ_i m_i b_is b_ir A_iᵀA_i / h².
// The potential is exactly quadratic in q within a step. With skinned node maps A_i = Σ_k w_ik R_k(t),
// H = Σ_{k≤l} T_kl(s, r) (R_kᵀR_l + R_lᵀR_k)/(1 + δ_kl) / h² with T_kl(s, r) = Σ_i m_i w_ik w_il b_is b_ir
// precomputed once: a step costs one 3×3 product per joint pair and entry of T, not a pass over the nodes.
#include <sflsh/model/problem.hpp>
#include <sflsh/model/skinned_trajectory.hpp>
#include <sflsh/reduced/subspace.hpp>

#include <vector>

namespace sflsh::reduced {

class ReducedInertia {
 public:
  ReducedInertia(const model::Problem& problem, const Subspace& subspace);

  const std::vector<int>& active_nodes() const { return active_; }
  /// Node maps of the active nodes at t and z_i from the prescribed state x_D (3N).
  void set_time(double t, const Eigen::VectorXd& x_prescribed);
  /// c for the step to the current time with prediction p̃ (active × 3), step h; inertia off → only gravity.
  Eigen::VectorXd linear_term(const meshing::RowMatrixX3d& p_tilde, double h, bool inertia) const;
  /// H (3S × 3S) at the current time for step h; zero when inertia is off.
  void mass_hessian(double h, Eigen::MatrixXd& H) const;
  /// The cross-time mass M(t, t') = Σ_i m_i b_is b_ir A_i(t)ᵀ A_i(t') (3S × 3S, not symmetric) between the current
  /// time t and `t_other`: ∂p_i(t')/∂q = A_i(t') b_i, so M(t, t') dq' is the reduced inertia pull-back of a posed
  /// displacement made at t'. M(t, t)/h² = mass_hessian(h). Used by forward sensitivities (reduced_sensitivity.hpp).
  void cross_mass(double t_other, Eigen::MatrixXd& M) const;
  /// Posed positions of the active nodes at the current time for coordinates q.
  void posed(const Eigen::VectorXd& q, meshing::RowMatrixX3d& p) const;
  /// The node maps (A_i, d_i) of the active nodes at the current time, and their posed positions at q = 0.
  const model::NodeFrame& frame() const { return frame_; }
  const meshing::RowMatrixX3d& posed_prescribed() const { return z_; }
  /// u_i = Σ_s b_is t_s at the active nodes (active × 3).
  void displacement(const Eigen::VectorXd& q, meshing::RowMatrixX3d& u) const;

 private:
  struct PairTerm {
    int k = 0, l = 0;
    std::vector<int> s, r;
    std::vector<double> value;
  };
  void build_pairs(const model::SkinnedTrajectory& skinned);

  const model::Problem& problem_;
  const Subspace& subspace_;
  std::vector<int> active_;
  std::vector<double> mass_;           ///< per active node
  model::NodeFrame frame_;         ///< per active node
  meshing::RowMatrixX3d z_;            ///< per active node
  const model::SkinnedTrajectory* skinned_ = nullptr;
  std::vector<PairTerm> pairs_;
  model::JointTransforms joints_;
};

}  // namespace sflsh::reduced
