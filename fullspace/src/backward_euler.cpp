#include <sflsh/fullspace/backward_euler.hpp>
#include <sflsh/fullspace/node_partition.hpp>

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>

#include <Eigen/LU>
#include <petscsnes.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace sflsh::fullspace {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// PETSc calls inside the integrator: a non-zero code becomes sflsh::Error naming the call.
void check(PetscErrorCode code, const char* what) {
  if (code != 0) throw_error("PETSc call {} failed with error code {}", what, static_cast<int>(code));
}
#define SFLSH_PETSC(call) check((call), #call)


constexpr double kInfinity = std::numeric_limits<double>::infinity();

material::TetNodes problem_rest_nodes(const Problem& problem, int e) {
  material::TetNodes nodes;
  for (int a = 0; a < 4; ++a) nodes.col(a) = problem.rest.row(problem.tets(e, a)).transpose();
  return nodes;
}

/// The preconditioner unless -pc_type says otherwise (measurements: docs/fullspace.md, docs/decisions.md).
/// Up to kDirectDofs a sparse direct factorization: faster there, and immune to the smoother trouble AMG has on
/// a handful of aggregates (GAMG's Chebyshev smoother came out indefinite on 72-dof verification bars).
/// Dynamic steps: M/h² keeps the system well conditioned, so CG converges in ~15 iterations with an incomplete
/// Cholesky factor (one block per rank in parallel), which costs a fraction of GAMG's setup; on the default
/// layer ICC took 0.43 s per step against GAMG's 1.2 s. Without the mass term (quasi-static and static
/// problems) the ICC iteration count grows with the mesh and GAMG, with the rigid-body near-null space, wins.
PCType default_pc_type(int dofs, int size, bool dynamic) {
  constexpr int kDirectDofs = 6000;
  if (dofs <= kDirectDofs) return size == 1 ? PCCHOLESKY : PCREDUNDANT;
  if (!dynamic) return PCGAMG;
  // Block Jacobi's blocks default to ICC for a matrix marked symmetric (MAT_SYMMETRIC below).
  return size == 1 ? PCICC : PCBJACOBI;
}

}  // namespace

struct BackwardEuler::Impl {
  const Problem& problem;
  MPI_Comm comm;
  BackwardEulerOptions options;
  int rank = 0;
  int size = 1;
  /// PETSc's numbering of the nodes (see node_partition.hpp): rows, vector entries and ownership ranges are
  /// in solver indices; the problem's vectors (x_full, prescribed, the Eigen state) stay in mesh order.
  NodePartition partition;
  int begin = 0, end = 0;           ///< this rank's solver indices
  std::vector<int> my_tets;         ///< tets whose lowest solver index is owned: each counted once in Φ
  /// Tets with at least one owned node: the gradient and Hessian rows of the owned nodes are complete from
  /// these alone, so no entry is sent to another rank (interface tets are evaluated on both sides).
  std::vector<int> row_tets;
  std::vector<char> constrained;    ///< per dof (mesh order)
  std::unique_ptr<tbb::task_arena> arena;

  Vec X = nullptr, F = nullptr, x_all = nullptr;
  VecScatter to_all = nullptr;
  Mat J = nullptr;
  SNES snes = nullptr;

  State state;

  // The step being solved.
  double t1 = 0.0, h = 0.0;
  bool inertia = true;
  NodeFrame frame;
  RowMatrixX3d p_tilde;
  Eigen::VectorXd x_full;
  Eigen::VectorXd prescribed;       ///< x values at t1 (full), valid on constrained dofs

  StepStats* stats = nullptr;
  bool linear_failure = false;      ///< the last substep failed in the linear solver
  std::string saved_pc_type;        ///< the configured PC while the fallback is in use (empty otherwise)

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
    Mat diag = nullptr, offdiag = nullptr;     ///< borrowed from J
    std::ptrdiff_t diag_nnz = 0, offdiag_nnz = 0;
    /// Per row tet, 16 blocks (a, b) × 3 rows: ≥ 0 offset into diag, < −1 offset −(o + 2) into offdiag,
    /// −1: the row belongs to another rank (which assembles it from its own row tets).
    std::vector<PetscInt> tet_offset;
    std::vector<PetscInt> node_offset;         ///< per owned node, 3 rows: offsets of its diagonal block
  } refill;

  Impl(const Problem& p, MPI_Comm c, const BackwardEulerOptions& o) : problem(p), comm(c), options(o) {}

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
  double objective(const Eigen::VectorXd& x);
  bool residual(const Eigen::VectorXd& x, Vec out);
  bool jacobian(const Eigen::VectorXd& x);
  void build_refill();
  void mark_diagonal_block_symmetric();
  bool solve_substep(State& s, double t0, double dt);

  static PetscErrorCode function_cb(SNES, Vec x, Vec f, void* ctx);
  static PetscErrorCode objective_cb(SNES, Vec x, PetscReal* value, void* ctx);
  static PetscErrorCode jacobian_cb(SNES, Vec x, Mat, Mat, void* ctx);
  static PetscErrorCode linesearch_cb(SNESLineSearch ls, void* ctx);
};

