// tetrahedralize(): checks the input surface, runs a backend, then orients, compacts and validates its
// output so that no inverted or degenerate tet is ever returned silently.
#include "backends.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/meshing/quality.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <numbers>

namespace sflsh::meshing {
namespace {

// Tets per "regular-tet volume" a³/(6√2) of the domain at target edge a, measured on layer-like shells
// (tests/meshing/test_backends.cpp, SizePresetsLandNearTheirTarget; see the table in the report):
// both meshers fill space with tets smaller than regular ones.
constexpr double kCalibrationCgal = 1.0;
constexpr double kCalibrationGmsh = 1.0;

// The meshed volume may differ from the enclosed volume by the surface approximation (CGAL) only.
constexpr double kVolumeWarn = 0.03;
constexpr double kVolumeFail = 0.25;

/// Closed two-manifold check: every edge is used exactly twice, once in each direction; every
/// vertex is used; no triangle repeats a vertex.
void check_surface(const ClosedSurface& surface, const char* backend) {
  const Eigen::Index count = surface.vertices.rows(), faces = surface.triangles.rows();
  require(count > 0 && faces > 0, "{}: the input surface is empty ({} vertices, {} triangles)", backend, count, faces);
  require(surface.patch.empty() || surface.patch.size() == static_cast<std::size_t>(faces),
          "{}: the input surface has {} patch labels for {} triangles", backend, surface.patch.size(), faces);
  require(surface.vertices.allFinite(), "{}: the input surface has non-finite vertex coordinates", backend);
  std::vector<char> used(static_cast<std::size_t>(count), 0);
  std::map<std::pair<int, int>, std::array<int, 2>> edges;  // (low, high) → uses low→high, high→low
  for (Eigen::Index t = 0; t < faces; ++t) {
    for (int k = 0; k < 3; ++k) {
      const int v = surface.triangles(t, k);
      require(v >= 0 && v < count, "{}: input triangle {} uses vertex {} of {}", backend, t, v, count);
      used[static_cast<std::size_t>(v)] = 1;
    }
    const int a = surface.triangles(t, 0), b = surface.triangles(t, 1), c = surface.triangles(t, 2);
    require(a != b && b != c && c != a, "{}: input triangle {} repeats a vertex ({}, {}, {})", backend, t, a, b, c);
    for (const auto& [from, to] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}})
      ++edges[{std::min(from, to), std::max(from, to)}][from < to ? 0 : 1];
  }
  for (const auto& [edge, uses] : edges) {
    const int total = uses[0] + uses[1];
    require(total >= 2, "{}: the input surface is open (edge {}–{} has one triangle)", backend, edge.first,
            edge.second);
    require(total == 2, "{}: the input surface is not a two-manifold (edge {}–{} has {} triangles)", backend,
            edge.first, edge.second, total);
    require(uses[0] == 1,
            "{}: the input surface is not consistently oriented (both triangles at edge {}–{} run the same way)",
            backend, edge.first, edge.second);
  }
  const auto unused = std::count(used.begin(), used.end(), 0);
  require(unused == 0, "{}: {} input vertices are used by no triangle", backend, unused);
}

double signed_volume(const TetMesh& mesh, Eigen::Index e) {
  const Eigen::Vector3d x0 = mesh.nodes.row(mesh.tets(e, 0)).transpose();
  return (mesh.nodes.row(mesh.tets(e, 1)).transpose() - x0)
             .dot((mesh.nodes.row(mesh.tets(e, 2)).transpose() - x0)
                      .cross(mesh.nodes.row(mesh.tets(e, 3)).transpose() - x0)) /
         6.0;
}

/// Orients the mesh positively as a whole (a backend with the opposite convention has every tet
/// negative; single negative tets are real inversions and stay so for validation to count).
void orient(TetMesh& mesh) {
  Eigen::Index negative = 0;
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e)
    if (signed_volume(mesh, e) < 0.0) ++negative;
  if (2 * negative > mesh.tets.rows()) mesh.tets.col(1).swap(mesh.tets.col(2));
}

/// Drops nodes used by no tet and renumbers the rest in their order.
void remove_unused_nodes(TetMesh& mesh) {
  const Eigen::Index count = mesh.nodes.rows();
  std::vector<int> remap(static_cast<std::size_t>(count), -1);
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e)
    for (int k = 0; k < 4; ++k) remap[static_cast<std::size_t>(mesh.tets(e, k))] = 0;
  int next = 0;
  for (int& r : remap)
    if (r == 0) r = next++;
  if (next == count) return;
  RowMatrixX3d nodes(next, 3);
  std::vector<int> input_vertex(static_cast<std::size_t>(next), -1);
  for (Eigen::Index i = 0; i < count; ++i) {
    const int r = remap[static_cast<std::size_t>(i)];
    if (r < 0) continue;
    nodes.row(r) = mesh.nodes.row(i);
    input_vertex[static_cast<std::size_t>(r)] = mesh.input_vertex[static_cast<std::size_t>(i)];
  }
  for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e)
    for (int k = 0; k < 4; ++k) mesh.tets(e, k) = remap[static_cast<std::size_t>(mesh.tets(e, k))];
  logger()->debug("tetrahedralize: removed {} nodes used by no tet", count - next);
  mesh.nodes = std::move(nodes);
  mesh.input_vertex = std::move(input_vertex);
}

