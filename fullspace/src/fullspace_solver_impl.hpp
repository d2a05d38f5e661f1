#pragma once
// Internal to the full-space solver: its state (FullSpaceSolver::Impl) and the helpers shared by
// fullspace_solver.cpp (setup, PETSc callbacks, the step with its integrator) and fullspace_assembly.cpp
// (Φ, residual and Hessian as sums of model terms, the PETSc Hessian sink with the direct refill of the AIJ
// arrays).
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/fullspace/node_partition.hpp>
#include <sflsh/model/terms.hpp>

#include <Eigen/LU>
#include <petscsnes.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>

namespace sflsh::fullspace {

namespace {

using Clock = std::chrono::steady_clock;

/// PETSc calls inside the integrator: a non-zero code becomes sflsh::Error naming the call.
inline void check(PetscErrorCode code, const char* what) {
  if (code != 0) throw_error("PETSc call {} failed with error code {}", what, static_cast<int>(code));
}
#define SFLSH_PETSC(call) check((call), #call)

using model::kInfinity;  // model/terms.hpp

inline material::TetNodes problem_rest_nodes(const Problem& problem, int e) {
  material::TetNodes nodes;
  for (int a = 0; a < 4; ++a) nodes.col(a) = problem.rest.row(problem.tets(e, a)).transpose();
  return nodes;
}

/// The PETSc type of a preconditioner choice on `size` processes (automatic_preconditioner resolves automatic).
inline PCType default_pc_type(int dofs, int size, bool dynamic, Preconditioner choice = Preconditioner::automatic) {
  if (choice == Preconditioner::automatic) choice = automatic_preconditioner(dofs, size, dynamic);
  switch (choice) {
    case Preconditioner::direct:
      return size == 1 ? PCCHOLESKY : PCREDUNDANT;
    case Preconditioner::icc:
      // Block Jacobi's blocks default to ICC for a matrix marked symmetric (MAT_SYMMETRIC below).
      return size == 1 ? PCICC : PCBJACOBI;
    case Preconditioner::gamg:
      return PCGAMG;
    case Preconditioner::hypre:
      return PCHYPRE;
    case Preconditioner::automatic:
      break;
  }
  return PCGAMG;
}

}  // namespace

struct FullSpaceSolver::Impl {
  const Problem& problem;
  MPI_Comm comm;
  FullSpaceOptions options;
  int rank = 0;
  int size = 1;
  /// PETSc's numbering of the nodes (see node_partition.hpp): rows, vector entries and ownership ranges are
  /// in solver indices; the problem's vectors (x_full, prescribed, the Eigen state) stay in mesh order.
  NodePartition partition;
  int begin = 0, end = 0;    ///< this rank's solver indices
  std::vector<int> my_tets;  ///< tets whose lowest solver index is owned: each counted once in Φ
  /// Tets with at least one owned node: the gradient and Hessian rows of the owned nodes are complete from
  /// these alone, so no entry is sent to another rank (interface tets are evaluated on both sides).
  std::vector<int> row_tets;
  std::vector<char> constrained;  ///< per dof (mesh order)
  std::unique_ptr<tbb::task_arena> arena;

  Vec X = nullptr, F = nullptr, x_all = nullptr;
  VecScatter to_all = nullptr;
  Mat J = nullptr;
  SNES snes = nullptr;

  State state;

  // The substep being solved.
  double t1 = 0.0;
  bool inertia = true;          ///< Φ has the inertia term (dynamic problem, not quasi-static)
  NodeFrame frame;              ///< the maps at t1
  model::InertiaTarget target;  ///< ĥ and p̃ of the substep (time_integrator.hpp)
  Eigen::VectorXd x_full;
  Eigen::VectorXd prescribed;  ///< x values at t1 (full), valid on constrained dofs

  // Φ as a sum of terms (model/terms.hpp) over this rank's share: values over my_tets and the owned nodes,
  // gradient and Hessian rows from row_tets (subset.row_tets = row_tets, so a sink's k indexes both).
  std::shared_ptr<model::TermSubset> subset;
  std::unique_ptr<model::ElasticTerm> elastic_term;
  std::unique_ptr<model::InertiaTerm> inertia_term;
  std::unique_ptr<model::GravityTerm> gravity_term;
  std::unique_ptr<model::PotentialTerm> potential_term;
  /// Per row tet: bit 3a + k set when component k of its node a is constrained (those Hessian rows and
  /// columns are dropped; the constrained row is D e_d).
  std::vector<std::uint16_t> tet_constrained;