void BackwardEuler::Impl::setup() {
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const int n = problem.num_nodes();
  partition = partition_nodes(n, problem.tets, size);
  begin = partition.range[static_cast<std::size_t>(rank)];
  end = partition.range[static_cast<std::size_t>(rank) + 1];
  const int local = end - begin;

  // Threads within a rank share the machine with the other ranks.
  const int threads = std::max(1, tbb::this_task_arena::max_concurrency() / size);
  arena = std::make_unique<tbb::task_arena>(threads);

  constrained = problem.dirichlet.mask(n);
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
  auto by_lowest = [&](int a, int b) { return lowest[static_cast<std::size_t>(a)] < lowest[static_cast<std::size_t>(b)]; };
  std::stable_sort(my_tets.begin(), my_tets.end(), by_lowest);
  std::stable_sort(row_tets.begin(), row_tets.end(), by_lowest);

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
  SFLSH_PETSC(MatSetOption(J, MAT_ROW_ORIENTED, PETSC_FALSE));   // Eigen's column-major blocks
  SFLSH_PETSC(MatSetOption(J, MAT_SYMMETRIC, PETSC_TRUE));
  SFLSH_PETSC(MatSetOption(J, MAT_SYMMETRY_ETERNAL, PETSC_TRUE));

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

  {
    double sum = 0.0, count = 0.0;
    for (int e : my_tets) {
      const auto se = static_cast<std::size_t>(e);
      const material::Matrix12d K = material::tet_elastic_dq2(problem.tet_rest[se], problem_rest_nodes(problem, e),
                                                              problem.tet_material[se], material::HessianProjection::kNone);
      if (K.allFinite()) {
        sum += K.diagonal().sum();
        count += 12.0;
      }
    }
    double mine[2] = {sum, count}, global[2] = {0.0, 0.0};
    MPI_Allreduce(mine, global, 2, MPI_DOUBLE, MPI_SUM, comm);
    if (global[1] > 0.0 && global[0] > 0.0) dirichlet_diagonal = global[0] / global[1];
  }
  // The project's defaults are set on the objects before SNESSetFromOptions, so any -snes_*, -ksp_*, -pc_*
  // option (command line, PETSC_OPTIONS, -options_file) overrides them, and nothing leaks into the global
  // options database that a later solver in the same process would mistake for a user choice.
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
  SFLSH_PETSC(PCSetType(pc, default_pc_type(3 * n, size, dynamic)));
  SNESLineSearch linesearch = nullptr;
  SFLSH_PETSC(SNESGetLineSearch(snes, &linesearch));
  SFLSH_PETSC(SNESLineSearchSetType(linesearch, SNESLINESEARCHSHELL));
  SFLSH_PETSC(SNESLineSearchShellSetUserFunc(linesearch, &Impl::linesearch_cb, this));
  SFLSH_PETSC(SNESSetFromOptions(snes));
}

void BackwardEuler::Impl::destroy() {
  if (snes) SNESDestroy(&snes);
  if (J) MatDestroy(&J);
  if (to_all) VecScatterDestroy(&to_all);
  if (x_all) VecDestroy(&x_all);
  if (F) VecDestroy(&F);
  if (X) VecDestroy(&X);
}

void BackwardEuler::Impl::gather(Vec v, Eigen::VectorXd& out) {
  SFLSH_PETSC(VecScatterBegin(to_all, v, x_all, INSERT_VALUES, SCATTER_FORWARD));
  SFLSH_PETSC(VecScatterEnd(to_all, v, x_all, INSERT_VALUES, SCATTER_FORWARD));
  const PetscScalar* a = nullptr;
  SFLSH_PETSC(VecGetArrayRead(x_all, &a));
  out.resize(problem.num_dofs());
  for (int k = 0; k < problem.num_nodes(); ++k) out.segment<3>(3 * node_of(k)) = Eigen::Map<const Eigen::Vector3d>(a + 3 * k);
  SFLSH_PETSC(VecRestoreArrayRead(x_all, &a));
}

