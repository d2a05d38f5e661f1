#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/reduced/cubature.hpp>
#include <sflsh/reduced/cubature_coverage.hpp>
#include <sflsh/reduced/cubature_elastic.hpp>
#include <sflsh/reduced/nnls.hpp>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

namespace sflsh::reduced {

namespace {

meshing::RowMatrixX3d tet_centroids(const model::Problem& problem) {
  meshing::RowMatrixX3d c(problem.num_tets(), 3);
  for (int e = 0; e < problem.num_tets(); ++e) {
    Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
    for (int a = 0; a < 4; ++a) sum += problem.rest.row(problem.tets(e, a));
    c.row(e) = 0.25 * sum;
  }
  return c;
}

/// Farthest-point tets with Voronoi or NNLS weights (defined below select_cubature).
Cubature fitted_cubature(const model::Problem& problem, const Subspace& subspace, const CubatureOptions& options);

}  // namespace

Cubature exact_cubature(int num_tets) {
  Cubature c;
  c.tets.resize(static_cast<std::size_t>(num_tets));
  std::iota(c.tets.begin(), c.tets.end(), 0);
  c.weights.assign(static_cast<std::size_t>(num_tets), 1.0);
  c.method = "exact";
  return c;
}

std::vector<int> farthest_point_tets(const model::Problem& problem, int count, const std::vector<double>& density) {
  const int m = problem.num_tets();
  require(count >= 1 && count <= m, "cubature: {} points requested for a mesh of {} tets", count, m);
  require(density.empty() || static_cast<int>(density.size()) == m, "cubature: {} density values for {} tets",
          density.size(), m);
  const meshing::RowMatrixX3d c = tet_centroids(problem);
  Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
  double volume = 0.0;
  for (int e = 0; e < m; ++e) {
    mean += problem.tet_rest[static_cast<std::size_t>(e)].volume * c.row(e);
    volume += problem.tet_rest[static_cast<std::size_t>(e)].volume;
  }
  mean /= volume;
  Eigen::Index first = 0;
  (c.rowwise() - mean).rowwise().squaredNorm().minCoeff(&first);
  std::vector<int> chosen{static_cast<int>(first)};
  Eigen::VectorXd distance = Eigen::VectorXd::Constant(m, std::numeric_limits<double>::infinity());
  for (int k = 1; k < count; ++k) {
    const Eigen::RowVector3d last = c.row(chosen.back());
    for (int e = 0; e < m; ++e) {
      const double scale = density.empty() ? 1.0 : density[static_cast<std::size_t>(e)];
      distance[e] = std::min(distance[e], scale * (c.row(e) - last).norm());
    }
    Eigen::Index next = 0;
    distance.maxCoeff(&next);  // ties: the smallest index
    chosen.push_back(static_cast<int>(next));
  }
  return chosen;
}

std::vector<double> voronoi_weights(const model::Problem& problem, const std::vector<int>& tets) {
  const meshing::RowMatrixX3d c = tet_centroids(problem);
  meshing::RowMatrixX3d points(static_cast<Eigen::Index>(tets.size()), 3);
  for (std::size_t k = 0; k < tets.size(); ++k) points.row(static_cast<Eigen::Index>(k)) = c.row(tets[k]);
  std::vector<double> cell(tets.size(), 0.0);
  for (int e = 0; e < problem.num_tets(); ++e) {
    Eigen::Index nearest = 0;
    (points.rowwise() - c.row(e)).rowwise().squaredNorm().minCoeff(&nearest);
    cell[static_cast<std::size_t>(nearest)] += problem.tet_rest[static_cast<std::size_t>(e)].volume;
  }
  std::vector<double> w(tets.size());
  for (std::size_t k = 0; k < tets.size(); ++k)
    w[k] = cell[k] / problem.tet_rest[static_cast<std::size_t>(tets[k])].volume;
  return w;
}

Cubature select_cubature(const model::Problem& problem, const Subspace& subspace, const CubatureOptions& options) {
  Cubature out = fitted_cubature(problem, subspace, options);
  if (options.coverage > 0.0 && subspace.num_dofs() > 0) cover_every_function(problem, subspace, out, options.coverage);
  return out;
}

namespace {

Cubature fitted_cubature(const model::Problem& problem, const Subspace& subspace, const CubatureOptions& options) {
  Cubature out;
  out.tets = farthest_point_tets(problem, options.count, options.density);
  out.weights = voronoi_weights(problem, out.tets);
  out.method = "voronoi";
  if (options.weighting == CubatureWeighting::voronoi || subspace.num_dofs() == 0) return out;

  // Training-free targets: the exact reduced forces at random handle displacements, and the volume.
  const int K = out.size();
  const int dofs = subspace.num_dofs();
  const Cubature all = exact_cubature(problem.num_tets());
  const CubatureElastic exact(problem, subspace, all);
  Cubature unit = out;
  std::fill(unit.weights.begin(), unit.weights.end(), 1.0);
  const CubatureElastic candidates(problem, subspace, unit);

  std::mt19937 rng(options.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(K, K);
  Eigen::VectorXd h = Eigen::VectorXd::Zero(K);
  Eigen::MatrixXd A(dofs, K);
  int used = 0;
  for (double amplitude : options.amplitudes) {
    for (int sample = 0; sample < options.samples_per_amplitude; ++sample) {
      Eigen::VectorXd q(dofs);
      for (int d = 0; d < dofs; ++d) q[d] = amplitude * normal(rng);
      Eigen::VectorXd target = Eigen::VectorXd::Zero(dofs);
      try {
        exact.add_gradient(q, target);
        for (int k = 0; k < K; ++k) {
          Eigen::VectorXd column = Eigen::VectorXd::Zero(dofs);
          candidates.add_point_gradient(k, q, column, 1.0);
          A.col(k) = column;
        }
      } catch (const Error& e) {
        logger()->debug("cubature: sample at amplitude {} m skipped ({})", amplitude, e.what());
        continue;
      }
      const double norm = target.norm();
      if (!(norm > 0.0) || !A.allFinite()) continue;
      // Each sample counts equally: rows scaled by 1/‖target‖.
      G.noalias() += A.transpose() * A / (norm * norm);
      h.noalias() += A.transpose() * target / (norm * norm);
      ++used;
    }
  }
  if (used == 0) {
    logger()->warn("cubature: no force sample could be evaluated; Voronoi weights kept");
    return out;
  }
  // Volume: Σ ω_c V_c = V, as one more equation of the same weight as a sample.
  double volume = 0.0;
  Eigen::VectorXd v(K);
  for (int e = 0; e < problem.num_tets(); ++e) volume += problem.tet_rest[static_cast<std::size_t>(e)].volume;
  for (int k = 0; k < K; ++k)
    v[k] = problem.tet_rest[static_cast<std::size_t>(out.tets[static_cast<std::size_t>(k)])].volume / volume;
  G.noalias() += v * v.transpose();
  h += v;
  logger()->debug("cubature: NNLS system over {} samples: h in [{:.3e}, {:.3e}], diag(G) in [{:.3e}, {:.3e}]", used,
                  h.minCoeff(), h.maxCoeff(), G.diagonal().minCoeff(), G.diagonal().maxCoeff());
  const NnlsResult fit = nnls_normal_equations(G, h);
  const double fitted_volume = v.dot(fit.x);
  if (!fit.converged || !(std::abs(fitted_volume - 1.0) <= 0.05)) {
    logger()->warn("cubature: NNLS fit {} (volume ratio {:.3f}); Voronoi weights kept",
                   fit.converged ? "off in volume" : "did not converge", fitted_volume);
    return out;
  }
  out.weights.assign(fit.x.data(), fit.x.data() + K);
  out.method = "nnls";
  const long nonzero = std::count_if(out.weights.begin(), out.weights.end(), [](double w) { return w > 0.0; });
  logger()->debug("cubature: NNLS over {} samples: {} of {} points carry weight, volume ratio {:.4f}, {} iterations",
                  used, nonzero, K, fitted_volume, fit.iterations);
  return out;
}

}  // namespace

Eigen::MatrixXd rest_stiffness(const model::Problem& problem, const Subspace& subspace, const Cubature& cubature) {
  const CubatureElastic elastic(problem, subspace, cubature);
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(subspace.num_dofs(), subspace.num_dofs());
  elastic.add_hessian(Eigen::VectorXd::Zero(subspace.num_dofs()), K, material::HessianProjection::kNone);
  return K;
}

CubatureCoverage cubature_coverage(const Eigen::MatrixXd& exact_stiffness, const Eigen::MatrixXd& cubature_stiffness) {
  require(exact_stiffness.rows() == cubature_stiffness.rows() && exact_stiffness.cols() == cubature_stiffness.cols(),
          "cubature: stiffness matrices of {} and {} rows", exact_stiffness.rows(), cubature_stiffness.rows());
  CubatureCoverage c;
  if (exact_stiffness.rows() == 0) return c;
  const Eigen::LLT<Eigen::MatrixXd> factor(cubature_stiffness);
  if (factor.info() != Eigen::Success) {
    c.max_ratio = std::numeric_limits<double>::infinity();
    return c;
  }
  // L⁻¹ K_x L⁻ᵀ has the generalized eigenvalues of (K_x, K_c = L Lᵀ).
  Eigen::MatrixXd A = factor.matrixL().solve(exact_stiffness);
  A = factor.matrixL().solve(Eigen::MatrixXd(A.transpose()));
  const Eigen::VectorXd lambda =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(0.5 * (A + A.transpose()), Eigen::EigenvaluesOnly).eigenvalues();
  c.max_ratio = lambda.maxCoeff();
  c.min_ratio = lambda.minCoeff();
  return c;
}

Cubature select_covering_cubature(const model::Problem& problem, const Subspace& subspace,
                                  const CubatureOptions& options, double max_ratio, double growth) {
  require(max_ratio >= 1.0 && growth > 1.0, "cubature: coverage ratio {} must be ≥ 1 and growth {} > 1", max_ratio,
          growth);
  const Eigen::MatrixXd exact = rest_stiffness(problem, subspace, exact_cubature(problem.num_tets()));
  CubatureOptions o = options;
  for (;;) {
    Cubature c =
        o.count >= problem.num_tets() ? exact_cubature(problem.num_tets()) : select_cubature(problem, subspace, o);
    const CubatureCoverage coverage = cubature_coverage(exact, rest_stiffness(problem, subspace, c));
    c.stiffness_ratio_max = coverage.max_ratio;
    c.stiffness_ratio_min = coverage.min_ratio;
    logger()->info(
        "cubature: {} tets ({}): exact / cubature rest stiffness over the subspace's directions in [{:.3g}, {:.3g}]{}",
        c.size(), c.method, coverage.min_ratio, coverage.max_ratio,
        coverage.max_ratio <= max_ratio ? "" : fmt::format(" (above {:.3g}: more tets)", max_ratio));
    if (coverage.max_ratio <= max_ratio || c.method == "exact") return c;
    o.count = std::min(problem.num_tets(), static_cast<int>(std::ceil(growth * o.count)));
  }
}

}  // namespace sflsh::reduced
