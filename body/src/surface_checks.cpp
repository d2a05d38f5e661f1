// Topological and geometric checks of a triangle surface given as arrays (a soup: no manifoldness is
// assumed, so broken meshes are reported rather than rejected).
#include <sflsh/body/surface_checks.hpp>
#include <sflsh/core/error.hpp>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>
#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <numeric>
#include <unordered_map>
#include <vector>

namespace sflsh::body {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Segment = Kernel::Segment_3;
using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::size_t>;

/// Incidence of one undirected edge: faces that use it as (lo → hi) and as (hi → lo).
struct EdgeUse {
  int forward = 0;
  int backward = 0;
  int total() const { return forward + backward; }
};

std::uint64_t edge_key(int a, int b) {
  const auto lo = static_cast<std::uint64_t>(std::min(a, b)), hi = static_cast<std::uint64_t>(std::max(a, b));
  return (lo << 32) | hi;
}

int find_root(std::vector<int>& parent, int x) {
  while (parent[static_cast<std::size_t>(x)] != x) {
    parent[static_cast<std::size_t>(x)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(x)])];
    x = parent[static_cast<std::size_t>(x)];
  }
  return x;
}

/// True when the link of every vertex (the edges opposite to it in its faces) is one cycle, or one
/// path for a vertex on a boundary.
bool links_are_disks(Eigen::Index num_vertices, const RowMatrixX3i& faces) {
  std::vector<std::vector<std::pair<int, int>>> links(static_cast<std::size_t>(num_vertices));
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      links[static_cast<std::size_t>(faces(f, k))].emplace_back(faces(f, (k + 1) % 3), faces(f, (k + 2) % 3));
  for (const auto& link : links) {
    if (link.empty()) continue;
    std::unordered_map<int, int> degree;
    std::unordered_map<int, int> parent;
    for (const auto& [a, b] : link) {
      ++degree[a];
      ++degree[b];
      parent.emplace(a, a);
      parent.emplace(b, b);
    }
    const auto root = [&parent](int x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    int ends = 0;
    for (const auto& [vertex, d] : degree) {
      if (d > 2) return false;
      if (d == 1) ++ends;
    }
    if (ends != 0 && ends != 2) return false;
    for (const auto& [a, b] : link) parent[root(a)] = root(b);
    const int first = root(link.front().first);
    for (const auto& [vertex, d] : degree)
      if (root(vertex) != first) return false;
  }
  return true;
}

/// Number of face pairs that intersect (beyond their shared vertices or edge), with exact predicates.
int count_self_intersections(const RowMatrixX3d& vertices, const RowMatrixX3i& faces,
                             const std::vector<bool>& degenerate) {
  std::vector<Point> points;
  points.reserve(static_cast<std::size_t>(vertices.rows()));
  for (Eigen::Index v = 0; v < vertices.rows(); ++v)
    points.emplace_back(vertices(v, 0), vertices(v, 1), vertices(v, 2));
  std::vector<Box> boxes;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    if (degenerate[static_cast<std::size_t>(f)]) continue;
    const Point& a = points[static_cast<std::size_t>(faces(f, 0))];
    const Point& b = points[static_cast<std::size_t>(faces(f, 1))];
    const Point& c = points[static_cast<std::size_t>(faces(f, 2))];
    boxes.emplace_back(a.bbox() + b.bbox() + c.bbox(), static_cast<std::size_t>(f));
  }
  int count = 0;
  const auto test = [&](const Box& box_a, const Box& box_b) {
    const auto fa = static_cast<Eigen::Index>(box_a.info()), fb = static_cast<Eigen::Index>(box_b.info());
    const std::array<int, 3> ta = {faces(fa, 0), faces(fa, 1), faces(fa, 2)};
    const std::array<int, 3> tb = {faces(fb, 0), faces(fb, 1), faces(fb, 2)};
    const auto p = [&points](int v) -> const Point& { return points[static_cast<std::size_t>(v)]; };
    // Shared vertex positions in ta/tb.
    std::vector<std::pair<int, int>> shared;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (ta[static_cast<std::size_t>(i)] == tb[static_cast<std::size_t>(j)]) shared.emplace_back(i, j);
    bool hit = false;
    if (shared.empty()) {
      hit = CGAL::do_intersect(Triangle(p(ta[0]), p(ta[1]), p(ta[2])), Triangle(p(tb[0]), p(tb[1]), p(tb[2])));
    } else if (shared.size() == 1) {
      // Common vertex v: they intersect iff the edge opposite v in one triangle meets the other triangle.
      const auto [i, j] = shared.front();
      const int a1 = ta[static_cast<std::size_t>((i + 1) % 3)], a2 = ta[static_cast<std::size_t>((i + 2) % 3)];
      const int b1 = tb[static_cast<std::size_t>((j + 1) % 3)], b2 = tb[static_cast<std::size_t>((j + 2) % 3)];
      hit = CGAL::do_intersect(Segment(p(a1), p(a2)), Triangle(p(tb[0]), p(tb[1]), p(tb[2]))) ||
            CGAL::do_intersect(Segment(p(b1), p(b2)), Triangle(p(ta[0]), p(ta[1]), p(ta[2])));
    } else if (shared.size() == 2) {
      // Common edge (e0, e1): they overlap iff coplanar with the opposite vertices on the same side.
      const int e0 = ta[static_cast<std::size_t>(shared[0].first)], e1 = ta[static_cast<std::size_t>(shared[1].first)];
      const int ra = ta[static_cast<std::size_t>(3 - shared[0].first - shared[1].first)];
      const int rb = tb[static_cast<std::size_t>(3 - shared[0].second - shared[1].second)];
      hit = CGAL::coplanar(p(e0), p(e1), p(ra), p(rb)) &&
            CGAL::coplanar_orientation(p(e0), p(e1), p(ra), p(rb)) == CGAL::POSITIVE;
    } else {
      hit = true;  // the same triangle twice
    }
    if (hit) ++count;
  };
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), test);
  return count;
}

}  // namespace

