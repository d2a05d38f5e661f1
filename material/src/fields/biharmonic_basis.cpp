// Bounded biharmonic basis functions of the material control points (biharmonic_basis.hpp).
#include "bounded_qp.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/material/biharmonic_basis.hpp>

#include <Eigen/SparseCholesky>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cstring>
#include <numeric>

namespace sflsh::material {

namespace {

void check_controls(const std::vector<int>& controls, const RowMatrixX3i& F, Eigen::Index n) {
  require(!controls.empty(), "biharmonic basis: no control vertices");
  std::vector<char> taken(static_cast<std::size_t>(n), 0);
  for (std::size_t i = 0; i < controls.size(); ++i) {
    const int v = controls[i];
    require(v >= 0 && v < n, "biharmonic basis: control vertex {} (#{}) outside [0, {})", v, i, n);
    require(!taken[static_cast<std::size_t>(v)], "biharmonic basis: control vertex {} is repeated (#{})", v, i);
    taken[static_cast<std::size_t>(v)] = 1;
  }
  // Q's null space is the piecewise constants, so every connected component needs a fixed vertex.
  const std::vector<int> component = connected_components(vertex_adjacency(F, static_cast<int>(n)));
  const int count = component.empty() ? 0 : *std::max_element(component.begin(), component.end()) + 1;
  std::vector<char> covered(static_cast<std::size_t>(count), 0);
  for (const int v : controls) covered[static_cast<std::size_t>(component[static_cast<std::size_t>(v)])] = 1;
  for (int c = 0; c < count; ++c) {
    if (covered[static_cast<std::size_t>(c)]) continue;
    const auto first = std::find(component.begin(), component.end(), c) - component.begin();
    throw_error("biharmonic basis: surface component {} (containing vertex {}) has no control vertex", c, first);
  }
}

// The unconstrained biharmonic interpolants of all N functions at once (one factorization, N solves):
// Q_UU X_U = −Q_UK, with U the non-control vertices. Σ_i φ_i = 1 holds since Q·1 = 0.
Eigen::MatrixXd unconstrained_basis(const SparseMatrixd& Q, const std::vector<int>& controls) {
  const auto n = static_cast<int>(Q.rows());
  const auto N = static_cast<Eigen::Index>(controls.size());
  std::vector<int> column_of(static_cast<std::size_t>(n), -1), free, local(static_cast<std::size_t>(n), -1);
  for (std::size_t i = 0; i < controls.size(); ++i)
    column_of[static_cast<std::size_t>(controls[i])] = static_cast<int>(i);
  for (int v = 0; v < n; ++v) {
    if (column_of[static_cast<std::size_t>(v)] >= 0) continue;
    local[static_cast<std::size_t>(v)] = static_cast<int>(free.size());
    free.push_back(v);
  }
  Eigen::MatrixXd phi = Eigen::MatrixXd::Zero(n, N);
  for (Eigen::Index i = 0; i < N; ++i) phi(controls[static_cast<std::size_t>(i)], i) = 1.0;
  if (free.empty()) return phi;
  // Right-hand side −Q_UK: column k of Q restricted to the free rows.
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(free.size()), N);
  for (Eigen::Index i = 0; i < N; ++i)
    for (SparseMatrixd::InnerIterator it(Q, controls[static_cast<std::size_t>(i)]); it; ++it)
      if (const int r = local[static_cast<std::size_t>(it.row())]; r >= 0) rhs(r, i) = -it.value();
  Eigen::SimplicialLDLT<SparseMatrixd> ldlt(detail::principal_submatrix(Q, free, local));
  require(ldlt.info() == Eigen::Success, "biharmonic basis: factorization of the {}-vertex free block failed",
          free.size());
  const Eigen::MatrixXd solution = ldlt.solve(rhs);
  require(solution.allFinite(), "biharmonic basis: non-finite values in the unconstrained solve");
  for (std::size_t r = 0; r < free.size(); ++r) phi.row(free[r]) = solution.row(static_cast<Eigen::Index>(r));
  return phi;
}

}  // namespace

int BiharmonicBasis::total_iterations() const { return std::accumulate(iterations.begin(), iterations.end(), 0); }

SparseMatrixd biharmonic_energy_matrix(const RowMatrixX3d& V, const RowMatrixX3i& F, MassLumping lumping) {
  const SparseMatrixd L = cotangent_laplacian(V, F);
  const Eigen::VectorXd inverse_mass = lumped_mass(V, F, lumping).cwiseInverse();
  SparseMatrixd Q = L * inverse_mass.asDiagonal() * L;
  Q = 0.5 * (Q + SparseMatrixd(Q.transpose()));  // exactly symmetric (the product is, up to round-off)
  return Q;
}