namespace {

material::TetNodes tet_nodes(const Problem& problem, const Eigen::VectorXd& x, int e) {
  material::TetNodes nodes;
  for (int a = 0; a < 4; ++a) nodes.col(a) = x.segment<3>(3 * problem.tets(e, a));
  return nodes;
}

}  // namespace

// The potential sees constrained components at their prescribed values (so the free rows do not depend on
// them) plus the penalty ½ D (x_d − x̄_d)², which is zero at every Newton iterate; its gradient and Hessian are
// then exactly what residual() and jacobian() assemble.
double BackwardEuler::Impl::objective(const Eigen::VectorXd& x_in) {
  const auto t0 = Clock::now();
  const Eigen::VectorXd& x = with_prescribed(x_in);
  double penalty = 0.0;
  for (int k = begin; k < end; ++k) {
    for (int d = 3 * node_of(k); d < 3 * node_of(k) + 3; ++d) {
      if (constrained[static_cast<std::size_t>(d)]) penalty += 0.5 * dirichlet_diagonal * std::pow(x_in[d] - x[d], 2);
    }
  }
  tbb::enumerable_thread_specific<double> partial(0.0);
  arena->execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, my_tets.size(), 256), [&](const auto& range) {
      double& acc = partial.local();
      for (std::size_t k = range.begin(); k < range.end(); ++k) {
        const int e = my_tets[k];
        const auto se = static_cast<std::size_t>(e);
        try {
          const double scale = problem.tet_energy_scale.empty() ? 1.0 : problem.tet_energy_scale[se];
          acc += scale * material::tet_elastic_energy(problem.tet_rest[se], tet_nodes(problem, x, e), problem.tet_material[se]);
        } catch (const Error&) {
          acc = kInfinity;   // the Fung exponent overflowed: this trial point is out of reach
        }
      }
    });
  });
  double local = partial.combine(std::plus<double>()) + penalty;
  for (int k = begin; k < end; ++k) {
    const int i = node_of(k);
    const double m = problem.mass[i];
    if (m == 0.0) continue;
    const auto si = static_cast<std::size_t>(i);
    const Eigen::Vector3d p = frame.A[si] * x.segment<3>(3 * i) + frame.d.row(i).transpose();
    if (inertia) local += m / (2.0 * h * h) * (p - p_tilde.row(i).transpose()).squaredNorm();
    local -= m * problem.gravity.dot(p);
  }
  if (!std::isfinite(local)) local = kInfinity;
  double global = 0.0;
  MPI_Allreduce(&local, &global, 1, MPI_DOUBLE, MPI_SUM, comm);
  if (stats) stats->function_seconds += seconds_since(t0);
  return global;
}

