// The consistent mass of the SUNDIALS reference (reference_mass.hpp).
#include "reference_mass.hpp"

#include <sflsh/core/error.hpp>

#include <algorithm>
#include <cmath>

namespace sflsh::fullspace::detail {

ComponentMass component_mass(const Problem& problem, const std::vector<char>& constrained) {
  const int n = problem.num_nodes();
  const Eigen::Index dofs = problem.num_dofs();
  require(static_cast<Eigen::Index>(constrained.size()) == dofs, "consistent mass: {} mask entries for {} components",
          constrained.size(), dofs);
  const Eigen::SparseMatrix<double, Eigen::RowMajor> M = problem.mass_matrix();
  require(M.rows() == n && M.cols() == n, "consistent mass: the mass matrix is {}×{}, expected {}×{}", M.rows(),
          M.cols(), n, n);
  std::vector<Eigen::Triplet<double>> free_entries, coupling_entries;
  free_entries.reserve(static_cast<std::size_t>(3 * M.nonZeros()));
  for (int i = 0; i < n; ++i) {
    for (int alpha = 0; alpha < 3; ++alpha) {
      const Eigen::Index row = 3 * i + alpha;
      if (constrained[static_cast<std::size_t>(row)] != 0) {
        free_entries.emplace_back(row, row, 1.0);  // ẇ = 0 on prescribed components (their w is not used)
        continue;
      }
      double diagonal = 0.0;
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(M, i); it; ++it) {
        require(std::isfinite(it.value()), "consistent mass: M({}, {}) = {} is not finite", i, it.col(), it.value());
        const Eigen::Index col = 3 * it.col() + alpha;  // M ⊗ I₃: the same axis only
        if (it.col() == i) diagonal = it.value();
        if (constrained[static_cast<std::size_t>(col)] != 0) {
          coupling_entries.emplace_back(row, col, it.value());
        } else {
          free_entries.emplace_back(row, col, it.value());
        }
      }
      require(diagonal > 0.0,
              "consistent mass: node {} is not fully prescribed but its mass matrix diagonal is {} "
              "(every moving node needs mass > 0)",
              i, diagonal);
    }
  }
  ComponentMass out;
  out.free.resize(dofs, dofs);
  out.free.setFromTriplets(free_entries.begin(), free_entries.end());
  out.free.makeCompressed();
  out.coupling.resize(dofs, dofs);
  out.coupling.setFromTriplets(coupling_entries.begin(), coupling_entries.end());
  out.coupling.makeCompressed();
  return out;
}

Eigen::VectorXd prescribed_acceleration(const Problem& problem, double t, double t_start) {
  const double ahead = 1e-4 * std::max(1.0, std::abs(t));  // [s]
  const double behind = std::clamp(t - t_start, 0.0, ahead);
  // ṗ of the prescribed motion: initial_state's posed velocity (x = X + u(t), ẋ = du/dt on prescribed components).
  const Eigen::VectorXd later = initial_state(problem, t + ahead).w;
  const Eigen::VectorXd earlier = initial_state(problem, t - behind).w;
  return (later - earlier) / (ahead + behind);
}

}  // namespace sflsh::fullspace::detail
