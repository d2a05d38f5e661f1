#pragma once
// What every integrator solves (the full-space solver on PETSc, the SUNDIALS reference, the reduced model in
// its subspace): a tet mesh with a per-tet orthotropic StVK–Fung material, lumped or consistent masses
// (mass.hpp), prescribed (Dirichlet) components, and
// a per-node affine map from the unposed elastic state x to posed positions p (docs/physics.md §5):
//   p_i(t) = A_i(t) x_i + d_i(t),   d_i = A_i b_i + c_i  (b_i: pose corrective, [A_i | c_i]: blended LBS).
// The elastic energy E(x) is measured in the unposed frame; inertia and gravity act on p.
// Equation of motion (Euler–Lagrange of ½ṗᵀMṗ − E(x) + gᵀMp): A_iᵀ [M (p̈ − g)]_i = −∇_i E(x), with M the
// lumped diagonal m_i or the consistent matrix M_ij (per axis).
#include <sflsh/material/orthotropic_fung.hpp>
#include <sflsh/material/psd_projection.hpp>
#include <sflsh/material/tet_element.hpp>
#include <sflsh/meshing/types.hpp>
#include <sflsh/model/mass.hpp>
#include <sflsh/model/node_potential.hpp>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace sflsh::model {

using meshing::RowMatrixX3d;
using meshing::RowMatrixX4i;

/// The affine maps of all nodes at one instant: p_i = A_i x_i + d_i.
struct NodeFrame {
  std::vector<Eigen::Matrix3d> A;  ///< per node (3×3); identity for an unposed problem
  RowMatrixX3d d;                  ///< per node offset [m]
};

/// Time-dependent node maps (the skinning of the layer, or the identity). Implementations must be C¹ in
/// t so that the adaptive reference integrator sees a smooth forcing.
class NodeTrajectory {
 public:
  virtual ~NodeTrajectory() = default;
  virtual int num_nodes() const = 0;
  /// The maps at time t [s]; `rate`, when not null, receives dA/dt and dd/dt.
  virtual void evaluate(double t, NodeFrame& frame, NodeFrame* rate = nullptr) const = 0;
  /// The maps of the listed nodes only (entry k of `frame` is node nodes[k]); the default evaluates all
  /// nodes and gathers. Reduced models call it every step on the nodes their basis moves.
  virtual void evaluate_nodes(double t, const std::vector<int>& nodes, NodeFrame& frame) const;
};

/// A scalar prescribed displacement u(t) [m] and its time derivative.
struct ScalarDrive {
  std::function<double(double)> value;  ///< u(t)
  std::function<double(double)> rate;   ///< du/dt
};

/// Prescribed components of x: x_dof(t) = rest_dof + u(t), with u ≡ 0 for fixed components.
/// dof = 3·node + axis. Each dof appears at most once.
struct Dirichlet {
  std::vector<int> dof;    ///< constrained dofs, ascending
  std::vector<int> drive;  ///< per entry of `dof`: index into `drives`, or −1 (fixed: u ≡ 0)
  std::vector<ScalarDrive> drives;

  /// Adds components of one node (axes as a mask bit 0 = x, 1 = y, 2 = z) with an optional drive
  /// (−1 = fixed). A dof given twice with different drives throws sflsh::Error.
  void add(int node, unsigned axis_mask, int drive_index = -1);
  /// Sorts `dof` (and `drive` with it) and checks uniqueness; called by Problem::validate().
  void finalize();
  /// u(t) per constrained dof (same order as `dof`).
  Eigen::VectorXd values(double t) const;
  /// du/dt per constrained dof.
  Eigen::VectorXd rates(double t) const;
  /// Per dof of a 3N vector: true when constrained.
  std::vector<char> mask(int num_nodes) const;
};

