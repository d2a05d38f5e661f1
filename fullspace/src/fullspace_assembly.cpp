// Backward Euler on PETSc: the incremental potential, its gradient (residual) and Hessian assembled over
// this rank's tets, and the direct refill of the assembled AIJ arrays (backward_euler_impl.hpp).
#include "fullspace_solver_impl.hpp"

namespace sflsh::fullspace {

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
double FullSpaceSolver::Impl::objective(const Eigen::VectorXd& x_in) {
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
  const auto t_mass = Clock::now();
  for (int k = begin; k < end; ++k) {
    const int i = node_of(k);
    const double m = problem.mass[i];
    if (m == 0.0) continue;
    const auto si = static_cast<std::size_t>(i);
    const Eigen::Vector3d p = frame.A[si] * x.segment<3>(3 * i) + frame.d.row(i).transpose();
    if (inertia) local += m / (2.0 * h * h) * (p - p_tilde.row(i).transpose()).squaredNorm();
    local -= m * problem.gravity.dot(p);
  }
  if (stats) stats->inertia_seconds += seconds_since(t_mass);
  local += potential_energy(x);
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
  const auto t_mass = Clock::now();
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
  if (stats) stats->inertia_seconds += seconds_since(t_mass);
  add_potential_gradient(x, g);
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
  const auto t_mass = Clock::now();
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
  if (stats) stats->inertia_seconds += seconds_since(t_mass);
  // Node potentials: one 3×3 block on the diagonal of each owned candidate (always in the pattern).
  for (const auto& [node, block] : potential_hessian_blocks(x)) {
    if (!block.allFinite()) ++local_failed;
    const int row = index_of(node);
    if (refill.ready) {
      add_rows(refill.node_offset.data() + 3 * (row - begin), block);
      continue;
    }
    const PetscInt index = row;
    SFLSH_PETSC(MatSetValuesBlocked(J, 1, &index, 1, &index, block.data(), ADD_VALUES));
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

}  // namespace sflsh::fullspace
