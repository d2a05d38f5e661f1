#pragma once
// The problem's node potentials (contact, model/node_potential.hpp) in the reduced incremental potential:
// with p_i(q) = z_i + A_i Σ_s b_is t_s (z_i: posed at q = 0),
//   U(q) = Σ_k u_k(p_{n_k}(q)),   ∂U/∂t_s = Σ_k b_{n_k s} A_kᵀ ∇u_k,   ∂²U/∂t_s∂t_r = Σ_k b_ks b_kr A_kᵀ ∇²u_k A_k,
// summed over each potential's candidates of the substep only, so an idle or absent potential costs nothing.
// With a tracking root (root_tracking.hpp) every position is carried by the root deviation, p ↦ R(θ)(p − c) + c + τ,
// and the gradient and Hessian gain the root's rows: ∂p/∂t_s = b_s R A, ∂p/∂τ = I, ∂p/∂θ_k = ∂_kR (p − c).
#include <sflsh/model/problem.hpp>
#include <sflsh/reduced/reduced_inertia.hpp>
#include <sflsh/reduced/rotation_vector.hpp>
#include <sflsh/reduced/subspace.hpp>

#include <Eigen/Core>

#include <vector>

namespace sflsh::reduced {

/// The posed position z_a + A_a Σ_s b_as t_s of active node a (an index into inertia.active_nodes()) at the
/// inertia's current time; q may be longer than 3S (extra coordinates after it are ignored).
Eigen::Vector3d posed_node(const Subspace& subspace, const ReducedInertia& inertia, const Eigen::VectorXd& q, int a);

/// Adds the root's rows and columns of one node's contribution to a Hessian over x = [q; θ; τ; …] (the root at
/// root.offset): u of the deviated position y = R(p − c) + c + τ, with p the node's posed position before the
/// deviation, ∇u = g and ∇²u = H at y, A the node's map and `node` its mesh index (its basis row). Also adds the
/// soft-tissue block (R A)ᵀ H (R A) b_s b_r.
void add_root_node_blocks(const Subspace& subspace, const RootFrame& root, int node, const Eigen::Matrix3d& A,
                          const Eigen::Vector3d& p, const Eigen::Vector3d& g, const Eigen::Matrix3d& H,
                          Eigen::MatrixXd& hessian);

class ReducedPotentials {
 public:
  /// Throws when a potential acts on a node without basis functions (it could not respond).
  ReducedPotentials(const model::Problem& problem, const Subspace& subspace, const std::vector<int>& active_nodes);

  bool empty() const { return potentials_.empty(); }
  /// begin_substep of every potential; `inertia` must be set to the end time, p_start are the active nodes'
  /// posed positions at t0. Returns whether any potential has candidates.
  /// `root` (may be null) carries the skinned end positions (the root at the start of the substep).
  bool begin(double t0, double dt, const meshing::RowMatrixX3d& p_start, const ReducedInertia& inertia,
             const RootFrame* root = nullptr);
  bool active() const { return !terms_.empty(); }
  /// With `root`, q is x = [q; θ; τ] and the gradient and Hessian also fill the root's rows and columns.
  double energy(const Eigen::VectorXd& q, const ReducedInertia& inertia, const RootFrame* root = nullptr) const;
  void add_gradient(const Eigen::VectorXd& q, const ReducedInertia& inertia, Eigen::VectorXd& gradient,
                    const RootFrame* root = nullptr) const;
  void add_hessian(const Eigen::VectorXd& q, const ReducedInertia& inertia, Eigen::MatrixXd& hessian,
                   const RootFrame* root = nullptr) const;
  /// accept_substep of the active potentials at q; false when one refused (and stiffened).
  bool accept(const Eigen::VectorXd& q, const ReducedInertia& inertia, const RootFrame* root = nullptr);
  int max_refinements() const;

 private:
  struct Term {
    model::NodePotential* potential = nullptr;
    std::vector<int> active;  ///< per candidate: index into the active nodes
  };
  /// Posed position of active node a (before the root deviation).
  Eigen::Vector3d posed(const Eigen::VectorXd& q, const ReducedInertia& inertia, int a) const;

  const Subspace& subspace_;
  const std::vector<int>& active_nodes_;
  std::vector<model::NodePotential*> potentials_;
  std::vector<std::vector<int>> active_of_;  ///< per potential, per entry of nodes(): its active index
  std::vector<Term> terms_;
};

}  // namespace sflsh::reduced