std::string SurfaceReport::summary() const {
  std::string out = fmt::format(
      "{}, {}, {}, {} component{}, χ = {}, {} degenerate face{}, ", closed ? "closed" : "NOT closed",
      edge_manifold && vertex_manifold ? "manifold" : (edge_manifold ? "NOT vertex-manifold" : "NOT edge-manifold"),
      !consistently_oriented ? "NOT consistently oriented" : (outward ? "oriented outward" : "oriented INWARD"),
      connected_components, connected_components == 1 ? "" : "s", euler_characteristic, degenerate_faces,
      degenerate_faces == 1 ? "" : "s");
  out += self_intersections < 0
             ? "self-intersections not checked"
             : fmt::format("{} self-intersecting face pair{}", self_intersections, self_intersections == 1 ? "" : "s");
  out += fmt::format(", volume {:.5f} m³, area {:.4f} m², min angle {:.1f}°", volume, area, min_angle_deg);
  return out;
}

SurfaceReport check_surface(const RowMatrixX3d& vertices, const RowMatrixX3i& faces, bool check_intersections) {
  const Eigen::Index n = vertices.rows();
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      require(faces(f, k) >= 0 && faces(f, k) < n, "check_surface: face {} references vertex {} of {}", f, faces(f, k),
              n);
  SurfaceReport r;

  // Edges: closedness, manifoldness and orientation.
  std::unordered_map<std::uint64_t, EdgeUse> edges;
  edges.reserve(static_cast<std::size_t>(3 * faces.rows()));
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = faces(f, k), b = faces(f, (k + 1) % 3);
      if (a == b) continue;
      EdgeUse& use = edges[edge_key(a, b)];
      (a < b ? use.forward : use.backward) += 1;
    }
  r.closed = !edges.empty();
  r.edge_manifold = true;
  r.consistently_oriented = true;
  for (const auto& [key, use] : edges) {
    if (use.total() != 2) r.closed = false;
    if (use.total() > 2) r.edge_manifold = false;
    if (use.forward > 1 || use.backward > 1) r.consistently_oriented = false;
  }
  r.vertex_manifold = r.edge_manifold && links_are_disks(n, faces);

  // Components and Euler characteristic over the vertices that faces use.
  std::vector<int> parent(static_cast<std::size_t>(n));
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<bool> used(static_cast<std::size_t>(n), false);
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      used[static_cast<std::size_t>(faces(f, k))] = true;
      parent[static_cast<std::size_t>(find_root(parent, faces(f, k)))] = find_root(parent, faces(f, (k + 1) % 3));
    }
  int used_count = 0;
  for (Eigen::Index v = 0; v < n; ++v) {
    if (!used[static_cast<std::size_t>(v)]) continue;
    ++used_count;
    if (find_root(parent, static_cast<int>(v)) == v) ++r.connected_components;
  }
  r.euler_characteristic = used_count - static_cast<int>(edges.size()) + static_cast<int>(faces.rows());

  // Geometry: volume (divergence theorem), area, angles, degenerate faces.
  std::vector<bool> degenerate(static_cast<std::size_t>(faces.rows()), false);
  r.min_angle_deg = 180.0;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Eigen::Vector3d a = vertices.row(faces(f, 0)).transpose();
    const Eigen::Vector3d b = vertices.row(faces(f, 1)).transpose();
    const Eigen::Vector3d c = vertices.row(faces(f, 2)).transpose();
    r.volume += a.dot(b.cross(c)) / 6.0;
    const double twice_area = (b - a).cross(c - a).norm();
    r.area += 0.5 * twice_area;
    const double longest = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
    if (twice_area <= 1e-10 * longest || longest == 0.0) {
      degenerate[static_cast<std::size_t>(f)] = true;
      ++r.degenerate_faces;
      continue;
    }
    const std::array<Eigen::Vector3d, 3> p = {a, b, c};
    for (std::size_t k = 0; k < 3; ++k) {
      const Eigen::Vector3d u = p[(k + 1) % 3] - p[k], w = p[(k + 2) % 3] - p[k];
      const double angle = std::atan2(u.cross(w).norm(), u.dot(w)) * 180.0 / std::numbers::pi;
      r.min_angle_deg = std::min(r.min_angle_deg, angle);
    }
  }
  if (faces.rows() == 0) r.min_angle_deg = 0.0;
  r.outward = r.consistently_oriented && r.volume > 0.0;
  if (check_intersections) r.self_intersections = count_self_intersections(vertices, faces, degenerate);
  return r;
}

}  // namespace sflsh::body
