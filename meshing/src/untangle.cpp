// Local untangling of a tet mesh by convex node relocation (docs/meshing.md §6).
#include <sflsh/meshing/quality.hpp>
#include <sflsh/meshing/untangle.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

namespace sflsh::meshing {
namespace {

// ∂V/∂x_c of a tet's signed volume with respect to its corner c; V is linear in each corner.
Eigen::Vector3d volume_gradient(const RowMatrixX3d& x, const RowMatrixX4i& tets, Eigen::Index e, int c) {
  const Eigen::Vector3d p0 = x.row(tets(e, 0)).transpose();
  const Eigen::Vector3d d1 = x.row(tets(e, 1)).transpose() - p0, d2 = x.row(tets(e, 2)).transpose() - p0,
                        d3 = x.row(tets(e, 3)).transpose() - p0;
  const Eigen::Vector3d g1 = d2.cross(d3) / 6.0, g2 = d3.cross(d1) / 6.0, g3 = d1.cross(d2) / 6.0;
  switch (c) {
    case 1:
      return g1;
    case 2:
      return g2;
    case 3:
      return g3;
    default:
      return -(g1 + g2 + g3);
  }
}

// Moves one free node to the minimum of the untangling functional Σ_e g(V_e), g(V) = √(V² + δ²) − V, over the
// tets around it (Escobar et al. 2003): g is convex and decreasing, V_e is linear in the node, so the 3-variable
// problem is convex and Newton with backtracking converges; for δ → 0 it is 2 Σ max(−V_e, 0), and the δ²/2V tail
// keeps valid tets away from zero volume. δ is a tenth of the star's mean |V| (a thousandth left slivers of 0.02°
// beside untangled tets). Returns true if the node moved.
bool relocate(RowMatrixX3d& x, const RowMatrixX4i& tets, int node, const std::vector<int>& star) {
  struct Corner {
    Eigen::Index tet;
    int corner;
  };
  std::vector<Corner> corners;
  double mean_volume = 0.0;
  for (int e : star) {
    int c = 0;
    while (tets(e, c) != node) ++c;
    corners.push_back({e, c});
    mean_volume += std::abs(signed_volume(x, tets, e)) / static_cast<double>(star.size());
  }
  if (!(mean_volume > 0.0)) return false;
  const double delta2 = 1e-2 * mean_volume * mean_volume;
  const auto functional = [&] {
    double value = 0.0;
    for (const auto& [e, c] : corners) {
      const double v = signed_volume(x, tets, e);
      value += std::sqrt(v * v + delta2) - v;
    }
    return value;
  };
  const Eigen::RowVector3d start = x.row(node);
  double value = functional();
  for (int iteration = 0; iteration < 30; ++iteration) {
    Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
    Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();
    for (const auto& [e, c] : corners) {
      const double v = signed_volume(x, tets, e);
      const double root = std::sqrt(v * v + delta2);
      const Eigen::Vector3d a = volume_gradient(x, tets, e, c);
      gradient += (v / root - 1.0) * a;
      hessian += (delta2 / (root * root * root)) * a * a.transpose();
    }
    hessian.diagonal().array() += 1e-12 * hessian.trace() + std::numeric_limits<double>::min();
    const Eigen::Vector3d step = -hessian.ldlt().solve(gradient);
    const double slope = gradient.dot(step);
    if (!step.allFinite() || !(slope < 0.0)) break;
    const Eigen::RowVector3d from = x.row(node);
    double t = 1.0, trial = value;
    for (int halving = 0; halving < 40; ++halving, t *= 0.5) {
      x.row(node) = from + t * step.transpose();
      trial = functional();
      if (trial <= value + 1e-4 * t * slope) break;
    }
    if (!(trial < value)) {
      x.row(node) = from;
      break;
    }
    const bool converged = value - trial <= 1e-12 * value;
    value = trial;
    if (converged) break;
  }
  return x.row(node) != start;
}

}  // namespace

int untangle(RowMatrixX3d& x, const RowMatrixX4i& tets, const std::vector<char>& fixed,
             const std::vector<std::vector<int>>& tets_of, int sweeps) {
  const auto is_free = [&](int node) { return fixed[static_cast<std::size_t>(node)] == 0; };
  int moved = 0;
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    std::vector<int> candidates;
    for (Eigen::Index e = 0; e < tets.rows(); ++e)
      if (signed_volume(x, tets, e) <= 0.0)
        for (int c = 0; c < 4; ++c)
          for (int around : tets_of[static_cast<std::size_t>(tets(e, c))])
            for (int k = 0; k < 4; ++k)
              if (is_free(tets(around, k))) candidates.push_back(tets(around, k));
    if (candidates.empty()) break;
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    for (int node : candidates)
      if (relocate(x, tets, node, tets_of[static_cast<std::size_t>(node)])) ++moved;
  }
  return moved;
}

int untangle(RowMatrixX3d& x, const RowMatrixX4i& tets, const std::vector<char>& fixed, int sweeps) {
  std::vector<std::vector<int>> tets_of(fixed.size());
  for (Eigen::Index e = 0; e < tets.rows(); ++e)
    for (int c = 0; c < 4; ++c) tets_of[static_cast<std::size_t>(tets(e, c))].push_back(static_cast<int>(e));
  return untangle(x, tets, fixed, tets_of, sweeps);
}

}  // namespace sflsh::meshing