BiharmonicBasis biharmonic_basis(const RowMatrixX3d& V, const RowMatrixX3i& F, const std::vector<int>& control_vertices,
                                 const BiharmonicOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  validate_surface(V, F);
  check_controls(control_vertices, F, V.rows());
  require(options.max_iterations >= 1, "biharmonic basis: max_iterations = {} (must be ≥ 1)", options.max_iterations);
  const auto N = static_cast<Eigen::Index>(control_vertices.size());

  BiharmonicBasis basis;
  basis.control_vertices = control_vertices;
  basis.bounded = options.bounded;
  basis.normalized = options.normalize;
  basis.lumping = options.lumping;
  basis.surface_fingerprint = surface_fingerprint(V, F);
  basis.iterations.assign(static_cast<std::size_t>(N), 0);
  basis.used_fallback.assign(static_cast<std::size_t>(N), 0);
  if (N == 1) {  // the only interpolant of a single unit value with Q·1 = 0 at zero energy
    basis.phi = Eigen::MatrixXd::Ones(V.rows(), 1);
    return basis;
  }
  const SparseMatrixd Q = biharmonic_energy_matrix(V, F, options.lumping);
  basis.phi = unconstrained_basis(Q, control_vertices);

  if (options.bounded) {
    detail::BoxQpSettings settings;
    settings.max_iterations = options.max_iterations;
    std::vector<double> multiplier_violation(static_cast<std::size_t>(N), 0.0);
    const auto solve_one = [&](Eigen::Index i) {
      const detail::BoxQpResult r = detail::solve_box_qp(Q, control_vertices, basis.phi.col(i), settings);
      basis.phi.col(i) = r.x;
      basis.iterations[static_cast<std::size_t>(i)] = r.iterations;
      basis.used_fallback[static_cast<std::size_t>(i)] = r.used_fallback ? 1 : 0;
      multiplier_violation[static_cast<std::size_t>(i)] = r.max_multiplier_violation;
    };
    if (options.parallel) {
      tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, N, 1), [&](const tbb::blocked_range<Eigen::Index>& range) {
        for (Eigen::Index i = range.begin(); i != range.end(); ++i) solve_one(i);
      });
    } else {
      for (Eigen::Index i = 0; i < N; ++i) solve_one(i);
    }
    const int fallbacks = std::accumulate(basis.used_fallback.begin(), basis.used_fallback.end(), 0);
    if (fallbacks > 0)
      logger()->info(
          "biharmonic basis: the primal-dual active set cycled for {} of {} functions (primal fallback used)",
          fallbacks, N);
    const double worst = *std::max_element(multiplier_violation.begin(), multiplier_violation.end());
    logger()->debug("biharmonic basis: largest KKT multiplier violation {:.2e} (relative to max diag Q)", worst);
  }
  if (options.bounded && options.normalize) {
    const Eigen::VectorXd sums = basis.phi.rowwise().sum();
    for (Eigen::Index v = 0; v < sums.size(); ++v)
      require(sums(v) > 1e-12,
              "biharmonic basis: every bounded weight is zero at vertex {} (sum {:.3g}); add control points there", v,
              sums(v));
    basis.phi = sums.cwiseInverse().asDiagonal() * basis.phi;
    for (Eigen::Index i = 0; i < N; ++i) {  // exact interpolation and bounds after the division's round-off
      basis.phi.row(control_vertices[static_cast<std::size_t>(i)]).setZero();
      basis.phi(control_vertices[static_cast<std::size_t>(i)], i) = 1.0;
    }
    basis.phi = basis.phi.cwiseMax(0.0).cwiseMin(1.0);
  }
  const double seconds = seconds_since(start);
  logger()->info("biharmonic basis: {} functions on {} vertices ({}), {} active-set solves, {:.2f} s", N, V.rows(),
                 options.bounded ? "bounded" : "unbounded", basis.total_iterations(), seconds);
  return basis;
}

std::uint64_t surface_fingerprint(const RowMatrixX3d& V, const RowMatrixX3i& F) {
  std::uint64_t hash = 14695981039346656037ull;  // FNV-1a offset basis
  const auto mix = [&hash](const void* data, std::size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < bytes; ++i) hash = (hash ^ p[i]) * 1099511628211ull;  // FNV prime
  };
  const std::int64_t sizes[2] = {V.rows(), F.rows()};
  mix(sizes, sizeof(sizes));
  mix(V.data(), static_cast<std::size_t>(V.size()) * sizeof(double));
  mix(F.data(), static_cast<std::size_t>(F.size()) * sizeof(int));
  return hash;
}

}  // namespace sflsh::material
