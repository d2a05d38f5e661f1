// Point location in a tet mesh with a uniform grid over tet bounding boxes.
#include "skin_embedding.hpp"

#include <sflsh/core/error.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace sflsh::meshing::detail {
namespace {

Eigen::Vector4d barycentric(const RowMatrixX3d& nodes, const Eigen::Vector4i& tet, const Eigen::Vector3d& p) {
  Eigen::Matrix3d dm;
  for (int k = 0; k < 3; ++k) dm.col(k) = (nodes.row(tet(k + 1)) - nodes.row(tet(0))).transpose();
  const Eigen::Vector3d local = dm.partialPivLu().solve(p - nodes.row(tet(0)).transpose());
  return {1.0 - local.sum(), local(0), local(1), local(2)};
}

}  // namespace

PointLocation locate_points(const RowMatrixX3d& nodes, const RowMatrixX4i& tets, const RowMatrixX3d& queries) {
  require(tets.rows() > 0, "point location: empty tet mesh");
  const Eigen::Vector3d lo = nodes.colwise().minCoeff().transpose(), hi = nodes.colwise().maxCoeff().transpose();
  // Cell size: about two mean tet extents, so each tet touches a handful of cells.
  double extent = 0.0;
  for (Eigen::Index e = 0; e < tets.rows(); ++e) extent += (nodes.row(tets(e, 0)) - nodes.row(tets(e, 1))).norm();
  const double cell = std::max(2.0 * extent / static_cast<double>(tets.rows()), 1e-6);
  const auto key = [&](const Eigen::Vector3i& c) {
    return (static_cast<long long>(c(0)) * 73856093LL) ^ (static_cast<long long>(c(1)) * 19349663LL) ^
           (static_cast<long long>(c(2)) * 83492791LL);
  };
  const auto cell_of = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector3i(static_cast<int>(std::floor((p(0) - lo(0)) / cell)),
                           static_cast<int>(std::floor((p(1) - lo(1)) / cell)),
                           static_cast<int>(std::floor((p(2) - lo(2)) / cell)));
  };
  std::unordered_map<long long, std::vector<int>> grid;
  for (Eigen::Index e = 0; e < tets.rows(); ++e) {
    Eigen::Vector3d a = nodes.row(tets(e, 0)).transpose(), b = a;
    for (int k = 1; k < 4; ++k) {
      a = a.cwiseMin(nodes.row(tets(e, k)).transpose());
      b = b.cwiseMax(nodes.row(tets(e, k)).transpose());
    }
    const Eigen::Vector3i ca = cell_of(a), cb = cell_of(b);
    for (int x = ca(0); x <= cb(0); ++x)
      for (int y = ca(1); y <= cb(1); ++y)
        for (int z = ca(2); z <= cb(2); ++z) grid[key({x, y, z})].push_back(static_cast<int>(e));
  }
  (void)hi;

  PointLocation location;
  location.tet.resize(static_cast<std::size_t>(queries.rows()));
  location.bary.resize(static_cast<std::size_t>(queries.rows()));
  for (Eigen::Index q = 0; q < queries.rows(); ++q) {
    const Eigen::Vector3d p = queries.row(q).transpose();
    const Eigen::Vector3i c = cell_of(p);
    int best = -1;
    double best_min = -1e300;
    Eigen::Vector4d best_bary = Eigen::Vector4d::Zero();
    // Search growing shells of cells until a containing tet is found (or a few shells were searched).
    for (int radius = 0; radius <= 4 && best_min < -1e-12; ++radius) {
      for (int x = c(0) - radius; x <= c(0) + radius; ++x)
        for (int y = c(1) - radius; y <= c(1) + radius; ++y)
          for (int z = c(2) - radius; z <= c(2) + radius; ++z) {
            if (std::max({std::abs(x - c(0)), std::abs(y - c(1)), std::abs(z - c(2))}) != radius) continue;
            const auto it = grid.find(key({x, y, z}));
            if (it == grid.end()) continue;
            for (int e : it->second) {
              const Eigen::Vector4d bary = barycentric(nodes, tets.row(e).transpose(), p);
              if (bary.minCoeff() > best_min) {
                best_min = bary.minCoeff();
                best = e;
                best_bary = bary;
              }
            }
          }
      if (best >= 0 && radius >= 1) break;
    }
    require(best >= 0, "point location: point {} ({:.4f}, {:.4f}, {:.4f}) is far from every tet", q, p(0), p(1), p(2));
    location.tet[static_cast<std::size_t>(q)] = best;
    location.bary[static_cast<std::size_t>(q)] = best_bary;
    location.worst_outside = std::min(location.worst_outside, best_min);
  }
  return location;
}

}  // namespace sflsh::meshing::detail