bool BackwardEuler::Impl::residual(const Eigen::VectorXd& x_in, Vec out) {
  const auto t0 = Clock::now();
  const Eigen::VectorXd& x = with_prescribed(x_in);
  const int n = problem.num_nodes();
  tbb::enumerable_thread_specific<Eigen::VectorXd> partial([n] { return Eigen::VectorXd::Zero(3 * n); });
  tbb::enumerable_thread_specific<int> failed(0);
  arena->execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, row_tets.size(), 256), [&](const auto& range) {
      Eigen::VectorXd& g = partial.local();
      for (std::size_t k = range.begin(); k < range.end(); ++k) {
        const int e = row_tets[k];
        const auto se = static_cast<std::size_t>(e);
        try {
          const double scale = problem.tet_energy_scale.empty() ? 1.0 : problem.tet_energy_scale[se];
          const material::Vector12d ge =
              scale * material::tet_elastic_dq(problem.tet_rest[se], tet_nodes(problem, x, e), problem.tet_material[se]);
          for (int a = 0; a < 4; ++a) g.segment<3>(3 * problem.tets(e, a)) += ge.segment<3>(3 * a);
        } catch (const Error&) {
          ++failed.local();
        }
      }
    });
  });
  Eigen::VectorXd g = Eigen::VectorXd::Zero(3 * n);
  for (const auto& part : partial) g += part;
  int local_failed = failed.combine(std::plus<int>());
  for (int k = begin; k < end; ++k) {
    const int i = node_of(k);
    const double m = problem.mass[i];
    if (m == 0.0) continue;
    const auto si = static_cast<std::size_t>(i);
    const Eigen::Vector3d p = frame.A[si] * x.segment<3>(3 * i) + frame.d.row(i).transpose();
    Eigen::Vector3d force = -m * problem.gravity;
    if (inertia) force += m / (h * h) * (p - p_tilde.row(i).transpose());
    g.segment<3>(3 * i) += frame.A[si].transpose() * force;
  }
  // Constrained rows: D (x_d − x̄_d), zero at every iterate (x starts on the prescribed values and the Jacobian row
  // D e_d keeps it there), so that the residual's derivative is the assembled row (PETSc's Jacobian test).
  for (int d = 0; d < 3 * n; ++d) {
    if (constrained[static_cast<std::size_t>(d)]) g[d] = dirichlet_diagonal * (x_in[d] - prescribed[d]);
  }
  if (!g.allFinite()) ++local_failed;
  int any_failed = 0;
  MPI_Allreduce(&local_failed, &any_failed, 1, MPI_INT, MPI_SUM, comm);

  // The owned rows are complete (row_tets): written in place, nothing goes to another rank.
  PetscScalar* a = nullptr;
  SFLSH_PETSC(VecGetArray(out, &a));
  for (int k = begin; k < end; ++k) {
    Eigen::Map<Eigen::Vector3d> row(a + 3 * (k - begin));
    if (any_failed == 0) {
      row = g.segment<3>(3 * node_of(k));
    } else {
      row.setZero();
    }
  }
  SFLSH_PETSC(VecRestoreArray(out, &a));
  if (stats) stats->function_seconds += seconds_since(t0);
  return any_failed == 0;
}

