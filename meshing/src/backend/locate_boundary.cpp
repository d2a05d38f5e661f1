// Boundary nodes of a tet mesh → closest point on the input surface (CGAL AABB tree; much lighter to
// compile than Mesh_3).
#include <sflsh/core/error.hpp>
#include <sflsh/meshing/tet_backend.hpp>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <vector>

namespace sflsh::meshing {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

/// Nodes on a face used by exactly one tet.
std::vector<char> boundary_node_mask(const TetMesh& mesh) {
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::vector<std::array<int, 3>> faces;
  faces.reserve(static_cast<std::size_t>(4 * mesh.tets.rows()));
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e)
    for (const auto& f : kFace) {
      std::array<int, 3> key{mesh.tets(e, f[0]), mesh.tets(e, f[1]), mesh.tets(e, f[2])};
      std::sort(key.begin(), key.end());
      faces.push_back(key);
    }
  std::sort(faces.begin(), faces.end());
  std::vector<char> on_boundary(static_cast<std::size_t>(mesh.nodes.rows()), 0);
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j] == faces[i]) ++j;
    if (j - i == 1)
      for (int v : faces[i]) on_boundary[static_cast<std::size_t>(v)] = 1;
    i = j;
  }
  return on_boundary;
}

/// Barycentric coordinates of p (a point on or near triangle abc) w.r.t. a, b, c, clamped to the
/// triangle and normalized (the closest point lies in the triangle up to rounding).
Eigen::Vector3d barycentric(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c) {
  const Eigen::Vector3d e0 = b - a, e1 = c - a, d = p - a;
  const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1), d20 = d.dot(e0), d21 = d.dot(e1);
  const double denominator = d00 * d11 - d01 * d01;
  if (!(denominator > 0.0)) return Eigen::Vector3d(1.0, 0.0, 0.0);  // degenerate triangle: its first corner
  const double v = (d11 * d20 - d01 * d21) / denominator;
  const double w = (d00 * d21 - d01 * d20) / denominator;
  Eigen::Vector3d bary(1.0 - v - w, v, w);
  bary = bary.cwiseMax(0.0);
  return bary / bary.sum();
}

}  // namespace

BoundaryLocation locate_boundary_nodes(const TetMesh& mesh, const ClosedSurface& surface) {
  require(surface.triangles.rows() > 0, "locate boundary nodes: the surface has no triangles");
  const auto point = [&](int v) {
    return Point(surface.vertices(v, 0), surface.vertices(v, 1), surface.vertices(v, 2));
  };
  std::vector<Triangle> triangles;
  triangles.reserve(static_cast<std::size_t>(surface.triangles.rows()));
  for (Eigen::Index t = 0; t < surface.triangles.rows(); ++t)
    triangles.emplace_back(point(surface.triangles(t, 0)), point(surface.triangles(t, 1)),
                           point(surface.triangles(t, 2)));
  Tree tree(triangles.cbegin(), triangles.cend());
  tree.accelerate_distance_queries();

  const std::vector<char> on_boundary = boundary_node_mask(mesh);
  BoundaryLocation location;
  location.triangle.assign(static_cast<std::size_t>(mesh.nodes.rows()), -1);
  location.bary.assign(static_cast<std::size_t>(mesh.nodes.rows()), Eigen::Vector3d::Zero());
  for (Eigen::Index i = 0; i < mesh.nodes.rows(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (!on_boundary[k]) continue;
    const Eigen::Vector3d x = mesh.nodes.row(i).transpose();
    const auto [closest, primitive] = tree.closest_point_and_primitive(Point(x.x(), x.y(), x.z()));
    const int t = static_cast<int>(primitive - triangles.cbegin());
    const Eigen::Vector3d q(closest.x(), closest.y(), closest.z());
    location.triangle[k] = t;
    location.bary[k] = barycentric(q, surface.vertices.row(surface.triangles(t, 0)).transpose(),
                                   surface.vertices.row(surface.triangles(t, 1)).transpose(),
                                   surface.vertices.row(surface.triangles(t, 2)).transpose());
    location.max_distance = std::max(location.max_distance, (q - x).norm());
  }
  return location;
}

}  // namespace sflsh::meshing
