// The full-space solver's Φ, residual and Hessian as sums of the model's terms (model/terms.hpp) over this
// rank's share (fullspace_solver_impl.hpp), the Dirichlet penalty on constrained components, and the PETSc
// Hessian sink: the first assembly goes through MatSetValuesBlocked, later ones add every 3×3 block directly
// into the AIJ value arrays at offsets computed once (build_refill).
#include "fullspace_solver_impl.hpp"

namespace sflsh::fullspace {

// ---------------------------------------------------------------------------------------------------------
// The Hessian sink

/// Adds the terms' blocks to J, rows of this rank only, with constrained rows and columns dropped (the
/// constrained rows get D e_d afterwards, add_dirichlet_rows).
class FullSpaceSolver::Impl::PetscSink final : public model::HessianSink {
 public:
  /// `diag` / `offdiag`: the value arrays of J's local blocks when the refill is ready (else null).
  PetscSink(Impl& solver, PetscScalar* diag, PetscScalar* offdiag) : solver_(solver), diag_(diag), offdiag_(offdiag) {}

  void add_tet(std::size_t k, int e, const material::Matrix12d& block) override {
    const unsigned mask = solver_.tet_constrained[k];
    if (!solver_.refill.ready) return set_tet(e, block, mask);
    const PetscInt* offsets = solver_.refill.tet_offset.data() + 48 * k;
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b, offsets += 3) {
        if (offsets[0] == -1) continue;  // row of another rank
        if (mask == 0) {
          add_rows(offsets, block.block<3, 3>(3 * a, 3 * b));
        } else {
          add_rows_masked(offsets, block.block<3, 3>(3 * a, 3 * b), mask >> (3 * a), mask >> (3 * b));
        }
      }
    }
  }

  void add_node(int node, const Eigen::Matrix3d& block) override {
    require(solver_.owns(node), "full-space Hessian: a node block for node {}, which this process does not own", node);
    const unsigned mask = node_mask(node);
    const int row = solver_.index_of(node);
    if (solver_.refill.ready) {
      add_rows_masked(solver_.refill.node_offset.data() + 3 * (row - solver_.begin), block, mask, mask);
      return;
    }
    Eigen::Matrix3d masked = block;
    for (int r = 0; r < 3; ++r) {
      if (!(mask >> r & 1u)) continue;
      masked.row(r).setZero();
      masked.col(r).setZero();
    }
    const PetscInt index = row;
    SFLSH_PETSC(MatSetValuesBlocked(solver_.J, 1, &index, 1, &index, masked.data(), ADD_VALUES));
  }

  /// D on the diagonal of the constrained components of every owned node. The first assembly also sets every
  /// owned node's diagonal block (zero where free), so the pattern always holds it.
  void add_dirichlet_rows() {
    for (int row = solver_.begin; row < solver_.end; ++row) {
      const unsigned mask = node_mask(solver_.node_of(row));
      if (mask == 0 && solver_.refill.ready) continue;
      Eigen::Matrix3d B = Eigen::Matrix3d::Zero();
      for (int r = 0; r < 3; ++r)
        if (mask >> r & 1u) B(r, r) = solver_.dirichlet_diagonal;
      if (solver_.refill.ready) {
        add_rows(solver_.refill.node_offset.data() + 3 * (row - solver_.begin), B);
        continue;
      }
      const PetscInt index = row;
      SFLSH_PETSC(MatSetValuesBlocked(solver_.J, 1, &index, 1, &index, B.data(), ADD_VALUES));
    }
  }

 private:
  unsigned node_mask(int node) const {
    const auto first = 3 * static_cast<std::size_t>(node);
    return (solver_.constrained[first] ? 1u : 0u) | (solver_.constrained[first + 1] ? 2u : 0u) |
           (solver_.constrained[first + 2] ? 4u : 0u);
  }
  /// Where the value of scalar row `offset` lives (Refill's encoding).
  PetscScalar* destination(PetscInt offset) const { return offset >= 0 ? diag_ + offset : offdiag_ + (-offset - 2); }

  /// The three rows of a 3×3 block at their offsets (adjacent columns).
  template <typename Block>
  void add_rows(const PetscInt* offsets, const Block& block) const {
    for (int r = 0; r < 3; ++r) {
      PetscScalar* dst = destination(offsets[r]);
      for (int c = 0; c < 3; ++c) dst[c] += block(r, c);
    }
  }
  /// The same without the rows in `row_mask` and the columns in `col_mask` (bit k = component k).
  template <typename Block>
  void add_rows_masked(const PetscInt* offsets, const Block& block, unsigned row_mask, unsigned col_mask) const {
    for (int r = 0; r < 3; ++r) {
      if (row_mask >> r & 1u) continue;
      PetscScalar* dst = destination(offsets[r]);
      for (int c = 0; c < 3; ++c)
        if (!(col_mask >> c & 1u)) dst[c] += block(r, c);
    }
  }
  /// First assembly: the whole 12×12 block through PETSc; rows of other ranks get index −1, which PETSc skips
  /// (their owner adds them from its own row tets).
  void set_tet(int e, const material::Matrix12d& block, unsigned mask) const {
    const Problem& problem = solver_.problem;
    material::Matrix12d masked = block;
    for (int j = 0; j < 12; ++j) {
      if (!(mask >> j & 1u)) continue;
      masked.row(j).setZero();
      masked.col(j).setZero();
    }
    PetscInt rows[4], cols[4];
    for (int a = 0; a < 4; ++a) {
      cols[a] = solver_.index_of(problem.tets(e, a));
      rows[a] = solver_.owns(problem.tets(e, a)) ? cols[a] : -1;
    }
    SFLSH_PETSC(MatSetValuesBlocked(solver_.J, 4, rows, 4, cols, masked.data(), ADD_VALUES));
  }

  Impl& solver_;
  PetscScalar* diag_;
  PetscScalar* offdiag_;
};