bool BackwardEuler::Impl::jacobian(const Eigen::VectorXd& x) {
  const auto t0 = Clock::now();
  PetscScalar* diag_values = nullptr;
  PetscScalar* offdiag_values = nullptr;
  if (refill.ready) {
    SFLSH_PETSC(MatSeqAIJGetArray(refill.diag, &diag_values));
    std::fill(diag_values, diag_values + refill.diag_nnz, 0.0);
    if (refill.offdiag) {
      SFLSH_PETSC(MatSeqAIJGetArray(refill.offdiag, &offdiag_values));
      std::fill(offdiag_values, offdiag_values + refill.offdiag_nnz, 0.0);
    }
  } else {
    SFLSH_PETSC(MatZeroEntries(J));
  }
  auto add_rows = [&](const PetscInt* offsets, const auto& block) {   // 3 rows of a 3×3 block
    for (int r = 0; r < 3; ++r) {
      const PetscInt o = offsets[r];
      PetscScalar* dst = o >= 0 ? diag_values + o : offdiag_values + (-o - 2);
      for (int c = 0; c < 3; ++c) dst[c] += block(r, c);
    }
  };
  constexpr std::size_t kBatch = 8192;
  std::vector<material::Matrix12d> blocks(std::min(kBatch, row_tets.size()));
  int local_failed = 0;
  for (std::size_t first = 0; first < row_tets.size(); first += kBatch) {
    const std::size_t count = std::min(kBatch, row_tets.size() - first);
    tbb::enumerable_thread_specific<int> failed(0);
    arena->execute([&] {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 64), [&](const auto& range) {
        for (std::size_t k = range.begin(); k < range.end(); ++k) {
          const int e = row_tets[first + k];
          const auto se = static_cast<std::size_t>(e);
          material::Matrix12d& K = blocks[k];
          try {
            const double scale = problem.tet_energy_scale.empty() ? 1.0 : problem.tet_energy_scale[se];
            K = scale * material::tet_elastic_dq2(problem.tet_rest[se], tet_nodes(problem, x, e), problem.tet_material[se],
                                                  projection_now);
          } catch (const Error&) {
            K.setZero();
            ++failed.local();
          }
          for (int a = 0; a < 4; ++a) {
            for (int i = 0; i < 3; ++i) {
              if (!constrained[static_cast<std::size_t>(3 * problem.tets(e, a) + i)]) continue;
              K.row(3 * a + i).setZero();
              K.col(3 * a + i).setZero();
            }
          }
          if (!K.allFinite()) ++failed.local();
        }
      });
    });
    local_failed += failed.combine(std::plus<int>());
    for (std::size_t k = 0; k < count; ++k) {
      const int e = row_tets[first + k];
      if (!refill.ready) {
        // Rows of other ranks get a negative index, which PETSc skips: their owner adds them.
        PetscInt rows[4], cols[4];
        for (int a = 0; a < 4; ++a) {
          cols[a] = index_of(problem.tets(e, a));
          rows[a] = owns(problem.tets(e, a)) ? cols[a] : -1;
        }
        SFLSH_PETSC(MatSetValuesBlocked(J, 4, rows, 4, cols, blocks[k].data(), ADD_VALUES));
        continue;
      }
      const PetscInt* offsets = refill.tet_offset.data() + 48 * (first + k);
      for (int a = 0; a < 4; ++a) {
        for (int b = 0; b < 4; ++b, offsets += 3) {
          if (offsets[0] != -1) add_rows(offsets, blocks[k].block<3, 3>(3 * a, 3 * b));
        }
      }
    }
  }
  for (int row = begin; row < end; ++row) {
    const int i = node_of(row);
    const auto si = static_cast<std::size_t>(i);
    Eigen::Matrix3d B = Eigen::Matrix3d::Zero();
    if (inertia && problem.mass[i] > 0.0) B = problem.mass[i] / (h * h) * frame.A[si].transpose() * frame.A[si];
    for (int k = 0; k < 3; ++k) {
      if (!constrained[3 * si + static_cast<std::size_t>(k)]) continue;
      B.row(k).setZero();
      B.col(k).setZero();
      B(k, k) = dirichlet_diagonal;
    }
    if (refill.ready) {
      add_rows(refill.node_offset.data() + 3 * (row - begin), B);
      continue;
    }
    const PetscInt block = row;
    SFLSH_PETSC(MatSetValuesBlocked(J, 1, &block, 1, &block, B.data(), ADD_VALUES));
  }
  if (refill.ready) {
    SFLSH_PETSC(MatSeqAIJRestoreArray(refill.diag, &diag_values));
    if (refill.offdiag) SFLSH_PETSC(MatSeqAIJRestoreArray(refill.offdiag, &offdiag_values));
    // Preconditioners must see a new matrix: adding a zero through the public API raises J's object state.
    if (end > begin) {
      const PetscInt block = begin;
      const Eigen::Matrix3d zero = Eigen::Matrix3d::Zero();
      SFLSH_PETSC(MatSetValuesBlocked(J, 1, &block, 1, &block, zero.data(), ADD_VALUES));
    }
  }
  SFLSH_PETSC(MatAssemblyBegin(J, MAT_FINAL_ASSEMBLY));
  SFLSH_PETSC(MatAssemblyEnd(J, MAT_FINAL_ASSEMBLY));
  if (!refill.ready) {
    mark_diagonal_block_symmetric();
    build_refill();
  }
  int any_failed = 0;
  MPI_Allreduce(&local_failed, &any_failed, 1, MPI_INT, MPI_SUM, comm);
  if (stats) stats->jacobian_seconds += seconds_since(t0);
  return any_failed == 0;
}

// J is marked symmetric, but the symmetry flag of the whole matrix does not reach its local diagonal block,
// which is what block Jacobi hands to each block's preconditioner: marked too, its blocks default to ICC
// (PETSc's choice for a matrix known to be symmetric) instead of ILU, at half the factorization cost.
// An explicit -sub_pc_type still wins.
void BackwardEuler::Impl::mark_diagonal_block_symmetric() {
  PetscBool has_block = PETSC_FALSE;
  SFLSH_PETSC(MatHasOperation(J, MATOP_GET_DIAGONAL_BLOCK, &has_block));
  if (!has_block) return;
  Mat block = nullptr;
  SFLSH_PETSC(MatGetDiagonalBlock(J, &block));
  SFLSH_PETSC(MatSetOption(block, MAT_SYMMETRIC, PETSC_TRUE));
  SFLSH_PETSC(MatSetOption(block, MAT_SYMMETRY_ETERNAL, PETSC_TRUE));
}

