#pragma once
// The terms of the incremental potential Φ (time_integrator.hpp) on the full-space elastic state x (3N,
// unposed; constrained components at their prescribed values), each with its value [J], gradient [N] and
// Hessian [N/m]; a solver sums the terms a problem asks for and builds no other:
//   ElasticTerm    E(x) = Σ_e Ψ_e(x)                  12×12 tet blocks (exact, or dP/dF projected to PSD)
//   InertiaTerm    1/(2ĥ²) (p − p̃)ᵀ M (p − p̃)        lumped: node blocks m_i A_iᵀA_i/ĥ²; consistent: tet blocks
//                                                     ρV_e/20 (1 + δ_ab) A_aᵀA_b/ĥ² (p_i = A_i x_i + d_i)
//   GravityTerm    −Σ_i m_i gᵀ p_i                    (linear: no Hessian)
//   PotentialTerm  Σ_k u_k(p_{n_k}) of the problem's node potentials on their candidates (contact): node
//                  blocks A_iᵀ ∇²u A_i
// A TermSubset says which tets and nodes a term sums over: the value counts each tet and node once over all
// processes, the gradient and Hessian rows of the nodes a process owns come complete from its row tets (the
// MPI split of the full-space solver). The finite-difference harness (tests/model) runs over every term.
#include <sflsh/material/psd_projection.hpp>
#include <sflsh/material/tet_element.hpp>
#include <sflsh/model/problem.hpp>
#include <sflsh/model/time_integrator.hpp>

#include <Eigen/Core>

#include <array>
#include <functional>
#include <limits>
#include <memory>
#include <string_view>
#include <vector>

namespace sflsh::model {

/// Receives a term's Hessian.
class HessianSink {
 public:
  virtual ~HessianSink() = default;
  /// The 12×12 block of tet e (node order of problem.tets), the k-th of the subset's row tets.
  virtual void add_tet(std::size_t k, int e, const material::Matrix12d& block) = 0;
  /// A 3×3 block on node i's diagonal.
  virtual void add_node(int node, const Eigen::Matrix3d& block) = 0;
};

/// The tets and nodes a term sums over (see the file comment).
struct TermSubset {
  std::vector<int> value_tets;  ///< tets counted in the value
  std::vector<int> row_tets;    ///< tets giving the gradient and Hessian rows (order = HessianSink's k)
  std::vector<int> nodes;       ///< nodes whose node-level terms are counted (value, rows)
  /// Every tet and node.
  static std::shared_ptr<const TermSubset> whole(const Problem& problem);
};

/// The value of a term at a state out of reach (a Fung exponent over its cap, an inverted or non-finite state).
inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

class Term {
 public:
  virtual ~Term() = default;
  virtual std::string_view name() const = 0;
  /// The value at x [J]; +∞ where the material refuses the state (Fung exponent over its cap).
  virtual double value(const Eigen::VectorXd& x) const = 0;
  /// Adds the gradient [N] to g (3N); false when some contribution is not finite or out of range.
  virtual bool add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& g) const = 0;
  /// Hands the Hessian [N/m] to `sink`; false when some block is not finite or out of range.
  virtual bool add_hessian(const Eigen::VectorXd& x, HessianSink& sink) const = 0;
};

/// The elastic term reads each tet's rest data and material from a copy packed in the subset's order when it is
/// constructed (PackedTet): the problem's tets, materials and Young moduli must not change while the term is in use
/// (the full-space solver builds its terms for one problem; a new material means a new solver).
class ElasticTerm final : public Term {
 public:
  ElasticTerm(const Problem& problem, std::shared_ptr<const TermSubset> subset);
  std::string_view name() const override { return "elastic"; }
  /// The Hessian of the next add_hessian calls: exact (kNone) or with dP/dF projected.
  void set_projection(material::HessianProjection projection) { projection_ = projection; }
  double value(const Eigen::VectorXd& x) const override;
  bool add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& g) const override;
  bool add_hessian(const Eigen::VectorXd& x, HessianSink& sink) const override;

 private:
  /// What the kernels read of one tet, contiguous. The row tets come in matrix-row order (the Hessian refill
  /// walks the rows), which is not the mesh's: read from the problem's per-tet arrays in that order, every tet's
  /// rest data and material were a cache and TLB miss (the energy pass 3.3× slower on the 115k-tet block,
  /// docs/results/performance.md).
  struct PackedTet {
    material::TetRest rest;
    material::OrthotropicFung material;
    double energy_scale = 1.0;
    std::array<int, 4> nodes{};
    int tet = 0;  ///< its index in the problem
  };
  std::vector<PackedTet> packed_;  ///< the row tets in their order, then value tets that are not row tets
  std::vector<int> value_slots_;   ///< per value tet: its entry of packed_
  std::size_t row_count_ = 0;      ///< packed_[0, row_count_) are the row tets
  material::HessianProjection projection_ = material::HessianProjection::kNone;
};

