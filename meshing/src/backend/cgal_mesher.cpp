// CGAL Mesh_3 backend (CGAL 5.5.1). The only translation unit that instantiates Mesh_3: keep its
// includes here and its interface plain (backends.hpp).
//
// Domain: Polyhedral_mesh_domain_with_features_3 on one closed Surface_mesh; the feature polylines
// (layer rims) are protected with balls of radius ≤ edge_size so that the rims stay sharp.
// Criteria (Boost.Parameter style; the chained style of newer CGAL does not compile on 5.5.1):
// Mesh_3 bounds circumradii, not edges. A regular tet of edge a has circumradius a·√6/4 = 0.61a and a
// regular facet a circumradius a/√3 = 0.58a, so both size bounds are set to kSizeToEdge · edge_length.
#include "backends.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polyhedral_mesh_domain_with_features_3.h>
#include <CGAL/Random.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/make_mesh_3.h>
#include <CGAL/refine_mesh_3.h>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/global_control.h>
#endif

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <unordered_map>
#include <vector>

namespace sflsh::meshing::detail {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
using Domain = CGAL::Polyhedral_mesh_domain_with_features_3<Kernel, SurfaceMesh>;
#ifdef CGAL_LINKED_WITH_TBB
using Concurrency = CGAL::Parallel_tag;
constexpr bool kParallel = true;
#else
using Concurrency = CGAL::Sequential_tag;
constexpr bool kParallel = false;
#endif
using Triangulation = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, Concurrency>::type;
using Complex = CGAL::Mesh_complex_3_in_triangulation_3<Triangulation, Domain::Corner_index, Domain::Curve_index>;
using Criteria = CGAL::Mesh_criteria_3<Triangulation>;
namespace params = CGAL::parameters;

// Temporary tuning knobs (environment) while calibrating; removed once the constants are fixed.
double knob(const char* name, double fallback) {
  const char* value = std::getenv(name);
  return value ? std::atof(value) : fallback;
}

SurfaceMesh to_surface_mesh(const ClosedSurface& surface) {
  SurfaceMesh mesh;
  std::vector<SurfaceMesh::Vertex_index> vertex;
  vertex.reserve(static_cast<std::size_t>(surface.vertices.rows()));
  for (Eigen::Index v = 0; v < surface.vertices.rows(); ++v)
    vertex.push_back(mesh.add_vertex(Point(surface.vertices(v, 0), surface.vertices(v, 1), surface.vertices(v, 2))));
  for (Eigen::Index t = 0; t < surface.triangles.rows(); ++t) {
    const auto face = mesh.add_face(vertex[static_cast<std::size_t>(surface.triangles(t, 0))],
                                    vertex[static_cast<std::size_t>(surface.triangles(t, 1))],
                                    vertex[static_cast<std::size_t>(surface.triangles(t, 2))]);
    require(face != SurfaceMesh::null_face(), "cgal: input triangle {} makes the surface non-manifold", t);
  }
  require(CGAL::is_closed(mesh), "cgal: the input surface is not closed");
  return mesh;
}

/// Seeds the refinement with input vertices (dimension 2) at least `spacing` apart and away from the
/// protected features. Mesh_3 otherwise starts from the feature points plus a few ray-shot surface
/// points; with coplanar rims that start can be a flat triangulation from which it refines nothing
/// and returns an empty mesh (seen on a hemispherical shell whose two rims lie in one plane).
int add_surface_seeds(Complex& complex, const Domain& domain, const ClosedSurface& surface, double spacing) {
  std::vector<Eigen::Vector3d> normal(static_cast<std::size_t>(surface.vertices.rows()), Eigen::Vector3d::Zero());
  for (Eigen::Index t = 0; t < surface.triangles.rows(); ++t) {
    const Eigen::Vector3d a = surface.vertices.row(surface.triangles(t, 0)).transpose();
    const Eigen::Vector3d n = (surface.vertices.row(surface.triangles(t, 1)).transpose() - a)
                                  .cross(surface.vertices.row(surface.triangles(t, 2)).transpose() - a);
    for (int k = 0; k < 3; ++k) normal[static_cast<std::size_t>(surface.triangles(t, k))] += n;
  }
  // Greedy selection on a hash grid of cell `spacing`: a vertex is taken when no taken vertex (or
  // feature point) lies within `spacing`.
  std::unordered_map<std::uint64_t, std::vector<Eigen::Vector3d>> grid;
  const auto cell = [&](const Eigen::Vector3d& p, int dx, int dy, int dz) {
    const auto c = [&](double x, int d) {
      return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(x / spacing)) + d + (1 << 20)) & 0x1fffff;
    };
    return (c(p.x(), dx) << 42) | (c(p.y(), dy) << 21) | c(p.z(), dz);
  };
  const auto near_taken = [&](const Eigen::Vector3d& p) {
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find(cell(p, dx, dy, dz));
          if (it == grid.end()) continue;
          for (const auto& q : it->second)
            if ((p - q).norm() < spacing) return true;
        }
    return false;
  };
  for (const auto& feature : surface.features)
    for (const auto& p : feature) grid[cell(p, 0, 0, 0)].push_back(p);

  const auto weighted = complex.triangulation().geom_traits().construct_weighted_point_3_object();
  const auto intersect = domain.construct_intersection_object();
  const auto crosses = domain.do_intersect_surface_object();
  int seeds = 0;
  for (Eigen::Index v = 0; v < surface.vertices.rows(); ++v) {
    const Eigen::Vector3d p = surface.vertices.row(v).transpose();
    const Eigen::Vector3d n = normal[static_cast<std::size_t>(v)];
    if (n.norm() == 0.0 || near_taken(p)) continue;
    // The domain's own intersection gives the point its surface index.
    const Eigen::Vector3d d = 0.05 * spacing * n.normalized();
    const Kernel::Segment_3 segment(Point((p - d).x(), (p - d).y(), (p - d).z()),
                                    Point((p + d).x(), (p + d).y(), (p + d).z()));
    if (!crosses(segment)) continue;
    const auto hit = intersect(segment);
    if (std::get<2>(hit) == 0) continue;
    const auto vertex = complex.triangulation().insert(weighted(std::get<0>(hit)));
    if (vertex == Triangulation::Vertex_handle()) continue;  // hidden by a protecting ball
    complex.set_dimension(vertex, 2);
    complex.set_index(vertex, std::get<1>(hit));
    grid[cell(p, 0, 0, 0)].push_back(p);
    ++seeds;
  }
  return seeds;
}