// ---------------------------------------------------------------------------------------------------------
// The terms

void FullSpaceSolver::Impl::create_terms() {
  subset = std::make_shared<model::TermSubset>();
  subset->value_tets = my_tets;
  subset->row_tets = row_tets;
  for (int k = begin; k < end; ++k) subset->nodes.push_back(node_of(k));  // solver order: rows nearly in order
  elastic_term = std::make_unique<model::ElasticTerm>(problem, subset);
  inertia_term = std::make_unique<model::InertiaTerm>(problem, subset);
  gravity_term = std::make_unique<model::GravityTerm>(problem, subset);
  potential_term = std::make_unique<model::PotentialTerm>(problem);
  tet_constrained.assign(row_tets.size(), 0);
  for (std::size_t k = 0; k < row_tets.size(); ++k) {
    for (int a = 0; a < 4; ++a) {
      for (int c = 0; c < 3; ++c) {
        if (constrained[3 * static_cast<std::size_t>(problem.tets(row_tets[k], a)) + static_cast<std::size_t>(c)])
          tet_constrained[k] = static_cast<std::uint16_t>(tet_constrained[k] | (1u << (3 * a + c)));
      }
    }
  }
}

// Φ sees constrained components at their prescribed values (so the free rows do not depend on them) plus the
// penalty ½ D (x_d − x̄_d)², which is zero at every Newton iterate; its gradient and Hessian are then exactly
// what residual() and jacobian() assemble.
double FullSpaceSolver::Impl::objective(const Eigen::VectorXd& x_in) {
  const auto t0 = Clock::now();
  const Eigen::VectorXd& x = with_prescribed(x_in);
  double local = 0.0;
  for (int k = begin; k < end; ++k) {
    for (int d = 3 * node_of(k); d < 3 * node_of(k) + 3; ++d) {
      // ½ D (x_d − x̄_d)²
      if (constrained[static_cast<std::size_t>(d)]) local += 0.5 * dirichlet_diagonal * std::pow(x_in[d] - x[d], 2);
    }
  }
  const auto t_elastic = Clock::now();
  double elastic = 0.0;
  arena->execute([&] { elastic = elastic_term->value(x); });  // +∞ where the Fung exponent overflows
  local += elastic;
  const auto t_inertia = Clock::now();
  if (stats) stats->elastic_seconds += seconds_between(t_elastic, t_inertia);
  if (inertia) local += inertia_term->value(x);
  local += gravity_term->value(x);
  if (stats) stats->inertia_seconds += seconds_since(t_inertia);
  if (potential_term->active()) {
    const auto t_potential = Clock::now();
    local += potential_term->value(x);
    if (stats) stats->potential_seconds += seconds_since(t_potential);
  }
  if (!std::isfinite(local)) local = kInfinity;
  double global = 0.0;
  MPI_Allreduce(&local, &global, 1, MPI_DOUBLE, MPI_SUM, comm);
  if (stats) stats->function_seconds += seconds_since(t0);
  return global;
}

