// The full-space solver on PETSc: setup of the distributed problem, the SNES callbacks, and the step of the
// chosen integrator with its retry ladder (fullspace_solver_impl.hpp; Φ and its derivatives in
// fullspace_assembly.cpp).
#include "fullspace_solver_impl.hpp"

#include <sflsh/model/step_ladder.hpp>

namespace sflsh::fullspace {

namespace {

/// The integrator as error messages name it.
std::string_view integrator_label(model::Integrator integrator) {
  switch (integrator) {
    case model::Integrator::backward_euler:
      return "backward Euler";
    case model::Integrator::bdf2:
      return "BDF2";
    case model::Integrator::newmark:
      return "Newmark";
  }
  return "backward Euler";
}

/// A 3N node-major vector of N×3 row-major positions.
Eigen::VectorXd flattened(const RowMatrixX3d& positions) {
  return Eigen::Map<const Eigen::VectorXd>(positions.data(), positions.size());
}

}  // namespace

void FullSpaceSolver::Impl::setup() {
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  partition = partition_nodes(problem.num_nodes(), problem.tets, size);
  begin = partition.range[static_cast<std::size_t>(rank)];
  end = partition.range[static_cast<std::size_t>(rank) + 1];

  // Threads within a rank share the machine with the other ranks.
  const int threads =
      options.threads > 0 ? options.threads : std::max(1, tbb::this_task_arena::max_concurrency() / size);
  arena = std::make_unique<tbb::task_arena>(threads);

  constrained = problem.dirichlet.mask(problem.num_nodes());
  distribute_tets();
  create_terms();
  create_vectors_and_matrix();
  set_near_null_space();
  set_dirichlet_diagonal();
  create_snes();
}

// Up to kDirectDofs a sparse direct factorization: faster there, and immune to the smoother trouble AMG has on a
// handful of aggregates (GAMG's Chebyshev smoother came out indefinite on 72-dof verification bars). Dynamic steps:
// M/ĥ² keeps the system well conditioned, and ICC(0)'s cheap iterations win on one process up to ~10⁶ tets
// (driven block, one thread: 1.1 s per step for both at 115k tets, 11.2 vs 11.1 s at 922k); on P processes
// block-Jacobi ICC wins while dofs · P ≤ 360,000 (fullspace_solver.hpp). Without the mass term (quasi-static and
// static problems) ICC's iteration count grows with the mesh and GAMG wins on any process count.
Preconditioner automatic_preconditioner(int dofs, int processes, bool dynamic) {
  constexpr int kDirectDofs = 6000;
  constexpr double kIccDofsTimesProcesses = 360000.0;
  if (dofs <= kDirectDofs) return Preconditioner::direct;
  if (!dynamic) return Preconditioner::gamg;
  if (processes <= 1) return Preconditioner::icc;
  return static_cast<double>(dofs) * processes <= kIccDofsTimesProcesses ? Preconditioner::icc : Preconditioner::gamg;
}

void FullSpaceSolver::Impl::distribute_tets() {
  std::vector<int> lowest(static_cast<std::size_t>(problem.num_tets()));
  for (int e = 0; e < problem.num_tets(); ++e) {
    int& low = lowest[static_cast<std::size_t>(e)];
    low = index_of(problem.tets(e, 0));
    bool touches = false;
    for (int a = 0; a < 4; ++a) {
      low = std::min(low, index_of(problem.tets(e, a)));
      touches = touches || owns(problem.tets(e, a));
    }
    if (low >= begin && low < end) my_tets.push_back(e);
    if (touches) row_tets.push_back(e);
  }
  // Tets in the order of their lowest solver index: the Hessian refill then walks the matrix rows nearly
  // in order instead of scattering over them (mesh order is layer by layer, the rows are not).
  auto by_lowest = [&](int a, int b) {
    return lowest[static_cast<std::size_t>(a)] < lowest[static_cast<std::size_t>(b)];
  };
  std::stable_sort(my_tets.begin(), my_tets.end(), by_lowest);
  std::stable_sort(row_tets.begin(), row_tets.end(), by_lowest);
}

void FullSpaceSolver::Impl::create_vectors_and_matrix() {
  const int n = problem.num_nodes();
  const int local = end - begin;
  // Block sparsity of the owned block rows (solver indices): every node pair sharing a tet.
  std::vector<std::vector<int>> adjacency(static_cast<std::size_t>(local));
  for (int e : row_tets) {
    for (int a = 0; a < 4; ++a) {
      const int i = index_of(problem.tets(e, a));
      if (i < begin || i >= end) continue;
      auto& row = adjacency[static_cast<std::size_t>(i - begin)];
      for (int b = 0; b < 4; ++b) row.push_back(index_of(problem.tets(e, b)));
    }
  }
  std::vector<PetscInt> dnz(static_cast<std::size_t>(local), 1), onz(static_cast<std::size_t>(local), 0);
  for (int i = 0; i < local; ++i) {
    auto& row = adjacency[static_cast<std::size_t>(i)];
    row.push_back(begin + i);
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
    PetscInt d = 0, o = 0;
    for (int j : row) (j >= begin && j < end ? d : o)++;
    dnz[static_cast<std::size_t>(i)] = d;
    onz[static_cast<std::size_t>(i)] = o;
  }

  SFLSH_PETSC(VecCreate(comm, &X));
  SFLSH_PETSC(VecSetSizes(X, 3 * local, 3 * n));
  SFLSH_PETSC(VecSetBlockSize(X, 3));
  SFLSH_PETSC(VecSetType(X, VECSTANDARD));
  SFLSH_PETSC(VecDuplicate(X, &F));
  SFLSH_PETSC(VecScatterCreateToAll(X, &to_all, &x_all));

  const std::string& prefix = options.options_prefix;
  SFLSH_PETSC(MatCreate(comm, &J));
  SFLSH_PETSC(MatSetSizes(J, 3 * local, 3 * local, 3 * n, 3 * n));
  SFLSH_PETSC(MatSetBlockSize(J, 3));
  SFLSH_PETSC(MatSetType(J, MATAIJ));
  if (!prefix.empty()) SFLSH_PETSC(MatSetOptionsPrefix(J, prefix.c_str()));
  SFLSH_PETSC(MatSetFromOptions(J));
  SFLSH_PETSC(MatXAIJSetPreallocation(J, 3, dnz.data(), onz.data(), nullptr, nullptr));
  SFLSH_PETSC(MatSetOption(J, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  // Every rank assembles its rows completely from row_tets: assembly needs no stash exchange.
  SFLSH_PETSC(MatSetOption(J, MAT_NO_OFF_PROC_ENTRIES, PETSC_TRUE));
  SFLSH_PETSC(MatSetOption(J, MAT_ROW_ORIENTED, PETSC_FALSE));  // Eigen's column-major blocks
  SFLSH_PETSC(MatSetOption(J, MAT_SYMMETRIC, PETSC_TRUE));
  SFLSH_PETSC(MatSetOption(J, MAT_SYMMETRY_ETERNAL, PETSC_TRUE));
}

void FullSpaceSolver::Impl::create_snes() {
  // The project's defaults are set on the objects before SNESSetFromOptions, so any -snes_*, -ksp_*, -pc_*
  // option (command line, PETSC_OPTIONS, -options_file) overrides them, and nothing leaks into the global
  // options database that a later solver in the same process would mistake for a user choice.
  const std::string& prefix = options.options_prefix;
  SFLSH_PETSC(SNESCreate(comm, &snes));
  if (!prefix.empty()) SFLSH_PETSC(SNESSetOptionsPrefix(snes, prefix.c_str()));
  SFLSH_PETSC(SNESSetFunction(snes, F, &Impl::function_cb, this));
  SFLSH_PETSC(SNESSetJacobian(snes, J, J, &Impl::jacobian_cb, this));
  SFLSH_PETSC(SNESSetObjective(snes, &Impl::objective_cb, this));
  SFLSH_PETSC(SNESSetType(snes, SNESNEWTONLS));
  SFLSH_PETSC(SNESSetTolerances(snes, options.default_snes_atol, options.default_snes_rtol, PETSC_DEFAULT,
                                options.default_snes_max_it, PETSC_DEFAULT));
  SFLSH_PETSC(SNESSetDivergenceTolerance(snes, -1.0));
  KSP ksp = nullptr;
  PC pc = nullptr;
  SFLSH_PETSC(SNESGetKSP(snes, &ksp));
  SFLSH_PETSC(KSPSetType(ksp, KSPCG));
  SFLSH_PETSC(KSPSetTolerances(ksp, options.default_ksp_rtol, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT));
  SFLSH_PETSC(KSPGetPC(ksp, &pc));
  const bool dynamic = !options.quasi_static && problem.dynamic();
  SFLSH_PETSC(PCSetType(pc, default_pc_type(3 * problem.num_nodes(), size, dynamic, options.preconditioner)));
  SNESLineSearch linesearch = nullptr;
  SFLSH_PETSC(SNESGetLineSearch(snes, &linesearch));
  SFLSH_PETSC(SNESLineSearchSetType(linesearch, SNESLINESEARCHSHELL));
  SFLSH_PETSC(SNESLineSearchShellSetUserFunc(linesearch, &Impl::linesearch_cb, this));
  SFLSH_PETSC(SNESSetFromOptions(snes));
  configure_pc_reuse(pc);
}

void FullSpaceSolver::Impl::set_near_null_space() {
  // Rigid-body near-null space from the rest coordinates: what smoothed aggregation needs for elasticity.
  {
    Vec coords = nullptr;
    SFLSH_PETSC(VecDuplicate(X, &coords));
    PetscScalar* c = nullptr;
    SFLSH_PETSC(VecGetArray(coords, &c));
    for (int i = begin; i < end; ++i) {
      for (int k = 0; k < 3; ++k) c[3 * (i - begin) + k] = problem.rest(node_of(i), k);
    }
    SFLSH_PETSC(VecRestoreArray(coords, &c));
    MatNullSpace near_null = nullptr;
    SFLSH_PETSC(MatNullSpaceCreateRigidBody(coords, &near_null));
    SFLSH_PETSC(MatSetNearNullSpace(J, near_null));
    SFLSH_PETSC(MatNullSpaceDestroy(&near_null));
    SFLSH_PETSC(VecDestroy(&coords));
  }
}

/// The diagonal of constrained rows: the mean elastic diagonal at rest (dirichlet_diagonal).
void FullSpaceSolver::Impl::set_dirichlet_diagonal() {
  {
    double sum = 0.0, count = 0.0;
    for (int e : my_tets) {
      const auto se = static_cast<std::size_t>(e);
      const material::Matrix12d K =
          material::tet_elastic_dq2(problem.tet_rest[se], problem_rest_nodes(problem, e), problem.tet_material[se],
                                    material::HessianProjection::kNone);
      if (K.allFinite()) {
        sum += K.diagonal().sum();
        count += 12.0;
      }
    }
    double mine[2] = {sum, count}, global[2] = {0.0, 0.0};
    MPI_Allreduce(mine, global, 2, MPI_DOUBLE, MPI_SUM, comm);
    if (global[1] > 0.0 && global[0] > 0.0) dirichlet_diagonal = global[0] / global[1];
  }
}

void FullSpaceSolver::Impl::configure_pc_reuse(PC pc) {
  {
    PetscBool lag_given = PETSC_FALSE;
    SFLSH_PETSC(PetscOptionsHasName(nullptr, options.options_prefix.empty() ? nullptr : options.options_prefix.c_str(),
                                    "-snes_lag_preconditioner", &lag_given));
    PCType type = nullptr;
    SFLSH_PETSC(PCGetType(pc, &type));
    const std::string chosen = type ? type : "";
    // Multigrid only: its setup is most of a Newton step (GAMG's Galerkin products alone 4.2 of 11.2 s at 115k
    // tets), while an ICC factorization is ~5 % of one, and a stale ICC factor changed the truncated Newton–CG
    // directions in the indefinite region of FullspaceStability.ShakeHipsOfOpenTrain1WithoutRetries (one frame
    // took 88 Newton iterations and a projected retry instead of 15). A direct factor is never reused.
    const bool multigrid = chosen == PCGAMG || chosen == PCHYPRE || chosen == PCML;
    pc_reuse.enabled = options.pc_reuse_growth > 0.0 && multigrid && !lag_given;
  }
}

void FullSpaceSolver::Impl::choose_pc_rebuild(SNES s) {
  if (!pc_reuse.enabled) {  // rebuilt with every Jacobian (or as -snes_lag_preconditioner says)
    if (stats) ++stats->preconditioner_builds;
    return;
  }
  KSP ksp = nullptr;
  SFLSH_PETSC(SNESGetKSP(s, &ksp));
  PetscInt last = 0;  // the previous linear solve's CG iterations
  SFLSH_PETSC(KSPGetIterationNumber(ksp, &last));
  if (pc_reuse.measure_next) {
    pc_reuse.reference = static_cast<int>(last);
    pc_reuse.measure_next = false;
  }
  const bool grown =
      last > options.pc_reuse_growth * pc_reuse.reference && last > static_cast<PetscInt>(pc_reuse.reference) + 2;
  // A solve that stopped without converging (negative curvature in truncated Newton–CG, the iteration cap) was on
  // a system the kept preconditioner no longer fits: the next one starts from a fresh build.
  KSPConvergedReason previous = KSP_CONVERGED_ITERATING;
  SFLSH_PETSC(KSPGetConvergedReason(ksp, &previous));
  const bool rebuild = pc_reuse.force || grown || previous < 0;
  // Lag −2: rebuild once now, then reuse (−1) until told otherwise; SNES applies it after this callback.
  SFLSH_PETSC(SNESSetLagPreconditioner(s, rebuild ? -2 : -1));
  if (rebuild) {
    pc_reuse.force = false;
    pc_reuse.measure_next = true;
    if (stats) ++stats->preconditioner_builds;
  }
}

void FullSpaceSolver::Impl::destroy() {
  if (snes) SNESDestroy(&snes);
  if (J) MatDestroy(&J);
  if (to_all) VecScatterDestroy(&to_all);
  if (x_all) VecDestroy(&x_all);
  if (F) VecDestroy(&F);
  if (X) VecDestroy(&X);
}

void FullSpaceSolver::Impl::gather(Vec v, Eigen::VectorXd& out) {
  SFLSH_PETSC(VecScatterBegin(to_all, v, x_all, INSERT_VALUES, SCATTER_FORWARD));
  SFLSH_PETSC(VecScatterEnd(to_all, v, x_all, INSERT_VALUES, SCATTER_FORWARD));
  const PetscScalar* a = nullptr;
  SFLSH_PETSC(VecGetArrayRead(x_all, &a));
  out.resize(problem.num_dofs());
  for (int k = 0; k < problem.num_nodes(); ++k)
    out.segment<3>(3 * node_of(k)) = Eigen::Map<const Eigen::Vector3d>(a + 3 * k);
  SFLSH_PETSC(VecRestoreArrayRead(x_all, &a));
}

PetscErrorCode FullSpaceSolver::Impl::function_cb(SNES s, Vec x, Vec f, void* ctx) {
  auto* self = static_cast<Impl*>(ctx);
  try {
    self->gather(x, self->x_full);
    if (!self->residual(self->x_full, f)) PetscCall(SNESSetFunctionDomainError(s));
  } catch (const std::exception& e) {
    logger()->debug("residual evaluation failed: {}", e.what());
    PetscCall(SNESSetFunctionDomainError(s));
  }
  return 0;
}

PetscErrorCode FullSpaceSolver::Impl::objective_cb(SNES, Vec x, PetscReal* value, void* ctx) {
  auto* self = static_cast<Impl*>(ctx);
  try {
    self->gather(x, self->x_full);
    *value = self->objective(self->x_full);
  } catch (const std::exception&) {
    *value = kInfinity;
  }
  return 0;
}

PetscErrorCode FullSpaceSolver::Impl::jacobian_cb(SNES s, Vec x, Mat, Mat, void* ctx) {
  auto* self = static_cast<Impl*>(ctx);
  try {
    self->gather(x, self->x_full);
    if (!self->jacobian(self->x_full)) PetscCall(SNESSetJacobianDomainError(s));
    self->choose_pc_rebuild(s);
  } catch (const std::exception& e) {
    logger()->debug("Hessian assembly failed: {}", e.what());
    PetscCall(SNESSetJacobianDomainError(s));
  }
  return 0;
}

// Backtracking on the incremental potential Φ itself (Armijo, c = 1e-4), not on ‖∇Φ‖: Newton on a
// minimization must decrease the energy. Trial points where Φ is not finite (Fung overflow) are halved
// away. Near the minimum Φ stops resolving decrease (round-off ~1e-16 |Φ|); there a step is accepted
// when it reduces ‖∇Φ‖ instead.
PetscErrorCode FullSpaceSolver::Impl::linesearch_cb(SNESLineSearch ls, void* ctx) {
  auto* self = static_cast<Impl*>(ctx);
  Vec Xv = nullptr, Fv = nullptr, Yv = nullptr, Wv = nullptr, Gv = nullptr;
  SNES s = nullptr;
  PetscCall(SNESLineSearchGetVecs(ls, &Xv, &Fv, &Yv, &Wv, &Gv));
  PetscCall(SNESLineSearchGetSNES(ls, &s));
  PetscReal fnorm = 0.0, slope = 0.0;
  PetscCall(VecNorm(Fv, NORM_2, &fnorm));
  PetscCall(VecDot(Fv, Yv, &slope));  // the update is X − λY, so the directional derivative is −λ·slope
  double phi0 = kInfinity;
  try {
    self->gather(Xv, self->x_full);
    phi0 = self->accepted_phi_valid && self->x_full == self->accepted_x ? self->accepted_phi
                                                                        : self->objective(self->x_full);
  } catch (const std::exception&) {
    phi0 = kInfinity;
  }
  if (!(slope > 0.0) || !std::isfinite(phi0)) {
    PetscCall(SNESLineSearchSetReason(ls, SNES_LINESEARCH_FAILED_USER));
    return 0;
  }
  double lambda = 1.0;
  for (int k = 0; k < 40; ++k, lambda *= 0.5) {
    PetscCall(VecWAXPY(Wv, -lambda, Yv, Xv));
    double phi = kInfinity;
    try {
      self->gather(Wv, self->x_full);
      phi = self->objective(self->x_full);
    } catch (const std::exception&) {
      phi = kInfinity;
    }
    if (!std::isfinite(phi)) continue;
    const bool armijo = phi <= phi0 - 1e-4 * lambda * slope;
    const bool roundoff = std::abs(phi - phi0) <= 1e-12 * std::max(1.0, std::abs(phi0));
    if (!armijo && !roundoff) continue;
    PetscCall(SNESComputeFunction(s, Wv, Gv));
    PetscBool domain_error = PETSC_FALSE;
    PetscCall(SNESGetFunctionDomainError(s, &domain_error));
    if (domain_error) continue;
    PetscReal gnorm = 0.0;
    PetscCall(VecNorm(Gv, NORM_2, &gnorm));
    if (!armijo && !(gnorm < fnorm)) continue;
    self->accepted_x = self->x_full;  // function_cb gathered Wv into x_full
    self->accepted_phi = phi;
    self->accepted_phi_valid = true;
    PetscCall(VecCopy(Wv, Xv));
    PetscCall(VecCopy(Gv, Fv));
    PetscCall(SNESLineSearchSetLambda(ls, lambda));
    PetscCall(SNESLineSearchComputeNorms(ls));
    PetscCall(SNESLineSearchSetReason(ls, SNES_LINESEARCH_SUCCEEDED));
    return 0;
  }
  PetscCall(SNESLineSearchSetReason(ls, SNES_LINESEARCH_FAILED_REDUCT));
  return 0;
}

// One substep of the integrator (time_integrator.hpp): ĥ and p̃ from the posed history carried in the state,
// Φ minimized by SNES, then the history advanced from the posed minimizer (every node, constrained ones too).
bool FullSpaceSolver::Impl::solve_substep(State& s, double t0, double dt) {
  const auto t_setup = Clock::now();
  ++substep_serial;  // a new ĥ and new maps: the cached inertia Hessian is stale
  t1 = t0 + dt;
  inertia = !options.quasi_static && problem.dynamic();
  NodeFrame previous;
  problem.frame(t0, previous);
  problem.frame(t1, frame);
  const RowMatrixX3d p_n = posed_positions(previous, s.x);
  model::PosedHistory history = model::history_of(s, flattened(p_n));
  // Without inertia the velocities are only reported: backward Euler's difference quotient.
  target = model::inertia_target(inertia ? options.integrator : model::Integrator::backward_euler, history, dt);
  if (inertia && target.integrator != options.integrator) ++stats->startup_steps;
  if (inertia) inertia_term->set_step(frame, target);
  gravity_term->set_frame(frame);

  // Start from the previous state, or from the inertial prediction pulled back through the maps.
  Eigen::VectorXd start = s.x;
  problem.apply_dirichlet(t1, start);
  prescribed = start;
  stats->inertia_seconds += seconds_since(t_setup);
  if (!problem.potentials.empty()) {
    // The potentials see p_n and the skinned positions at t1 (rest state with the prescribed values at t1).
    const auto t_potential = Clock::now();
    Eigen::VectorXd rest_now = Eigen::Map<const Eigen::VectorXd>(problem.rest.data(), problem.num_dofs());
    problem.apply_dirichlet(t1, rest_now);
    potential_term->begin(p_n, t0, dt, frame, rest_now, [this](int node) { return owns(node); });
    stats->potential_seconds += seconds_since(t_potential);
  }
  if (inertia && options.use_predictor) {
    const auto t_predict = Clock::now();
    Eigen::VectorXd predicted = start;
    for (int i = 0; i < problem.num_nodes(); ++i) {
      const auto si = static_cast<std::size_t>(i);
      // x_i = A_i⁻¹ (p̃_i − d_i) on the free components
      const Eigen::Vector3d xi = frame.A[si].lu().solve(target.p_tilde.segment<3>(3 * i) - frame.d.row(i).transpose());
      for (int k = 0; k < 3; ++k) {
        if (!constrained[3 * si + static_cast<std::size_t>(k)]) predicted[3 * i + k] = xi[k];
      }
    }
    stats->inertia_seconds += seconds_since(t_predict);
    if (predicted.allFinite() && objective(predicted) < objective(start)) start = predicted;
  }
  const int max_refinements = potential_term->active() ? potential_term->max_refinements() : 0;
  Eigen::VectorXd x_new;
  for (int refinement = 0;; ++refinement) {
    if (!solve_from(start, dt)) return false;
    gather(X, x_new);
    if (!x_new.allFinite()) return false;
    if (!potential_term->active()) break;
    const auto t_accept = Clock::now();
    const bool accepted = potential_term->accept(x_new);
    stats->potential_seconds += seconds_since(t_accept);
    if (accepted) break;
    if (std::string why = potential_term->unresolved(); !why.empty()) {
      stats->converged_reason = why;  // refused for good: the ladder tries smaller substeps, then stops with it
      return false;
    }
    if (refinement >= max_refinements) {
      logger()->warn("t = {:.6g}: contact still over its tolerance after {} refinement(s); the substep is kept", t1,
                     refinement);
      break;
    }
    ++stats->potential_refinements;
  }
  PetscReal fnorm = 0.0;
  VecNorm(F, NORM_2, &fnorm);
  stats->final_gradient = fnorm;
  const auto t_history = Clock::now();
  model::advance_history(target, history, flattened(posed_positions(frame, x_new)));
  stats->inertia_seconds += seconds_since(t_history);
  if (!history.v.allFinite() || !history.a.allFinite()) return false;
  s.t = t1;
  s.x = std::move(x_new);
  model::store_history(history, s);
  return true;
}

bool FullSpaceSolver::Impl::solve_from(const Eigen::VectorXd& start, double dt) {
  {
    PetscScalar* a = nullptr;
    SFLSH_PETSC(VecGetArray(X, &a));
    for (int k = begin; k < end; ++k)
      Eigen::Map<Eigen::Vector3d>(a + 3 * (k - begin)) = start.segment<3>(3 * node_of(k));
    SFLSH_PETSC(VecRestoreArray(X, &a));
  }

  accepted_phi_valid = false;  // a new substep or refinement: Φ itself may have changed
  SFLSH_PETSC(PetscPushErrorHandler(PetscReturnErrorHandler, nullptr));
  const PetscErrorCode code = SNESSolve(snes, nullptr, X);
  PetscPopErrorHandler();
  SNESConvergedReason reason = SNES_CONVERGED_ITERATING;
  SNESGetConvergedReason(snes, &reason);
  PetscInt its = 0, lits = 0;
  SNESGetIterationNumber(snes, &its);
  SNESGetLinearSolveIterations(snes, &lits);
  stats->newton_iterations += static_cast<int>(its);
  stats->linear_iterations += static_cast<int>(lits);
  stats->converged_reason =
      code != 0 ? fmt::format("PETSc error {}", static_cast<int>(code)) : SNESConvergedReasons[reason];
  linear_failure = code == 0 && reason == SNES_DIVERGED_LINEAR_SOLVE;
  if (truncated_newton) {
    PetscInt failures = 0;
    SNESGetLinearSolveFailures(snes, &failures);
    stats->truncated_solves += static_cast<int>(failures);
  }
  if (code != 0 || reason <= 0) {
    pc_reuse.force = true;  // the retry starts from a fresh preconditioner
    logger()->debug("t = {:.6g}: substep of {:.3g} s failed ({})", t1, dt, stats->converged_reason);
    return false;
  }
  return true;
}

FullSpaceSolver::FullSpaceSolver(const Problem& problem, MPI_Comm comm, const FullSpaceOptions& options)
    : impl_(std::make_unique<Impl>(problem, comm, options)) {
  require(static_cast<int>(problem.tet_rest.size()) == problem.num_tets(),
          "FullSpaceSolver: the problem is not validated");
  try {
    impl_->setup();
  } catch (...) {
    impl_->destroy();
    throw;
  }
}

FullSpaceSolver::~FullSpaceSolver() { impl_->destroy(); }

void FullSpaceSolver::initialize(const State& s) {
  require(s.x.size() == impl_->problem.num_dofs() && s.w.size() == impl_->problem.num_dofs(),
          "FullSpaceSolver: initial state has {} / {} entries, expected {}", s.x.size(), s.w.size(),
          impl_->problem.num_dofs());
  require(s.x.allFinite() && s.w.allFinite(), "FullSpaceSolver: initial state is not finite");
  const Eigen::Index dofs = impl_->problem.num_dofs();
  for (const Eigen::VectorXd* history : {&s.a, &s.p_previous, &s.w_previous}) {
    require(history->size() == 0 || (history->size() == dofs && history->allFinite()),
            "FullSpaceSolver: the initial state's history has {} entries (expected 0 or {}) or is not finite",
            history->size(), dofs);
  }
  impl_->state = s;
  // Newmark starts from the accelerations of the equations of motion when the state carries none.
  const bool dynamic = !impl_->options.quasi_static && impl_->problem.dynamic();
  if (impl_->options.integrator == model::Integrator::newmark && dynamic && s.a.size() != impl_->problem.num_dofs())
    impl_->state.a = model::initial_acceleration(impl_->problem, impl_->state);
}

const State& FullSpaceSolver::state() const { return impl_->state; }

int FullSpaceSolver::assembly_threads() const { return impl_->arena->max_concurrency(); }

std::string FullSpaceSolver::preconditioner_type() const {
  if (!impl_->saved_pc_type.empty()) return impl_->saved_pc_type;  // during a CG + Jacobi fallback
  KSP ksp = nullptr;
  PC pc = nullptr;
  SFLSH_PETSC(SNESGetKSP(impl_->snes, &ksp));
  SFLSH_PETSC(KSPGetPC(ksp, &pc));
  PCType type = nullptr;
  SFLSH_PETSC(PCGetType(pc, &type));
  return type ? type : "";
}

std::vector<int> FullSpaceSolver::owned_nodes() const {
  std::vector<int> nodes;
  for (int k = impl_->begin; k < impl_->end; ++k) nodes.push_back(impl_->node_of(k));
  std::sort(nodes.begin(), nodes.end());
  return nodes;
}

namespace {

/// The full-space solver on the model's robustness ladder (step_ladder.hpp). A substep whose linear solve broke
/// down is tried once more with CG + Jacobi before the ladder moves on (the configured preconditioner comes back
/// after the step).
class FullSpaceLadder final : public model::LadderSolver {
 public:
  explicit FullSpaceLadder(FullSpaceSolver::Impl& impl) : impl_(impl) {}
  double time() const override { return impl_.state.t; }
  void save() override { saved_ = impl_.state; }
  void restore() override { impl_.state = saved_; }
  bool attempt(double dt, material::HessianProjection hessian, StepStats& stats, std::string& reason) override {
    impl_.stats = &stats;
    impl_.projection_now = hessian;
    impl_.set_truncated_newton(hessian == material::HessianProjection::kNone &&
                               impl_.options.truncate_on_negative_curvature);
    State s = impl_.state;
    bool ok = impl_.solve_substep(s, s.t, dt);
    if (!ok && impl_.linear_failure && impl_.saved_pc_type.empty() && hessian != material::HessianProjection::kNone) {
      impl_.use_fallback_pc();
      s = impl_.state;
      ok = impl_.solve_substep(s, s.t, dt);
    }
    if (!ok) {
      reason = stats.converged_reason;
      return false;
    }
    impl_.state = std::move(s);
    return true;
  }

 private:
  FullSpaceSolver::Impl& impl_;
  State saved_;
};

}  // namespace

StepStats FullSpaceSolver::step(double h) {
  // Exact Hessian first when the mass term keeps the system positive definite in practice; a failed attempt
  // repeats the same step with the problem's projection before any halving.
  model::LadderOptions ladder_options;
  ladder_options.exact_hessian_first = impl_->options.exact_hessian_first && !impl_->options.quasi_static &&
                                       impl_->problem.dynamic() &&
                                       impl_->problem.projection != material::HessianProjection::kNone;
  ladder_options.projection = impl_->problem.projection;
  ladder_options.max_halvings = impl_->options.max_halvings;
  FullSpaceLadder ladder(*impl_);
  StepStats stats;
  try {
    stats = model::step_with_ladder(ladder, h, ladder_options, integrator_label(impl_->options.integrator));
  } catch (...) {
    impl_->restore_pc();
    impl_->stats = nullptr;
    throw;
  }
  impl_->restore_pc();
  impl_->stats = nullptr;
  return stats;
}

}  // namespace sflsh::fullspace