void validate(const TetMesh& mesh, const ClosedSurface& surface, Mesher mesher) {
  const char* backend = mesher_name(mesher);
  const QualityReport q = quality_report(mesh.nodes, mesh.tets);
  require(q.inverted == 0 && q.degenerate == 0,
          "{}: {} inverted and {} degenerate of {} tets remain after optimization (min dihedral {:.3f}°, min volume "
          "{:.3e} m³)",
          backend, q.inverted, q.degenerate, q.tets, q.min_dihedral_deg, q.min_volume);
  const double enclosed = std::abs(enclosed_volume(surface));
  const double error = std::abs(q.total_volume - enclosed) / enclosed;
  require(error <= kVolumeFail, "{}: the tets fill {:.4e} m³ of the {:.4e} m³ the surface encloses ({:.0f}% off)",
          backend, q.total_volume, enclosed, 100.0 * error);
  if (error > kVolumeWarn)
    logger()->warn("{}: the tets fill {:.4e} m³ of the {:.4e} m³ the surface encloses ({:.1f}% off)", backend,
                   q.total_volume, enclosed, 100.0 * error);
  if (mesher == Mesher::gmsh) {  // the caller relies on every input vertex being a node
    std::vector<int> seen(static_cast<std::size_t>(surface.vertices.rows()), 0);
    for (int v : mesh.input_vertex)
      if (v >= 0) ++seen[static_cast<std::size_t>(v)];
    const auto missing = std::count(seen.begin(), seen.end(), 0);
    const auto repeated = std::count_if(seen.begin(), seen.end(), [](int s) { return s > 1; });
    require(missing == 0 && repeated == 0, "gmsh: {} input vertices are not mesh nodes and {} are several nodes",
            missing, repeated);
  }
  logger()->info("{}: {} tets, {} nodes; dihedral min {:.1f}° median {:.1f}° max {:.1f}°, max radius-edge {:.2f}",
                 backend, q.tets, q.nodes, q.min_dihedral_deg, q.median_dihedral_deg, q.max_dihedral_deg,
                 q.max_radius_edge);
}

}  // namespace

double enclosed_volume(const ClosedSurface& surface) {
  double volume = 0.0;
  for (Eigen::Index t = 0; t < surface.triangles.rows(); ++t) {
    const Eigen::Vector3d a = surface.vertices.row(surface.triangles(t, 0)).transpose();
    const Eigen::Vector3d b = surface.vertices.row(surface.triangles(t, 1)).transpose();
    const Eigen::Vector3d c = surface.vertices.row(surface.triangles(t, 2)).transpose();
    volume += a.dot(b.cross(c)) / 6.0;
  }
  return volume;
}

Mesher parse_mesher(const std::string& name) {
  if (name == "cgal") return Mesher::cgal;
  if (name == "gmsh") return Mesher::gmsh;
  if (name == "layered") return Mesher::layered;
  throw_error("mesher: unknown backend '{}' (expected cgal, gmsh or layered)", name);
}

const char* mesher_name(Mesher mesher) {
  switch (mesher) {
    case Mesher::cgal:
      return "cgal";
    case Mesher::gmsh:
      return "gmsh";
    case Mesher::layered:
      return "layered";
  }
  return "unknown";
}

SizeControl size_for_target_tets(double volume, long target_tets, Mesher mesher, int threads) {
  require(volume > 0.0 && std::isfinite(volume), "size: the volume to mesh is {} m³; expected a positive value",
          volume);
  require(target_tets > 0, "size: target tet count {}; expected a positive count", target_tets);
  const double calibration = mesher == Mesher::cgal ? kCalibrationCgal : kCalibrationGmsh;
  const double regular_volume_factor = 6.0 * std::numbers::sqrt2;  // a³ = 6√2 · (regular tet volume)
  SizeControl size;
  size.edge_length = std::cbrt(volume * regular_volume_factor / (calibration * static_cast<double>(target_tets)));
  size.surface_distance = 0.1 * size.edge_length;
  size.threads = std::max(1, threads);
  return size;
}

TetMesh tetrahedralize(const ClosedSurface& surface, Mesher mesher, const SizeControl& size) {
  const char* backend = mesher_name(mesher);
  check_surface(surface, backend);
  require(size.edge_length > 0.0 && size.surface_distance > 0.0,
          "{}: edge length {} m and surface distance {} m must be positive", backend, size.edge_length,
          size.surface_distance);
  const auto start = std::chrono::steady_clock::now();
  require(mesher != Mesher::layered,
          "layered: extruded layer meshes are built by build_layer_mesh, not from a closed surface");
  TetMesh mesh = mesher == Mesher::cgal ? detail::mesh_with_cgal(surface, size) : detail::mesh_with_gmsh(surface, size);
  require(mesh.tets.rows() > 0 && mesh.nodes.rows() > 0, "{}: the mesher returned no tets", backend);
  require(mesh.tets.minCoeff() >= 0 && mesh.tets.maxCoeff() < mesh.nodes.rows(),
          "{}: a tet uses a node that does not exist", backend);
  if (mesh.input_vertex.size() != static_cast<std::size_t>(mesh.nodes.rows()))
    mesh.input_vertex.assign(static_cast<std::size_t>(mesh.nodes.rows()), -1);
  orient(mesh);
  remove_unused_nodes(mesh);
  validate(mesh, surface, mesher);
  logger()->debug("{}: meshed in {:.2f} s", backend, seconds_since(start));
  return mesh;
}

}  // namespace sflsh::meshing