bool FullSpaceSolver::Impl::residual(const Eigen::VectorXd& x_in, Vec out) {
  const auto t0 = Clock::now();
  const Eigen::VectorXd& x = with_prescribed(x_in);
  const int n = problem.num_nodes();
  Eigen::VectorXd g = Eigen::VectorXd::Zero(3 * n);
  bool ok = true;
  arena->execute([&] { ok = elastic_term->add_gradient(x, g); });
  const auto t_inertia = Clock::now();
  if (stats) stats->elastic_seconds += seconds_between(t0, t_inertia);
  if (inertia) ok = inertia_term->add_gradient(x, g) && ok;
  ok = gravity_term->add_gradient(x, g) && ok;
  if (stats) stats->inertia_seconds += seconds_since(t_inertia);
  if (potential_term->active()) {
    const auto t_potential = Clock::now();
    ok = potential_term->add_gradient(x, g) && ok;
    if (stats) stats->potential_seconds += seconds_since(t_potential);
  }
  // Constrained rows: D (x_d − x̄_d), zero at every iterate (x starts on the prescribed values and the Jacobian row
  // D e_d keeps it there), so that the residual's derivative is the assembled row (PETSc's Jacobian test).
  for (int d = 0; d < 3 * n; ++d) {
    if (constrained[static_cast<std::size_t>(d)]) g[d] = dirichlet_diagonal * (x_in[d] - prescribed[d]);
  }
  int local_failed = ok && g.allFinite() ? 0 : 1;
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

bool FullSpaceSolver::Impl::jacobian(const Eigen::VectorXd& x) {
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
  PetscSink sink(*this, diag_values, offdiag_values);
  bool ok = true;
  elastic_term->set_projection(projection_now);
  arena->execute([&] { ok = elastic_term->add_hessian(x, sink); });
  const auto t_inertia = Clock::now();
  if (stats) stats->elastic_seconds += seconds_between(t0, t_inertia);
  // Lumped: M/ĥ² A_iᵀA_i on node i's diagonal block; consistent: tet blocks ρV/20 (1 + δ_ab) A_aᵀA_b/ĥ².
  if (inertia && problem.mass_kind == model::MassKind::consistent && refill.ready) {
    ok = add_cached_inertia_hessian(x, diag_values, offdiag_values) && ok;
  } else if (inertia) {
    ok = inertia_term->add_hessian(x, sink) && ok;
  }
  sink.add_dirichlet_rows();
  if (stats) stats->inertia_seconds += seconds_since(t_inertia);
  if (potential_term->active()) {  // one 3×3 block on the diagonal of each owned candidate (always in the pattern)
    const auto t_potential = Clock::now();
    ok = potential_term->add_hessian(x, sink) && ok;
    if (stats) stats->potential_seconds += seconds_since(t_potential);
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
  int local_failed = ok ? 0 : 1;
  int any_failed = 0;
  MPI_Allreduce(&local_failed, &any_failed, 1, MPI_INT, MPI_SUM, comm);
  if (stats) stats->jacobian_seconds += seconds_since(t0);
  return any_failed == 0;
}

bool FullSpaceSolver::Impl::add_cached_inertia_hessian(const Eigen::VectorXd& x, PetscScalar* diag_values,
                                                       PetscScalar* offdiag_values) {
  InertiaHessianCache& cache = inertia_cache;
  bool ok = true;
  if (cache.substep != substep_serial) {
    cache.diag.assign(static_cast<std::size_t>(refill.diag_nnz), 0.0);
    cache.offdiag.assign(static_cast<std::size_t>(refill.offdiag_nnz), 0.0);
    PetscSink cache_sink(*this, cache.diag.data(), cache.offdiag.empty() ? nullptr : cache.offdiag.data());
    ok = inertia_term->add_hessian(x, cache_sink);
    cache.substep = ok ? substep_serial : -1;
  }
  for (std::size_t k = 0; k < cache.diag.size(); ++k) diag_values[k] += cache.diag[k];
  for (std::size_t k = 0; k < cache.offdiag.size(); ++k) offdiag_values[k] += cache.offdiag[k];
  return ok;
}

// J is marked symmetric, but the symmetry flag of the whole matrix does not reach its local diagonal block,
// which is what block Jacobi hands to each block's preconditioner: marked too, its blocks default to ICC
// (PETSc's choice for a matrix known to be symmetric) instead of ILU, at half the factorization cost.
// An explicit -sub_pc_type still wins.
void FullSpaceSolver::Impl::mark_diagonal_block_symmetric() {
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
void FullSpaceSolver::Impl::build_refill() {
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
        for (int r = 0; r < 3; ++r)
          out[r] = find(3 * (I - begin) + r, 3 * static_cast<PetscInt>(index_of(problem.tets(e, b))));
      }
    }
  }
  refill.node_offset.resize(3 * static_cast<std::size_t>(end - begin));
  for (int i = begin; i < end; ++i) {
    for (int r = 0; r < 3; ++r)
      refill.node_offset[3 * static_cast<std::size_t>(i - begin) + static_cast<std::size_t>(r)] =
          find(3 * (i - begin) + r, 3 * static_cast<PetscInt>(i));
  }
  refill.diag = diag;
  refill.offdiag = offdiag;
  refill.diag_nnz = static_cast<std::ptrdiff_t>(d.ia.back());
  refill.offdiag_nnz = offdiag ? static_cast<std::ptrdiff_t>(o.ia.back()) : 0;
  refill.ready = true;
}

}  // namespace sflsh::fullspace