// Offsets of every block of the assembled pattern (see Refill). Only for PETSc's own AIJ storage; any other
// -mat_type keeps the MatSetValuesBlocked path.
void BackwardEuler::Impl::build_refill() {
  MatType type = nullptr;
  SFLSH_PETSC(MatGetType(J, &type));
  const PetscInt* colmap = nullptr;
  PetscInt colmap_size = 0;
  Mat diag = nullptr, offdiag = nullptr;
  std::string name = type;
  if (name == MATSEQAIJ) {
    diag = J;
  } else if (name == MATMPIAIJ) {
    SFLSH_PETSC(MatMPIAIJGetSeqAIJ(J, &diag, &offdiag, &colmap));
    PetscInt rows = 0;
    SFLSH_PETSC(MatGetSize(offdiag, &rows, &colmap_size));
  } else {
    logger()->debug("Hessian matrix type {}: assembling through MatSetValuesBlocked", name);
    refill.ready = false;
    return;
  }
  struct Csr {
    std::vector<PetscInt> ia, ja;
  };
  auto read_csr = [&](Mat m) {
    Csr csr;
    PetscInt n = 0;
    const PetscInt *ia = nullptr, *ja = nullptr;
    PetscBool done = PETSC_FALSE;
    SFLSH_PETSC(MatGetRowIJ(m, 0, PETSC_FALSE, PETSC_FALSE, &n, &ia, &ja, &done));
    require(done == PETSC_TRUE, "Hessian refill: the matrix does not expose its rows");
    csr.ia.assign(ia, ia + n + 1);
    csr.ja.assign(ja, ja + ia[n]);
    SFLSH_PETSC(MatRestoreRowIJ(m, 0, PETSC_FALSE, PETSC_FALSE, &n, &ia, &ja, &done));
    return csr;
  };
  const Csr d = read_csr(diag);
  const Csr o = offdiag ? read_csr(offdiag) : Csr{};
  // Offset of scalar column `col` (global) in local scalar row `row`, as encoded in Refill.
  auto find = [&](int row, PetscInt col) -> PetscInt {
    const PetscInt cstart = 3 * static_cast<PetscInt>(begin), cend = 3 * static_cast<PetscInt>(end);
    if (col >= cstart && col < cend) {
      const auto first = d.ja.begin() + d.ia[static_cast<std::size_t>(row)];
      const auto last = d.ja.begin() + d.ia[static_cast<std::size_t>(row) + 1];
      const auto it = std::lower_bound(first, last, col - cstart);
      require(it != last && *it == col - cstart, "Hessian refill: entry ({}, {}) is not in the pattern", row, col);
      return static_cast<PetscInt>(it - d.ja.begin());
    }
    require(offdiag != nullptr, "Hessian refill: column {} outside the owned range on one process", col);
    const PetscInt* k = std::lower_bound(colmap, colmap + colmap_size, col);
    require(k != colmap + colmap_size && *k == col, "Hessian refill: column {} is not in the column map", col);
    const PetscInt local = static_cast<PetscInt>(k - colmap);
    const auto first = o.ja.begin() + o.ia[static_cast<std::size_t>(row)];
    const auto last = o.ja.begin() + o.ia[static_cast<std::size_t>(row) + 1];
    const auto it = std::lower_bound(first, last, local);
    require(it != last && *it == local, "Hessian refill: entry ({}, {}) is not in the pattern", row, col);
    return -static_cast<PetscInt>(it - o.ja.begin()) - 2;
  };
  // The three columns of a block are adjacent in both storages (sorted columns, whole blocks present).
  refill.tet_offset.assign(48 * row_tets.size(), -1);
  for (std::size_t k = 0; k < row_tets.size(); ++k) {
    const int e = row_tets[k];
    PetscInt* out = refill.tet_offset.data() + 48 * k;
    for (int a = 0; a < 4; ++a) {
      const int I = index_of(problem.tets(e, a));
      for (int b = 0; b < 4; ++b, out += 3) {
        if (I < begin || I >= end) continue;
        for (int r = 0; r < 3; ++r) out[r] = find(3 * (I - begin) + r, 3 * static_cast<PetscInt>(index_of(problem.tets(e, b))));
      }
    }
  }
  refill.node_offset.resize(3 * static_cast<std::size_t>(end - begin));
  for (int i = begin; i < end; ++i) {
    for (int r = 0; r < 3; ++r) refill.node_offset[3 * static_cast<std::size_t>(i - begin) + static_cast<std::size_t>(r)] =
        find(3 * (i - begin) + r, 3 * static_cast<PetscInt>(i));
  }
  refill.diag = diag;
  refill.offdiag = offdiag;
  refill.diag_nnz = static_cast<std::ptrdiff_t>(d.ia.back());
  refill.offdiag_nnz = offdiag ? static_cast<std::ptrdiff_t>(o.ia.back()) : 0;
  refill.ready = true;
}

