#pragma once
// The full-space solver: each step of the chosen integrator (backward Euler, BDF2, Newmark;
// model/time_integrator.hpp, docs/integrators.md) minimizes the incremental potential with skinning-driven
// inertia (docs/physics.md §5, Kane et al. 2000) by Newton with an energy line search on PETSc SNES:
//   Φ(x) = 1/(2ĥ²) (p(x) − p̃)ᵀ M (p(x) − p̃) + E(x) − gᵀ M p(x) + U(p(x)),   p_i(x) = A_i x_i + d_i,
// summed from the model's terms (model/terms.hpp: elastic, inertia with lumped or consistent M, gravity, node
// potentials); the integrator sets ĥ and p̃ from the posed history carried in the State and updates it from the
// minimizer. ∇²Φ = Aᵀ M A/ĥ² + ∇²E(x) + Aᵀ∇²U A has 3×3 blocks per node pair sharing a tet (consistent M
// too).
// Distributed over MPI_COMM_WORLD: nodes are renumbered (reverse Cuthill–McKee, node_partition.hpp) and split
// in contiguous ranges; each rank assembles the complete rows of its nodes from every tet touching them (so no
// matrix or vector entry is sent between ranks) and counts in Φ the tets whose lowest node it owns; every
// rank keeps the full state (meshes here are ≤ 10⁶ dofs).
// Defaults (all overridable with -snes_*, -ksp_*, -pc_* or an options file): newtonls with an energy
// backtracking line search, KSP CG with ICC (block Jacobi + ICC in parallel) in dynamic steps and GAMG without
// inertia, a direct solve up to 6000 dofs; rtol 1e-8; the exact Hessian first, then each tet's projected to PSD.
// Node potentials of the problem (contact, node_potential.hpp) add u(p) to Φ on their candidate nodes; a
// substep a potential refuses (penetration over its tolerance) is solved again after the potential stiffened.
#include <sflsh/fullspace/model_names.hpp>
#include <sflsh/model/frame_loop.hpp>
#include <sflsh/model/step_stats.hpp>
#include <sflsh/model/time_integrator.hpp>

#include <mpi.h>

#include <memory>
#include <string>
#include <vector>