/// The full-space problem. Build it, then call validate() once before handing it to an integrator.
struct Problem {
  RowMatrixX3d rest;                                    ///< X: unposed rest positions (N×3) [m]
  RowMatrixX4i tets;                                    ///< positively oriented (M×4)
  std::vector<material::TetRest> tet_rest;              ///< per tet: D_m⁻¹ and V (filled by validate() when empty)
  std::vector<material::OrthotropicFung> tet_material;  ///< per tet
  std::vector<double> tet_energy_scale;                 ///< optional per-tet factor on the energy (empty = 1)
  Eigen::VectorXd mass;                                 ///< lumped mass per node [kg]; all zero = quasi-static
  double density = 0.0;                                 ///< ρ [kg/m³] that `mass` came from
  /// Lumped (diagonal `mass`) or consistent (ρV_e/20 (1 + δ_ab) per tet node pair, mass.hpp) inertia.
  MassKind mass_kind = MassKind::lumped;
  Eigen::VectorXd tet_mass;                           ///< ρV per tet [kg]; filled by validate() from `density`
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();  ///< g in the posed (world) frame [m/s²]
  Dirichlet dirichlet;
  std::shared_ptr<const NodeTrajectory> trajectory;  ///< null: p = x (identity maps, d = 0)
  material::HessianProjection projection = material::HessianProjection::kStressDerivative;
  /// Extra per-node energies on posed positions (contact, node_potential.hpp); empty unless a scene asks.
  /// Shared, and mutable through the pointer: integrators call begin_substep/accept_substep on them.
  std::vector<std::shared_ptr<NodePotential>> potentials;

  int num_nodes() const { return static_cast<int>(rest.rows()); }
  int num_tets() const { return static_cast<int>(tets.rows()); }
  int num_dofs() const { return 3 * num_nodes(); }
  bool dynamic() const { return mass.size() > 0 && mass.maxCoeff() > 0.0; }

  /// Fills tet_rest from `rest` when empty and checks every size, index, mass and the Dirichlet set.
  /// Throws sflsh::Error naming the first inconsistency.
  void validate();
  /// The node-level mass matrix (N×N) [kg]: consistent_mass_matrix of tet_mass, or diag(mass) when lumped.
  Eigen::SparseMatrix<double, Eigen::RowMajor> mass_matrix() const;
  /// The maps at time t (identity when there is no trajectory).
  void frame(double t, NodeFrame& frame, NodeFrame* rate = nullptr) const;
  /// x with its constrained components set to their prescribed values at time t.
  void apply_dirichlet(double t, Eigen::Ref<Eigen::VectorXd> x) const;
};

/// Lumped masses ρV/4 per node (docs/physics.md §5): the row sums of the consistent matrix.
Eigen::VectorXd lumped_masses(const RowMatrixX3d& rest, const RowMatrixX4i& tets, double density);

/// Elastic energy, gradient and (optionally) the element Hessians of the whole mesh at x (3N, node-major).
/// Serial and threaded (TBB) over tets; the PETSc assembly uses the same element kernel.
struct ElasticEvaluation {
  double energy = 0.0;
  Eigen::VectorXd gradient;  ///< ∂E/∂x (3N) [N]
};
ElasticEvaluation evaluate_elastic(const Problem& problem, const Eigen::VectorXd& x, bool with_gradient = true);

/// Posed positions p = A x + d (N×3 from 3N x).
RowMatrixX3d posed_positions(const NodeFrame& frame, const Eigen::VectorXd& x);

/// One trajectory sample: the state an integrator reports at recorded times, with the history the
/// multistep integrators carry (time_integrator.hpp).
struct State {
  double t = 0.0;
  Eigen::VectorXd x;           ///< unposed elastic positions (3N) [m]
  Eigen::VectorXd w;           ///< posed velocities ṗ (3N) [m/s]
  Eigen::VectorXd a;           ///< posed accelerations p̈ (3N) [m/s²] (Newmark); empty until an integrator sets it
  Eigen::VectorXd p_previous;  ///< posed positions one step back (3N) [m] (BDF2); empty at the start
  Eigen::VectorXd w_previous;  ///< posed velocities one step back (3N) [m/s] (BDF2)
  double h_previous = 0.0;     ///< length of that step [s]
};

/// Energy bookkeeping of a state (for bounded-energy checks and summaries) [J].
struct Energies {
  double kinetic = 0.0;  ///< ½ wᵀ M w (lumped or consistent, as the problem says)
  double elastic = 0.0;  ///< E(x)
  double gravity = 0.0;  ///< −Σ m_i gᵀ p_i
};
Energies energies(const Problem& problem, const State& state);

/// The usual initial state at t0: x = X with the Dirichlet values applied at t0, and w the posed velocity
/// of that configuration carried by the trajectory, ṗ = Ȧx + ḋ + Aẋ with ẋ = du/dt on prescribed
/// components and 0 elsewhere (the body moves rigidly with its skinning, no elastic velocity).
/// Shared by every integrator.
State initial_state(const Problem& problem, double t0);

}  // namespace sflsh::model
