// The consistent mass of the SUNDIALS reference (reference_integrator.hpp): M_y = diag(I, M_w) for ARKODE's
// mass-matrix form M_y ẏ = f, its own KLU solver (time-independent: one factorization per initialize), the Newton
// matrix M_y − γJ on the fixed Jacobian pattern (ARKStepSetLinSysFn; SUNMatScaleAdd on two sparse matrices scans a
// dense work array per row, O(rows²) per setup), and the force M_FC a_C of the prescribed accelerations.
#include "reference_integrator_impl.hpp"

#include <algorithm>
#include <cmath>

namespace sflsh::fullspace {

void ReferenceIntegrator::Impl::check_consistent_mass() const {
  const int m = problem.num_tets();
  require(problem.tet_mass.size() == m,
          "reference integrator: consistent mass needs ρV per tet (Problem::tet_mass from a "
          "density, filled by Problem::validate()), have {} for {} tets",
          problem.tet_mass.size(), m);
  require(problem.tet_mass.allFinite() && problem.tet_mass.minCoeff() >= 0.0,
          "reference integrator: the tet masses ρV must be finite and non-negative");
  // The lumped masses (gravity m_i g) must be the row sums of the consistent matrix, as validate() checks.
  Eigen::VectorXd row_sum = Eigen::VectorXd::Zero(n);
  for (int e = 0; e < m; ++e)
    for (int a = 0; a < 4; ++a) row_sum[problem.tets(e, a)] += 0.25 * problem.tet_mass[e];
  require((row_sum - problem.mass).cwiseAbs().maxCoeff() <= 1e-9 * problem.mass.cwiseAbs().maxCoeff(),
          "reference integrator: the lumped masses are not the row sums of the consistent mass (tet_mass and mass "
          "from different densities?)");
}

void ReferenceIntegrator::Impl::build_mass() {
  component_mass = detail::component_mass(problem, constrained);
  const Eigen::SparseMatrix<double, Eigen::RowMajor>& Mw = component_mass.free;
  // M_y = diag(I, M_w) in CSR.
  mass_row_ptr.assign(static_cast<std::size_t>(2 * nx + 1), 0);
  mass_col_idx.clear();
  mass_values.clear();
  for (sunindextype r = 0; r < nx; ++r) {
    mass_col_idx.push_back(r);
    mass_values.push_back(1.0);
    mass_row_ptr[static_cast<std::size_t>(r + 1)] = static_cast<sunindextype>(mass_col_idx.size());
  }
  for (Eigen::Index r = 0; r < nx; ++r) {
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(Mw, r); it; ++it) {
      mass_col_idx.push_back(nx + static_cast<sunindextype>(it.col()));
      mass_values.push_back(it.value());
    }
    mass_row_ptr[static_cast<std::size_t>(nx + r + 1)] = static_cast<sunindextype>(mass_col_idx.size());
  }
  // M_y on J's pattern (which holds every entry of M_y: the x diagonals and the w_{j,α} of the neighbours).
  mass_on_pattern.assign(col_idx.size(), 0.0);
  std::size_t placed = 0;
  for (sunindextype r = 0; r < 2 * nx; ++r) {
    auto q = static_cast<std::size_t>(row_ptr[static_cast<std::size_t>(r)]);
    const auto q_end = static_cast<std::size_t>(row_ptr[static_cast<std::size_t>(r + 1)]);
    for (auto k = static_cast<std::size_t>(mass_row_ptr[static_cast<std::size_t>(r)]);
         k < static_cast<std::size_t>(mass_row_ptr[static_cast<std::size_t>(r + 1)]); ++k) {
      while (q < q_end && col_idx[q] < mass_col_idx[k]) ++q;  // both rows sorted
      if (q < q_end && col_idx[q] == mass_col_idx[k]) {
        mass_on_pattern[q] = mass_values[k];
        ++placed;
      }
    }
  }
  require(placed == mass_values.size(), "reference integrator: {} of {} mass entries lie outside the Jacobian pattern",
          mass_values.size() - placed, mass_values.size());
}

void ReferenceIntegrator::Impl::create_mass_solver() {
  const auto mass_nnz = static_cast<sunindextype>(mass_col_idx.size());
  mass = SUNSparseMatrix(2 * nx, 2 * nx, mass_nnz, CSR_MAT, ctx);
  require(mass != nullptr, "reference integrator: SUNSparseMatrix({0}×{0}, {1} nonzeros) failed", 2 * nx, mass_nnz);
  std::copy(mass_row_ptr.begin(), mass_row_ptr.end(), SM_INDEXPTRS_S(mass));
  std::copy(mass_col_idx.begin(), mass_col_idx.end(), SM_INDEXVALS_S(mass));
  std::copy(mass_values.begin(), mass_values.end(), SM_DATA_S(mass));
  mass_solver = SUNLinSol_KLU(y, mass, ctx);
  require(mass_solver != nullptr, "reference integrator: SUNLinSol_KLU (mass) failed");
  require(SUNLinSol_KLUSetOrdering(mass_solver, 0) == SUNLS_SUCCESS, "reference integrator: KLU ordering rejected");
}

