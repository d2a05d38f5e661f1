#pragma once
// A coupled system (coupled_system.hpp) as a term of the reduced incremental potential over x = [q; y]: its
// candidates' posed positions p_c(q) = z_c + A_c Σ_s b_cs t_s, and the chain rule
//   ∂Φ_c/∂t_s = Σ_c b_cs A_cᵀ ∂Φ_c/∂p_c,   ∂²Φ_c/∂t_s∂t_r = Σ_c b_cs b_cr A_cᵀ (∂²Φ_c/∂p_c²) A_c,
//   ∂²Φ_c/∂t_s∂y = Σ_c b_cs A_cᵀ ∂²Φ_c/∂p_c∂y,
// with y at x[offset, offset + size). With a tracking skeleton (root_tracking.hpp) at x[root, root + size) the
// candidates sit at the deviated positions D_c(p_c(q)) (skeleton_deviation.hpp), and the deviation's rows and columns
// follow by the chain rule (add_deviation_node_blocks; the node × y blocks through ∂y/∂r and ∂y/∂t_s = b_s L A).
#include <sflsh/reduced/coupled_system.hpp>
#include <sflsh/reduced/reduced_inertia.hpp>
#include <sflsh/reduced/reduced_terms.hpp>
#include <sflsh/reduced/root_tracking.hpp>
#include <sflsh/reduced/subspace.hpp>

namespace sflsh::reduced {

class CoupledTerm final : public ReducedTerm {
 public:
  /// Throws when the system acts on a node no basis function moves.
  CoupledTerm(CoupledSystem& system, const Subspace& subspace, const ReducedInertia& inertia, Eigen::Index offset);
  std::string_view name() const override { return "coupled"; }
  Eigen::Index offset() const { return offset_; }
  /// A tracking skeleton's coordinates at x[offset, offset + skeleton.size()) (before this term's y), deviating the
  /// positions about the centres set by begin().
  void set_root(Eigen::Index offset, const SkeletonDeviation& skeleton) {
    root_offset_ = offset;
    skeleton_ = &skeleton;
  }
  /// begin_substep of the system; `inertia` must be at the substep's end, p_start the active nodes' posed
  /// positions at t0 (deviated by the skeleton at t0 when it tracks); `start` the deviation's frame at t0 and
  /// `pose` the centres at the substep's end (with a tracking skeleton).
  void begin(double t0, double dt, const meshing::RowMatrixX3d& p_start, const DeviationFrame* start = nullptr,
             const DeviationPose& pose = {});
  double value(const Eigen::VectorXd& x) const override;
  bool add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const override;
  bool add_hessian(const Eigen::VectorXd& x, Eigen::MatrixXd& hessian) const override;
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
  Eigen::Index root_offset_ = -1;      ///< the deviation's coordinates in x, or −1 (prescribed skeleton)
  const SkeletonDeviation* skeleton_ = nullptr;
  DeviationPose pose_;
};

}  // namespace sflsh::reduced