// Nodes: the vertices of the cells in the complex, numbered in order of first use.
TetMesh extract_tets(const Complex& complex) {
  TetMesh mesh;
  std::unordered_map<Triangulation::Vertex_handle, int> index;
  std::vector<Eigen::Vector3d> nodes;
  mesh.tets.resize(static_cast<Eigen::Index>(complex.number_of_cells_in_complex()), 4);
  Eigen::Index row = 0;
  for (auto cell = complex.cells_in_complex_begin(); cell != complex.cells_in_complex_end(); ++cell, ++row)
    for (int k = 0; k < 4; ++k) {
      const auto vertex = cell->vertex(k);
      auto [it, inserted] = index.emplace(vertex, static_cast<int>(nodes.size()));
      if (inserted) {
        const auto& p = vertex->point().point();
        nodes.emplace_back(p.x(), p.y(), p.z());
      }
      mesh.tets(row, k) = it->second;
    }
  mesh.nodes.resize(static_cast<Eigen::Index>(nodes.size()), 3);
  for (std::size_t i = 0; i < nodes.size(); ++i) mesh.nodes.row(static_cast<Eigen::Index>(i)) = nodes[i].transpose();
  mesh.input_vertex.assign(nodes.size(), -1);
  return mesh;
}

}  // namespace

TetMesh mesh_with_cgal(const ClosedSurface& surface, const SizeControl& size) {
  const auto start = std::chrono::steady_clock::now();
  const double size_to_edge = knob("SFLSH_CGAL_SIZE", 0.6);
  const double radius_edge = knob("SFLSH_CGAL_RE", 3.0);
  const double perturb_seconds = knob("SFLSH_CGAL_PERTURB_S", 30.0);
  const double exude_seconds = knob("SFLSH_CGAL_EXUDE_S", 30.0);
  const bool use_features = knob("SFLSH_CGAL_FEATURES", 1.0) != 0.0;

  CGAL::Random random(20231212);  // fixed seed: the same input gives the same mesh (sequential build)
  Domain domain(to_surface_mesh(surface), &random);
  if (use_features && !surface.features.empty()) {
    std::vector<std::vector<Point>> polylines;
    for (const auto& feature : surface.features) {
      if (feature.size() < 2) continue;
      auto& polyline = polylines.emplace_back();
      for (const Eigen::Vector3d& p : feature) polyline.emplace_back(p.x(), p.y(), p.z());
    }
    domain.add_features(polylines.begin(), polylines.end());
  }

  const double bound = size_to_edge * size.edge_length;
  const Criteria criteria(params::edge_size = size.edge_length, params::facet_angle = 25.0, params::facet_size = bound,
                          params::facet_distance = size.surface_distance, params::cell_radius_edge_ratio = radius_edge,
                          params::cell_size = bound);

  TetMesh mesh;
  int seeds = 0;
  try {
#ifdef CGAL_LINKED_WITH_TBB
    const tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                      static_cast<std::size_t>(std::max(1, size.threads)));
#endif
    // make_mesh_3, unrolled (CGAL 5.5.1 make_mesh_3_impl): protect the features, then our seeds, then refine.
    Complex complex;
    CGAL::Mesh_3::internal::C3t3_initializer<Complex, Domain, Criteria,
                                             CGAL::Mesh_3::internal::has_Has_features<Domain>::value>()(
        complex, domain, criteria, use_features && !surface.features.empty());
    seeds = add_surface_seeds(complex, domain, surface, knob("SFLSH_CGAL_SEED", 3.0) * size.edge_length);
    const auto perturb =
        perturb_seconds < 0 ? params::no_perturb() : params::perturb(params::time_limit = perturb_seconds);
    const auto exude = exude_seconds < 0 ? params::no_exude() : params::exude(params::time_limit = exude_seconds);
    CGAL::refine_mesh_3(complex, domain, criteria, perturb, exude, params::no_reset_c3t3());
    require(complex.number_of_cells_in_complex() > 0,
            "cgal: Mesh_3 returned no tets ({} vertices, {} surface facets, {} feature edges in the complex)",
            complex.triangulation().number_of_vertices(), complex.number_of_facets_in_complex(),
            complex.number_of_edges_in_complex());
    mesh = extract_tets(complex);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw_error("cgal: Mesh_3 failed: {}", e.what());
  }
  logger()->debug("cgal: {} tets, {} nodes in {:.2f} s ({} seeds, {} feature polylines{})", mesh.tets.rows(),
                  mesh.nodes.rows(), seconds_since(start), seeds, use_features ? surface.features.size() : 0,
                  kParallel ? ", parallel" : "");
  return mesh;
}

}  // namespace sflsh::meshing::detail
