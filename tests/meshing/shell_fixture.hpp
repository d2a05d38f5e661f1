#pragma once
// A layer-like closed surface built by the tests: an open spherical shell cap. The outer patch is a
// polar cap of a sphere of radius R (rings of near-equilateral triangles), the inner patch the same
// triangulation scaled to radius r and reversed, and a side strip joins the two rims, as
// meshing::build_layer_surface closes a layer at its boundary curves. Features are the two rims.
#include <sflsh/meshing/tet_backend.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <vector>

namespace sflsh::testing {

struct Shell {
  meshing::ClosedSurface surface;
  double volume = 0.0;  ///< analytic volume of the smooth shell [m³]
  double thickness = 0.0;
  int outer_vertices = 0;
};

/// Cap of polar angle `max_polar` [rad] between radii `inner_radius` < `outer_radius` [m], outer edges
/// about `surface_edge` [m]; `side_layers` rows of triangles across the side strip.
inline Shell spherical_shell(double outer_radius, double inner_radius, double surface_edge,
                             double max_polar = std::numbers::pi / 2, int side_layers = 0) {
  using meshing::NodeKind;
  const double step = surface_edge / outer_radius;
  const int rings = std::max(2, static_cast<int>(std::lround(max_polar / step)));
  std::vector<Eigen::Vector3d> unit{Eigen::Vector3d::UnitZ()};  // directions; the pole first
  std::vector<std::vector<int>> ring{{0}};
  for (int i = 1; i <= rings; ++i) {
    const double polar = max_polar * i / rings;
    const int count = std::max(6, static_cast<int>(std::lround(2.0 * std::numbers::pi * std::sin(polar) / step)));
    const double offset = (i % 2) * std::numbers::pi / count;
    auto& indices = ring.emplace_back();
    for (int k = 0; k < count; ++k) {
      const double azimuth = offset + 2.0 * std::numbers::pi * k / count;
      indices.push_back(static_cast<int>(unit.size()));
      unit.emplace_back(std::sin(polar) * std::cos(azimuth), std::sin(polar) * std::sin(azimuth), std::cos(polar));
    }
  }
  // Outer triangles: a fan at the pole, then a zipper between consecutive rings by azimuth.
  std::vector<Eigen::Vector3i> outer;
  for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
    const auto& a = ring[i];
    const auto& b = ring[i + 1];
    const auto m = a.size(), n = b.size();
    if (m == 1) {
      for (std::size_t j = 0; j < n; ++j) outer.emplace_back(a[0], b[j], b[(j + 1) % n]);
      continue;
    }
    const auto angle = [&](const std::vector<int>& r, std::size_t k) {
      const auto& u = unit[static_cast<std::size_t>(r[k % r.size()])];
      double phi = std::atan2(u.y(), u.x());
      if (phi < 0.0) phi += 2.0 * std::numbers::pi;
      return phi + (k >= r.size() ? 2.0 * std::numbers::pi : 0.0);
    };
    std::size_t p = 0, q = 0;
    while (p < m || q < n) {
      if (q == n || (p < m && angle(a, p + 1) < angle(b, q + 1))) {
        outer.emplace_back(a[p % m], a[(p + 1) % m], b[q % n]);
        ++p;
      } else {
        outer.emplace_back(a[p % m], b[(q + 1) % n], b[q % n]);
        ++q;
      }
    }
  }
  for (auto& t : outer) {  // outward: the normal points away from the centre
    const Eigen::Vector3d normal = (unit[t[1]] - unit[t[0]]).cross(unit[t[2]] - unit[t[0]]);
    if (normal.dot(unit[t[0]] + unit[t[1]] + unit[t[2]]) < 0.0) std::swap(t[1], t[2]);
  }

  const int count = static_cast<int>(unit.size());
  const double thickness = outer_radius - inner_radius;
  if (side_layers <= 0) side_layers = std::max(1, static_cast<int>(std::lround(thickness / surface_edge)));
  // The rim loop in the direction the outer patch uses its edges.
  std::map<int, int> next;
  {
    std::map<std::pair<int, int>, int> uses;
    for (const auto& t : outer)
      for (int k = 0; k < 3; ++k) ++uses[{t[k], t[(k + 1) % 3]}];
    for (const auto& [edge, n] : uses)
      if (!uses.count({edge.second, edge.first})) next[edge.first] = edge.second;
  }
  std::vector<int> rim{next.begin()->first};
  while (static_cast<int>(rim.size()) < static_cast<int>(next.size())) rim.push_back(next.at(rim.back()));

  Shell shell;
  shell.thickness = thickness;
  shell.outer_vertices = count;
  std::vector<Eigen::Vector3d> vertices;
  for (const auto& u : unit) vertices.push_back(outer_radius * u);
  for (const auto& u : unit) vertices.push_back(inner_radius * u);
  std::map<std::pair<int, int>, int> side_vertex;  // (rim vertex, layer) → index, 0 < layer < L
  for (int v : rim)
    for (int l = 1; l < side_layers; ++l) {
      side_vertex[{v, l}] = static_cast<int>(vertices.size());
      vertices.push_back((outer_radius - thickness * l / side_layers) * unit[static_cast<std::size_t>(v)]);
    }
  const auto at = [&](int v, int l) { return l == 0 ? v : l == side_layers ? count + v : side_vertex.at({v, l}); };

  std::vector<Eigen::Vector3i> triangles;
  auto& patch = shell.surface.patch;
  for (const auto& t : outer) {
    triangles.push_back(t);
    patch.push_back(NodeKind::outer);
  }
  for (const auto& t : outer) {
    triangles.emplace_back(count + t[0], count + t[2], count + t[1]);
    patch.push_back(NodeKind::inner);
  }
  for (std::size_t k = 0; k < rim.size(); ++k) {
    const int a = rim[k], b = rim[(k + 1) % rim.size()];
    for (int l = 0; l < side_layers; ++l) {
      triangles.emplace_back(at(b, l), at(a, l), at(a, l + 1));
      triangles.emplace_back(at(b, l), at(a, l + 1), at(b, l + 1));
      patch.insert(patch.end(), 2, NodeKind::side);
    }
  }
  auto& surface = shell.surface;
  surface.vertices.resize(static_cast<Eigen::Index>(vertices.size()), 3);
  for (std::size_t i = 0; i < vertices.size(); ++i)
    surface.vertices.row(static_cast<Eigen::Index>(i)) = vertices[i].transpose();
  surface.triangles.resize(static_cast<Eigen::Index>(triangles.size()), 3);
  for (std::size_t i = 0; i < triangles.size(); ++i)
    surface.triangles.row(static_cast<Eigen::Index>(i)) = triangles[i].transpose();
  for (double radius : {outer_radius, inner_radius}) {
    auto& feature = surface.features.emplace_back();
    for (int v : rim) feature.push_back(radius * unit[static_cast<std::size_t>(v)]);
    feature.push_back(feature.front());
  }
  const double r3 = outer_radius * outer_radius * outer_radius - inner_radius * inner_radius * inner_radius;
  shell.volume = 2.0 * std::numbers::pi / 3.0 * r3 * (1.0 - std::cos(max_polar));
  return shell;
}

}  // namespace sflsh::testing