int ReferenceIntegrator::Impl::update_coupling(double t_eval) {
  if (component_mass.coupling.nonZeros() == 0) {
    coupling_force.setZero(nx);
    return 0;
  }
  if (t_eval == acceleration_time) return 0;
  try {
    const Eigen::VectorXd acceleration = detail::prescribed_acceleration(problem, t_eval, t_start);
    if (!acceleration.allFinite()) {
      last_rhs_problem = fmt::format("the prescribed accelerations are not finite at t = {}", t_eval);
      return -1;
    }
    coupling_force = component_mass.coupling * acceleration;  // M_FC a_C
  } catch (const std::exception& error) {
    last_rhs_problem = error.what();
    return -1;
  }
  acceleration_time = t_eval;
  return 0;
}

int ReferenceIntegrator::Impl::mass_callback(sunrealtype /*t_eval*/, SUNMatrix M, void* user_data, N_Vector /*tmp1*/,
                                             N_Vector /*tmp2*/, N_Vector /*tmp3*/) {
  auto* impl = static_cast<Impl*>(user_data);
  if (SM_NNZ_S(M) < static_cast<sunindextype>(impl->mass_col_idx.size()) || SM_ROWS_S(M) != 2 * impl->nx) return -1;
  std::copy(impl->mass_row_ptr.begin(), impl->mass_row_ptr.end(), SM_INDEXPTRS_S(M));
  std::copy(impl->mass_col_idx.begin(), impl->mass_col_idx.end(), SM_INDEXVALS_S(M));
  std::copy(impl->mass_values.begin(), impl->mass_values.end(), SM_DATA_S(M));
  return 0;
}

int ReferenceIntegrator::Impl::linear_system_callback(sunrealtype t_eval, N_Vector yv, N_Vector /*fy*/, SUNMatrix A,
                                                      SUNMatrix /*M*/, sunbooleantype jok, sunbooleantype* jcur,
                                                      sunrealtype gamma, void* user_data, N_Vector /*tmp1*/,
                                                      N_Vector /*tmp2*/, N_Vector /*tmp3*/) {
  auto* impl = static_cast<Impl*>(user_data);
  if (SM_NNZ_S(A) < static_cast<sunindextype>(impl->col_idx.size()) || SM_ROWS_S(A) != 2 * impl->nx) {
    impl->last_rhs_problem = "the Newton matrix lost its storage";
    return -1;
  }
  if (jok == SUNFALSE || impl->saved_values.size() != impl->values.size()) {
    if (const int status = impl->jacobian(t_eval, NV_DATA_S(yv)); status != 0) return status;
    impl->saved_values = impl->values;
    *jcur = SUNTRUE;
  } else {
    *jcur = SUNFALSE;
  }
  std::copy(impl->row_ptr.begin(), impl->row_ptr.end(), SM_INDEXPTRS_S(A));
  std::copy(impl->col_idx.begin(), impl->col_idx.end(), SM_INDEXVALS_S(A));
  sunrealtype* data = SM_DATA_S(A);
  for (std::size_t q = 0; q < impl->saved_values.size(); ++q) {
    data[q] = impl->mass_on_pattern[q] - gamma * impl->saved_values[q];  // M_y − γJ
  }
  return 0;
}

Eigen::SparseMatrix<double, Eigen::RowMajor> ReferenceIntegrator::mass_matrix() const {
  const Impl& s = *impl_;
  Eigen::SparseMatrix<double, Eigen::RowMajor> M(2 * s.nx, 2 * s.nx);
  if (!s.consistent) {
    M.setIdentity();
    return M;
  }
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(s.mass_values.size());
  for (sunindextype r = 0; r < 2 * s.nx; ++r) {
    for (auto q = s.mass_row_ptr[static_cast<std::size_t>(r)]; q < s.mass_row_ptr[static_cast<std::size_t>(r + 1)];
         ++q) {
      const auto sq = static_cast<std::size_t>(q);
      triplets.emplace_back(static_cast<int>(r), static_cast<int>(s.mass_col_idx[sq]), s.mass_values[sq]);
    }
  }
  M.setFromTriplets(triplets.begin(), triplets.end());
  return M;
}

}  // namespace sflsh::fullspace
