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

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polyhedral_mesh_domain_with_features_3.h>
#include <CGAL/Random.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/make_mesh_3.h>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/global_control.h>
#endif

#include <chrono>
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

  CGAL::Random random(20231212);   // fixed seed: the same input gives the same mesh (sequential build)
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
  try {
#ifdef CGAL_LINKED_WITH_TBB
    const tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                      static_cast<std::size_t>(std::max(1, size.threads)));
#endif
    const Complex complex = CGAL::make_mesh_3<Complex>(domain, criteria,
                                                       params::perturb(params::time_limit = perturb_seconds),
                                                       params::exude(params::time_limit = exude_seconds),
                                                       params::mesh_3_options(params::number_of_initial_points =
                                                                                  static_cast<int>(knob("SFLSH_CGAL_INIT", -1))));
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
  logger()->debug("cgal: {} tets, {} nodes in {:.2f} s ({} feature polylines{})", mesh.tets.rows(), mesh.nodes.rows(),
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
                  use_features ? surface.features.size() : 0, kParallel ? ", parallel" : "");
  return mesh;
}

}  // namespace sflsh::meshing::detail