PetscErrorCode BackwardEuler::Impl::function_cb(SNES s, Vec x, Vec f, void* ctx) {
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

PetscErrorCode BackwardEuler::Impl::objective_cb(SNES, Vec x, PetscReal* value, void* ctx) {
  auto* self = static_cast<Impl*>(ctx);
  try {
    self->gather(x, self->x_full);
    *value = self->objective(self->x_full);
  } catch (const std::exception&) {
    *value = kInfinity;
  }
  return 0;
}

PetscErrorCode BackwardEuler::Impl::jacobian_cb(SNES s, Vec x, Mat, Mat, void* ctx) {
  auto* self = static_cast<Impl*>(ctx);
  try {
    self->gather(x, self->x_full);
    if (!self->jacobian(self->x_full)) PetscCall(SNESSetJacobianDomainError(s));
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
PetscErrorCode BackwardEuler::Impl::linesearch_cb(SNESLineSearch ls, void* ctx) {
  auto* self = static_cast<Impl*>(ctx);
  Vec Xv = nullptr, Fv = nullptr, Yv = nullptr, Wv = nullptr, Gv = nullptr;
  SNES s = nullptr;
  PetscCall(SNESLineSearchGetVecs(ls, &Xv, &Fv, &Yv, &Wv, &Gv));
  PetscCall(SNESLineSearchGetSNES(ls, &s));
  PetscReal fnorm = 0.0, slope = 0.0;
  PetscCall(VecNorm(Fv, NORM_2, &fnorm));
  PetscCall(VecDot(Fv, Yv, &slope));   // the update is X − λY, so the directional derivative is −λ·slope
  double phi0 = kInfinity;
  try {
    self->gather(Xv, self->x_full);
    phi0 = self->objective(self->x_full);
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

bool BackwardEuler::Impl::solve_substep(State& s, double t0, double dt) {
  t1 = t0 + dt;
  h = dt;
  inertia = !options.quasi_static && problem.dynamic();
  NodeFrame previous;
  problem.frame(t0, previous);
  problem.frame(t1, frame);
  const RowMatrixX3d p_n = posed_positions(previous, s.x);
  p_tilde = p_n;
  for (int i = 0; i < problem.num_nodes(); ++i) p_tilde.row(i) += dt * s.w.segment<3>(3 * i).transpose();

  // Start from the previous state, or from the inertial prediction pulled back through the maps.
  Eigen::VectorXd start = s.x;
  problem.apply_dirichlet(t1, start);
  prescribed = start;
  if (inertia && options.use_predictor) {
    Eigen::VectorXd predicted = start;
    for (int i = 0; i < problem.num_nodes(); ++i) {
      const auto si = static_cast<std::size_t>(i);
      const Eigen::Vector3d xi = frame.A[si].lu().solve(p_tilde.row(i).transpose() - frame.d.row(i).transpose());
      for (int k = 0; k < 3; ++k) {
        if (!constrained[3 * si + static_cast<std::size_t>(k)]) predicted[3 * i + k] = xi[k];
      }
    }
    if (predicted.allFinite() && objective(predicted) < objective(start)) start = predicted;
  }
  {
    PetscScalar* a = nullptr;
    SFLSH_PETSC(VecGetArray(X, &a));
    for (int k = begin; k < end; ++k) Eigen::Map<Eigen::Vector3d>(a + 3 * (k - begin)) = start.segment<3>(3 * node_of(k));
    SFLSH_PETSC(VecRestoreArray(X, &a));
  }

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
  stats->converged_reason = code != 0 ? fmt::format("PETSc error {}", static_cast<int>(code)) : SNESConvergedReasons[reason];
  linear_failure = code == 0 && reason == SNES_DIVERGED_LINEAR_SOLVE;
  if (code != 0 || reason <= 0) {
    logger()->debug("t = {:.6g}: substep of {:.3g} s failed ({})", t1, dt, stats->converged_reason);
    return false;
  }
  Eigen::VectorXd x_new;
  gather(X, x_new);
  PetscReal fnorm = 0.0;
  VecNorm(F, NORM_2, &fnorm);
  stats->final_residual = fnorm;
  if (!x_new.allFinite()) return false;
  const RowMatrixX3d p_new = posed_positions(frame, x_new);
  Eigen::VectorXd w_new(problem.num_dofs());
  for (int i = 0; i < problem.num_nodes(); ++i) w_new.segment<3>(3 * i) = (p_new.row(i) - p_n.row(i)).transpose() / dt;
  if (!w_new.allFinite()) return false;
  s.t = t1;
  s.x = std::move(x_new);
  s.w = std::move(w_new);
  return true;
}

BackwardEuler::BackwardEuler(const Problem& problem, MPI_Comm comm, const BackwardEulerOptions& options)
    : impl_(std::make_unique<Impl>(problem, comm, options)) {
  require(static_cast<int>(problem.tet_rest.size()) == problem.num_tets(), "BackwardEuler: the problem is not validated");
  try {
    impl_->setup();
  } catch (...) {
    impl_->destroy();
    throw;
  }
}

BackwardEuler::~BackwardEuler() { impl_->destroy(); }

void BackwardEuler::initialize(const State& s) {
  require(s.x.size() == impl_->problem.num_dofs() && s.w.size() == impl_->problem.num_dofs(),
          "BackwardEuler: initial state has {} / {} entries, expected {}", s.x.size(), s.w.size(),
          impl_->problem.num_dofs());
  require(s.x.allFinite() && s.w.allFinite(), "BackwardEuler: initial state is not finite");
  impl_->state = s;
}

const State& BackwardEuler::state() const { return impl_->state; }

std::vector<int> BackwardEuler::owned_nodes() const {
  std::vector<int> nodes;
  for (int k = impl_->begin; k < impl_->end; ++k) nodes.push_back(impl_->node_of(k));
  std::sort(nodes.begin(), nodes.end());
  return nodes;
}

StepStats BackwardEuler::step(double h) {
  require(std::isfinite(h) && h > 0.0, "BackwardEuler: step must be positive, got {}", h);
  const auto t0 = Clock::now();
  StepStats stats;
  impl_->stats = &stats;
  const State saved = impl_->state;
  // Exact Hessian first when the mass term keeps the system positive definite in practice; a failed
  // attempt repeats the same step with the problem's projection before any halving.
  const bool exact_first = impl_->options.exact_hessian_first && !impl_->options.quasi_static &&
                           impl_->problem.dynamic() && impl_->problem.projection != material::HessianProjection::kNone;
  int level = exact_first ? -1 : 0;
  for (; level <= impl_->options.max_halvings; ++level) {
    impl_->projection_now = level < 0 ? material::HessianProjection::kNone : impl_->problem.projection;
    const int substeps = 1 << std::max(level, 0);
    const double dt = h / substeps;
    State s = saved;
    bool ok = true;
    for (int k = 0; k < substeps && ok; ++k) {
      // Substep ends land exactly on saved.t + h at the last one.
      const double t_start = k == 0 ? saved.t : s.t;
      const double t_end = k + 1 == substeps ? saved.t + h : saved.t + (k + 1) * dt;
      ok = impl_->solve_substep(s, t_start, t_end - t_start);
    }
    if (ok) {
      impl_->restore_pc();
      impl_->state = std::move(s);
      stats.substeps = substeps;
      stats.seconds = seconds_since(t0);
      impl_->stats = nullptr;
      if (stats.failed_attempts > 0) {
        logger()->info("t = {:.6g}: step recovered with {} substeps after {} failed attempt(s)", impl_->state.t, substeps,
                       stats.failed_attempts);
      }
      return stats;
    }
    if (level < 0) {
      ++stats.projected_retries;
    } else {
      ++stats.failed_attempts;
      if (impl_->linear_failure && impl_->saved_pc_type.empty()) {
        // The same attempt again with the fallback preconditioner before halving the step.
        impl_->use_fallback_pc();
        --level;
      }
    }
  }
  impl_->restore_pc();
  impl_->stats = nullptr;
  throw_error("backward Euler failed at t = {:.6g} s: no convergence even with {} substeps of {:.3g} s (last reason: {})",
              saved.t + h, 1 << impl_->options.max_halvings, h / (1 << impl_->options.max_halvings),
              stats.converged_reason);
}

}  // namespace sflsh::fullspace