class InertiaTerm final : public Term {
 public:
  InertiaTerm(const Problem& problem, std::shared_ptr<const TermSubset> subset);
  std::string_view name() const override { return "inertia"; }
  /// The step: node maps at its end and the integrator's ĥ and p̃ (3N); both must outlive the evaluations.
  void set_step(const NodeFrame& frame, const InertiaTarget& target);
  double value(const Eigen::VectorXd& x) const override;
  bool add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& g) const override;
  bool add_hessian(const Eigen::VectorXd& x, HessianSink& sink) const override;

 private:
  Eigen::Vector3d residual(const Eigen::VectorXd& x, int node) const;  ///< p_i(x) − p̃_i
  Eigen::Matrix3Xd residuals(const Eigen::VectorXd& x) const;          ///< p_i(x) − p̃_i of residual_nodes_
  const Problem& problem_;
  std::shared_ptr<const TermSubset> subset_;
  // Consistent mass: the row tets' nodes and ρV in row order, then value tets that are not row tets (as
  // ElasticTerm packs them, for the same reason), and the nodes those tets touch.
  std::vector<std::array<int, 4>> tet_nodes_;
  std::vector<double> tet_mass_;
  std::vector<int> value_slots_;
  std::vector<int> residual_nodes_;
  std::size_t row_count_ = 0;
  const NodeFrame* frame_ = nullptr;
  const InertiaTarget* target_ = nullptr;
};

class GravityTerm final : public Term {
 public:
  GravityTerm(const Problem& problem, std::shared_ptr<const TermSubset> subset);
  std::string_view name() const override { return "gravity"; }
  void set_frame(const NodeFrame& frame) { frame_ = &frame; }
  double value(const Eigen::VectorXd& x) const override;
  bool add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& g) const override;
  bool add_hessian(const Eigen::VectorXd& x, HessianSink& sink) const override;

 private:
  const Problem& problem_;
  std::shared_ptr<const TermSubset> subset_;
  const NodeFrame* frame_ = nullptr;
};

/// The problem's node potentials in one substep: begin() lets each pick its candidates, the term then sums the
/// candidates whose node the process counts (`owns`).
class PotentialTerm final : public Term {
 public:
  explicit PotentialTerm(const Problem& problem);
  std::string_view name() const override { return "potential"; }
  /// Calls begin_substep of every potential with the posed positions p_n (N×3) at t0 and the skinned ones at
  /// t0 + dt (from `frame`, the maps at t0 + dt, and the prescribed state x_prescribed); keeps the active ones.
  /// Returns whether any is active.
  bool begin(const RowMatrixX3d& p_n, double t0, double dt, const NodeFrame& frame, const Eigen::VectorXd& x_prescribed,
             const std::function<bool(int)>& owns);
  bool active() const { return !active_.empty(); }
  /// accept_substep of every active potential at the new state (all see the result).
  bool accept(const Eigen::VectorXd& x_new) const;
  int max_refinements() const;
  /// The first active potential's unresolved() after accept() refused (empty: none refused for good).
  std::string unresolved() const;
  double value(const Eigen::VectorXd& x) const override;
  bool add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& g) const override;
  bool add_hessian(const Eigen::VectorXd& x, HessianSink& sink) const override;

 private:
  struct Active {
    NodePotential* potential = nullptr;
    std::vector<int> node;   ///< per candidate: its mesh node
    std::vector<int> owned;  ///< candidate entries counted by this process
  };
  Eigen::Vector3d posed(const Eigen::VectorXd& x, int node) const;
  const Problem& problem_;
  const NodeFrame* frame_ = nullptr;
  std::vector<Active> active_;
};

}  // namespace sflsh::model