  StepStats* stats = nullptr;
  bool linear_failure = false;  ///< the last substep failed in the linear solver
  std::string saved_pc_type;    ///< the configured PC while the fallback is in use (empty otherwise)

  /// Switches the KSP to CG + Jacobi, which cannot break down on a positive definite system: AMG smoothers
  /// occasionally come out indefinite on stiff or strongly heterogeneous states.
  void use_fallback_pc() {
    KSP ksp = nullptr;
    PC pc = nullptr;
    SFLSH_PETSC(SNESGetKSP(snes, &ksp));
    SFLSH_PETSC(KSPGetPC(ksp, &pc));
    PCType type = nullptr;
    SFLSH_PETSC(PCGetType(pc, &type));
    saved_pc_type = type ? type : PCGAMG;
    SFLSH_PETSC(PCSetType(pc, PCJACOBI));
    pc_reuse.force = true;
    if (stats) ++stats->fallback_preconditioner;
  }
  /// Restores the configured preconditioner (and re-reads its -pc_* options).
  void restore_pc() {
    if (saved_pc_type.empty()) return;
    KSP ksp = nullptr;
    PC pc = nullptr;
    SFLSH_PETSC(SNESGetKSP(snes, &ksp));
    SFLSH_PETSC(KSPGetPC(ksp, &pc));
    SFLSH_PETSC(PCSetType(pc, saved_pc_type.c_str()));
    SFLSH_PETSC(PCSetFromOptions(pc));
    saved_pc_type.clear();
    pc_reuse.force = true;
  }
  /// Truncated Newton–CG for this attempt (FullSpaceOptions::truncate_on_negative_curvature): linear solves
  /// that stop early (negative curvature) do not end the SNES solve; the line search judges their direction
  /// (a zero direction, negative curvature at the first CG iteration, fails it). Every other attempt ends at
  /// the first failed linear solve, so the projected rungs keep their CG + Jacobi fallback.
  bool truncated_newton = false;
  void set_truncated_newton(bool on) {
    truncated_newton = on;
    SFLSH_PETSC(SNESSetMaxLinearSolveFailures(snes, on ? options.default_snes_max_it + 1 : 1));
  }
  /// The elastic Hessian of this attempt: exact first in dynamic steps when options.exact_hessian_first,
  /// problem.projection otherwise and on every retry.
  material::HessianProjection projection_now = material::HessianProjection::kStressDerivative;
  /// Diagonal value of constrained rows: the mean elastic diagonal at rest, so that these rows do not
  /// spoil the spectrum the multigrid smoothers estimate (a 1 beside entries of 10²–10⁴ made GAMG's
  /// Chebyshev smoother indefinite).
  double dirichlet_diagonal = 1.0;

  /// Direct refill of the assembled AIJ arrays: after the first assembly fixed the pattern, every 3×3 block
  /// (I, J) of an owned row maps to three offsets (one per scalar row) into the diagonal or off-diagonal
  /// SeqAIJ value array; MatSetValues' per-entry search is then skipped (it cost more than the kernels).
  struct Refill {
    bool ready = false;
    Mat diag = nullptr, offdiag = nullptr;  ///< borrowed from J
    std::ptrdiff_t diag_nnz = 0, offdiag_nnz = 0;
    /// Per row tet, 16 blocks (a, b) × 3 rows: ≥ 0 offset into diag, < −1 offset −(o + 2) into offdiag,
    /// −1: the row belongs to another rank (which assembles it from its own row tets).
    std::vector<PetscInt> tet_offset;
    std::vector<PetscInt> node_offset;  ///< per owned node, 3 rows: offsets of its diagonal block
  } refill;

