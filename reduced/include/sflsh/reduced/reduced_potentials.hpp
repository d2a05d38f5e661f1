#pragma once
// The problem's node potentials (contact, model/node_potential.hpp) in the reduced incremental potential:
// with p_i(q) = z_i + A_i Σ_s b_is t_s (z_i: posed at q = 0),
//   U(q) = Σ_k u_k(p_{n_k}(q)),   ∂U/∂t_s = Σ_k b_{n_k s} A_kᵀ ∇u_k,   ∂²U/∂t_s∂t_r = Σ_k b_ks b_kr A_kᵀ ∇²u_k A_k,
// summed over each potential's candidates of the substep only, so an idle or absent potential costs nothing.
// With a tracking skeleton (skeleton_deviation.hpp) every position is carried by the skeleton's deviation y = D(p),
// and the gradient and Hessian gain the deviation's rows: ∂y/∂t_s = b_s L A, ∂y/∂r from the frame.
#include <sflsh/model/problem.hpp>
#include <sflsh/reduced/reduced_inertia.hpp>
#include <sflsh/reduced/skeleton_deviation.hpp>
#include <sflsh/reduced/subspace.hpp>

#include <Eigen/Core>

#include <vector>

namespace sflsh::reduced {

/// The posed position z_a + A_a Σ_s b_as t_s of active node a (an index into inertia.active_nodes()) at the
/// inertia's current time; q may be longer than 3S (extra coordinates after it are ignored).
Eigen::Vector3d posed_node(const Subspace& subspace, const ReducedInertia& inertia, const Eigen::VectorXd& q, int a);

/// Adds the deviation's rows of one node's contribution to a gradient over x = [q; r; …] (r at frame.offset): u of
/// the deviated position y = D(p), with p the node's posed position before the deviation, ∇u = g at y, A the
/// node's map and `node` its mesh index (its basis row).
void add_deviation_node_gradient(const Subspace& subspace, const DeviationFrame& frame, int node,
                                 const Eigen::Matrix3d& A, const Eigen::Vector3d& p, const Eigen::Vector3d& g,
                                 Eigen::VectorXd& gradient);
/// The same for the Hessian, with ∇²u = H at y: the deviation block, the soft tissue × deviation blocks and the
/// soft-tissue block (L A)ᵀ H (L A) b_s b_r.
void add_deviation_node_blocks(const Subspace& subspace, const DeviationFrame& frame, int node,
                               const Eigen::Matrix3d& A, const Eigen::Vector3d& p, const Eigen::Vector3d& g,
                               const Eigen::Matrix3d& H, Eigen::MatrixXd& hessian);

class ReducedPotentials {
 public:
  /// Throws when a potential acts on a node without basis functions (it could not respond).
  ReducedPotentials(const model::Problem& problem, const Subspace& subspace, const std::vector<int>& active_nodes);

  bool empty() const { return potentials_.empty(); }
  /// begin_substep of every potential; `inertia` must be set to the end time, p_start are the active nodes'
  /// posed positions at t0. Returns whether any potential has candidates.
  /// `root` (may be null) carries the skinned end positions (the root at the start of the substep).
  bool begin(double t0, double dt, const meshing::RowMatrixX3d& p_start, const ReducedInertia& inertia,
             const DeviationFrame* root = nullptr);
  bool active() const { return !terms_.empty(); }
  /// With `root`, q is x = [q; θ; τ] and the gradient and Hessian also fill the root's rows and columns.
  double energy(const Eigen::VectorXd& q, const ReducedInertia& inertia, const DeviationFrame* root = nullptr) const;
  void add_gradient(const Eigen::VectorXd& q, const ReducedInertia& inertia, Eigen::VectorXd& gradient,
                    const DeviationFrame* root = nullptr) const;
  void add_hessian(const Eigen::VectorXd& q, const ReducedInertia& inertia, Eigen::MatrixXd& hessian,
                   const DeviationFrame* root = nullptr) const;
  /// accept_substep of the active potentials at q; false when one refused (and stiffened).
  bool accept(const Eigen::VectorXd& q, const ReducedInertia& inertia, const DeviationFrame* root = nullptr);
  int max_refinements() const;
  /// The first potential's unresolved() reason after accept() refused (empty: none refused for good).
  std::string unresolved() const;

 private:
  struct Term {
    model::NodePotential* potential = nullptr;
    std::vector<int> active;  ///< per candidate: index into the active nodes
  };
  /// Posed position of active node a (before the root deviation).
  Eigen::Vector3d posed(const Eigen::VectorXd& q, const ReducedInertia& inertia, int a) const;
  /// Calls visit(term, c, a, node, p, at) for candidate c of every term: a its active index, node its mesh node,
  /// p its posed position and `at` where the potential sees it (p deviated by the root, or p).
  template <class Visit>
  void each_candidate(const Eigen::VectorXd& q, const ReducedInertia& inertia, const DeviationFrame* root,
                      Visit&& visit) const;

  const Subspace& subspace_;
  const std::vector<int>& active_nodes_;
  std::vector<model::NodePotential*> potentials_;
  std::vector<std::vector<int>> active_of_;  ///< per potential, per entry of nodes(): its active index
  std::vector<Term> terms_;
};

}  // namespace sflsh::reduced