namespace sflsh::fullspace {

/// The preconditioner of the Newton systems' CG (docs/fullspace.md "Preconditioner"); -pc_type overrides it.
/// automatic (automatic_preconditioner): a direct Cholesky up to 6000 dofs (redundant in parallel); above it
/// ICC(0) for dynamic steps on one process and block-Jacobi ICC(0) on P processes while dofs · P ≤ 360,000, GAMG on
/// larger parallel problems and without the mass term. The others force one choice at every size: direct, icc
/// (ICC(0) / block-Jacobi ICC(0)), gamg (smoothed aggregation with the rigid-body near-null space of the rest
/// coordinates) or hypre (BoomerAMG with hypre's defaults). Measured on the driven block (1,800 – 921,600 tets,
/// Newmark; docs/results/performance.md): GAMG's CG iterations per Newton step stay at 6 – 12 under refinement and
/// across 1 – 8 processes, block-Jacobi ICC's grow with both (8 → 52 under refinement, 14 → 50 over 8 ranks).
enum class Preconditioner { automatic, direct, icc, gamg, hypre };

/// What `automatic` resolves to (never automatic or hypre) for `dofs` unknowns on `processes` processes; `dynamic`:
/// the system has the mass term M/ĥ². Two processes, CG to 1e-4, one thread each (docs/results/performance.md):
/// block-Jacobi ICC 0.18 against GAMG 0.26 s per frame on the default body layer (25k dofs), 0.50 against 0.57 s
/// per step on the 115k-tet block (66k dofs), 8.7 against 7.5 s at 922k tets (492k dofs); block-Jacobi's
/// iterations also grow with the ranks (14 → 50 from 1 to 8 at 14,400 tets per rank), so the crossover, ~180k
/// dofs on two processes, is taken as dofs · P ≤ 360,000.
Preconditioner automatic_preconditioner(int dofs, int processes, bool dynamic);

struct FullSpaceOptions {
  Preconditioner preconditioner = Preconditioner::automatic;
  /// Assembly threads per process (TBB); 0: the machine's cores divided among the processes. PETSc's linear
  /// algebra runs on one thread per process either way, so strong scaling is measured with threads = 1.
  int threads = 0;
  /// Preconditioner reuse for the multigrid choices (GAMG, BoomerAMG; never ICC or the direct solve): the
  /// hierarchy built for one Newton system is kept for the following ones, across Newton iterations and steps,
  /// until a CG solve needs more than `pc_reuse_growth` times the iterations of the first solve after the build
  /// (and 2 more), a solve stops without converging (negative curvature, a failure), or the preconditioner is
  /// switched. The systems change little from one Newton step to the next (M/h² dominates), so the setup is paid
  /// rarely; the answers are unchanged (each CG solve still reaches its tolerance). 0: rebuild at every Newton
  /// step. -snes_lag_preconditioner overrides it.
  double pc_reuse_growth = 1.5;
  model::Integrator integrator = model::Integrator::backward_euler;  ///< time_integrator.hpp
  bool quasi_static = false;         ///< drop inertia (equilibrium at each time; gravity still acts through mass)
  int max_halvings = 6;              ///< a failed step is retried as 2, 4, … 2^max_halvings substeps
  std::string options_prefix;        ///< PETSc options prefix of the SNES (e.g. "full_")
  double default_snes_rtol = 1e-8;   ///< used unless -snes_rtol is given
  double default_snes_atol = 1e-10;  ///< [N], used unless -snes_atol is given
  int default_snes_max_it = 40;
  /// CG's relative tolerance per Newton step, unless -ksp_rtol is given. Newton's own test (‖∇Φ‖ against
  /// default_snes_rtol/atol) decides the answer, so a looser inner solve changes the path, not the solution:
  /// 1e-4 instead of 1e-6 cut the CG iterations by a third at one more Newton step in ~30 frames, with the
  /// trajectories equal to 1e-12 m (115k-tet block) and σ to 6 digits (default layer, jiggle_on_toes;
  /// docs/decisions.md "Inner solve tolerance").
  double default_ksp_rtol = 1e-4;
  bool use_predictor = true;  ///< start Newton from the pulled-back inertial prediction when it has lower Φ
  /// Dynamic steps try the exact elastic Hessian first: M/h² keeps the system positive definite unless the
  /// tissue is strongly compressed, CG then converges and Newton is quadratic, and the PSD projection
  /// (≈ 4 µs of the ≈ 5 µs per tet, bench_element) is skipped. A failed attempt (indefinite system, failed
  /// line search) repeats the step with problem.projection before halving. The solution is the same.
  bool exact_hessian_first = true;
  /// In the exact-Hessian attempt, a CG solve that meets negative curvature (an indefinite Hessian: StVK in
  /// compression, amplified by the Fung factor e^{2Ψ₀/c} of a tet stretched at the same time) ends with the
  /// iterate before it, a descent direction of Φ (truncated Newton–CG), and the energy line search takes it;
  /// the next iteration uses the exact Hessian again, so Newton is quadratic again once the iterates leave the
  /// indefinite region. Off: the first indefinite solve fails the attempt, which the ladder repeats with the
  /// projected Hessian from the start of the step (linear convergence; docs/fullspace.md "Hard cases").
  bool truncate_on_negative_curvature = true;
};

class FullSpaceSolver final : public model::BodySolver {
 public:
  /// `problem` must outlive the integrator and be validated. Collective on `comm`.
  FullSpaceSolver(const Problem& problem, MPI_Comm comm, const FullSpaceOptions& options = {});
  ~FullSpaceSolver();
  FullSpaceSolver(const FullSpaceSolver&) = delete;
  FullSpaceSolver& operator=(const FullSpaceSolver&) = delete;

  /// Sets the state (full vectors, identical on every rank; the history entries empty or full). Newmark
  /// computes the accelerations of the equations of motion when the state carries none.
  void initialize(const State& state);
  const State& state() const;
  State current_state() const override { return state(); }
  /// Advances by h [s]. Retries failed solves with smaller substeps; throws sflsh::Error (on every rank)
  /// naming the time and the reason when even 2^max_halvings substeps fail. The state is unchanged then.
  StepStats step(double h) override;
  /// The assembly threads of this process (FullSpaceOptions::threads resolved).
  int assembly_threads() const;
  /// PETSc's name of the configured preconditioner (after -pc_type), e.g. "icc", "gamg", "cholesky".
  std::string preconditioner_type() const;
  /// Local ownership (for reporting): the mesh nodes this rank owns, ascending.
  std::vector<int> owned_nodes() const;

  /// Internal state (fullspace/src/fullspace_solver_impl.hpp), named here for the solver's own sources.
  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace sflsh::fullspace