  /// The consistent inertia's Hessian blocks depend only on the maps at t1 and ĥ: assembled once per substep
  /// into copies of the AIJ value arrays and added to each Jacobian of that substep.
  struct InertiaHessianCache {
    long substep = -1;                       ///< the substep they belong to (−1: none)
    std::vector<PetscScalar> diag, offdiag;  ///< same layout as refill.diag / refill.offdiag
  } inertia_cache;
  long substep_serial = 0;  ///< counts solve_substep calls
  /// Preconditioner reuse (FullSpaceOptions::pc_reuse_growth): decided in jacobian_cb for the coming solve.
  struct PcReuse {
    bool enabled = false;       ///< an iterative preconditioner, growth > 0 and no -snes_lag_preconditioner
    bool force = true;          ///< rebuild at the next Jacobian (first one, after a failure or a switch)
    bool measure_next = false;  ///< the last solve was the first after a rebuild: its count is the reference
    int reference = 0;          ///< CG iterations of the first solve after the last rebuild
  } pc_reuse;
  /// Rebuilds or keeps the preconditioner for the solve that follows this Jacobian (SNES's lag −2 / −1).
  void choose_pc_rebuild(SNES s);
  void distribute_tets();            ///< my_tets and row_tets of this rank, ordered by their lowest solver index
  void create_vectors_and_matrix();  ///< X, F, the scatter to all, and J preallocated from the tets' node pairs
  void create_snes();                ///< SNES, CG, the preconditioner and the line search with the project's defaults
  void set_near_null_space();        ///< the rigid-body modes of the rest coordinates on J (for GAMG)
  void set_dirichlet_diagonal();     ///< dirichlet_diagonal from the elastic diagonal at rest
  void configure_pc_reuse(PC pc);    ///< pc_reuse.enabled for the configured preconditioner
  /// Φ at the point the line search last accepted (valid within one SNESSolve): the next Newton iteration's
  /// line search starts there, so its Φ(x₀) is this value instead of a second evaluation.
  bool accepted_phi_valid = false;
  double accepted_phi = 0.0;
  Eigen::VectorXd accepted_x;

  Impl(const Problem& p, MPI_Comm c, const FullSpaceOptions& o) : problem(p), comm(c), options(o) {}

  int index_of(int node) const { return partition.index_of[static_cast<std::size_t>(node)]; }
  int node_of(int index) const { return partition.node_of[static_cast<std::size_t>(index)]; }
  bool owns(int node) const {
    const int k = index_of(node);
    return k >= begin && k < end;
  }

  void setup();
  void destroy();

  void gather(Vec v, Eigen::VectorXd& out);
  Eigen::VectorXd x_prescribed_buffer;
  /// x with its constrained components replaced by their prescribed values (x itself before the first step).
  const Eigen::VectorXd& with_prescribed(const Eigen::VectorXd& x) {
    if (prescribed.size() != x.size()) return x;
    x_prescribed_buffer = x;
    for (std::size_t d = 0; d < constrained.size(); ++d) {
      if (constrained[d]) x_prescribed_buffer[static_cast<Eigen::Index>(d)] = prescribed[static_cast<Eigen::Index>(d)];
    }
    return x_prescribed_buffer;
  }
  /// The terms over this rank's share (after the tet split of setup()).
  void create_terms();
  /// Σ of the terms' values at x_in (constrained components replaced by their prescribed values), plus the
  /// Dirichlet penalty; summed over ranks.
  double objective(const Eigen::VectorXd& x);
  bool residual(const Eigen::VectorXd& x, Vec out);
  bool jacobian(const Eigen::VectorXd& x);
  /// Receives the terms' Hessian blocks (fullspace_assembly.cpp).
  class PetscSink;
  /// Adds the consistent inertia's Hessian (refill storage only), assembling it when the substep is new.
  bool add_cached_inertia_hessian(const Eigen::VectorXd& x, PetscScalar* diag_values, PetscScalar* offdiag_values);
  void build_refill();
  void mark_diagonal_block_symmetric();
  bool solve_substep(State& s, double t0, double dt);
  /// One SNES solve of the current substep from `start` (full, prescribed values set); true when converged.
  bool solve_from(const Eigen::VectorXd& start, double dt);

  static PetscErrorCode function_cb(SNES, Vec x, Vec f, void* ctx);
  static PetscErrorCode objective_cb(SNES, Vec x, PetscReal* value, void* ctx);
  static PetscErrorCode jacobian_cb(SNES, Vec x, Mat, Mat, void* ctx);
  static PetscErrorCode linesearch_cb(SNESLineSearch ls, void* ctx);
};

}  // namespace sflsh::fullspace
