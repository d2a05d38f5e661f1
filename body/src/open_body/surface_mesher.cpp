#include "surface_mesher.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>

#include <CGAL/Complex_2_in_triangulation_3.h>
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Delaunay_triangulation_cell_base_with_circumcenter_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/facets_in_complex_2_to_triangle_mesh.h>
#include <CGAL/Implicit_surface_3.h>
#include <CGAL/Polygon_mesh_processing/clip.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Robust_circumcenter_traits_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_cell_base_3.h>
#include <CGAL/Surface_mesh_default_criteria_3.h>
#include <CGAL/Surface_mesh_vertex_base_3.h>
#include <CGAL/make_surface_mesh.h>

#include <array>
#include <cmath>
#include <unordered_map>

namespace sflsh::body::detail {
namespace {

/// A vertex or cell base with an insertion time stamp. CGAL's compact container then orders handles
/// by creation time instead of by address, which makes the surface mesher's refinement order — and
/// so its output — independent of where the allocator puts things (as Mesh_3 does for its own bases).
template <class Base>
class Stamped : public Base {
 public:
  using Base::Base;
  template <class Tds2>
  struct Rebind_TDS {
    using Other = Stamped<typename Base::template Rebind_TDS<Tds2>::Other>;
  };
  using Has_timestamp = CGAL::Tag_true;
  std::size_t time_stamp() const { return time_stamp_; }
  void set_time_stamp(const std::size_t& stamp) { time_stamp_ = stamp; }

 private:
  std::size_t time_stamp_ = static_cast<std::size_t>(-1);  // "unset": the container stamps it
};

// CGAL::Surface_mesh_default_triangulation_3 with time-stamped vertices and cells.
using Kernel = CGAL::Robust_circumcenter_traits_3<CGAL::Exact_predicates_inexact_constructions_kernel>;
using VertexBase = Stamped<CGAL::Surface_mesh_vertex_base_3<Kernel>>;
using CellBase =
    Stamped<CGAL::Delaunay_triangulation_cell_base_with_circumcenter_3<Kernel, CGAL::Surface_mesh_cell_base_3<Kernel>>>;
using Triangulation =
    CGAL::Delaunay_triangulation_3<Kernel, CGAL::Triangulation_data_structure_3<VertexBase, CellBase>>;
using Complex = CGAL::Complex_2_in_triangulation_3<Triangulation>;
using Traits = Triangulation::Geom_traits;
using Point = Traits::Point_3;
using FT = Traits::FT;
using Mesh = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;

// Delaunay refinement criteria: minimum angle [deg], surface-Delaunay-ball radius and centre-to-surface
// distance bounds [m]. Fine enough (≈ 40k vertices) that remeshing only coarsens.
constexpr double kAngleBound = 30.0;
constexpr double kRadiusBound = 0.010;
constexpr double kDistanceBound = 0.0015;

/// The field as CGAL's implicit function.
struct FieldFunction {
  const BodyField* field;
  FT operator()(const Point& p) const { return field->value({p.x(), p.y(), p.z()}); }
};

/// A point on f = 0 between `inside` (f < 0) and the first sample outside along `direction`, or nothing.
bool shoot_ray(const BodyField& field, const Eigen::Vector3d& inside, const Eigen::Vector3d& direction,
               Eigen::Vector3d& hit) {
  constexpr double kStep = 0.004, kReach = 0.6;
  Eigen::Vector3d lo = inside;
  for (double t = kStep; t <= kReach; t += kStep) {
    const Eigen::Vector3d hi = inside + t * direction;
    if (field.value(hi) <= 0.0) {
      lo = hi;
      continue;
    }
    Eigen::Vector3d a = lo, b = hi;
    for (int it = 0; it < 60; ++it) {
      const Eigen::Vector3d m = 0.5 * (a + b);
      (field.value(m) <= 0.0 ? a : b) = m;
    }
    hit = 0.5 * (a + b);
    return true;
  }
  return false;
}

/// Deterministic initial points for the mesher: rays from every joint along 26 directions, so that
/// every limb, hand and foot is seeded (CGAL's own initial points use a time-seeded random generator).
std::vector<Point> initial_points(const BodyField& field, const Skeleton& skeleton) {
  std::vector<Point> points;
  for (const Eigen::Vector3d& joint : skeleton.joints) {
    if (field.value(joint) >= 0.0) continue;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          if (dx == 0 && dy == 0 && dz == 0) continue;
          Eigen::Vector3d hit;
          if (shoot_ray(field, joint, Eigen::Vector3d(dx, dy, dz).normalized(), hit))
            points.emplace_back(hit.x(), hit.y(), hit.z());
        }
  }
  return points;
}

Mesh delaunay_surface(const BodyField& field, const Skeleton& skeleton) {
  Triangulation triangulation;
  Complex complex(triangulation);
  const std::vector<Point> seeds = initial_points(field, skeleton);
  require(seeds.size() >= 20, "open body mesher: only {} seed points found on the surface", seeds.size());
  triangulation.insert(seeds.begin(), seeds.end());

  // The bounding sphere's centre (the pelvis joint) must be inside; its radius encloses the body.
  double radius = 0.0;
  for (const Eigen::Vector3d& joint : skeleton.joints) radius = std::max(radius, joint.norm());
  radius = std::max(radius, std::max(std::abs(skeleton.floor_y), std::abs(skeleton.head_top_y))) + 0.3;
  require(field.value(Eigen::Vector3d::Zero()) < 0.0, "open body mesher: the pelvis joint is outside the body");
  const CGAL::Implicit_surface_3<Traits, FieldFunction> surface(FieldFunction{&field},
                                                                Traits::Sphere_3(CGAL::ORIGIN, radius * radius), 1e-5);
  const CGAL::Surface_mesh_default_criteria_3<Triangulation> criteria(kAngleBound, kRadiusBound, kDistanceBound);
  CGAL::make_surface_mesh(complex, surface, criteria, CGAL::Manifold_tag(), 0);

  Mesh mesh;
  CGAL::facets_in_complex_2_to_triangle_mesh(complex, mesh);
  require(CGAL::is_closed(mesh), "open body mesher: the Delaunay surface mesh is not closed");
  if (!PMP::is_outward_oriented(mesh)) PMP::reverse_face_orientations(mesh);
  return mesh;
}

void snap_border(Mesh& half);

/// The right half (x ≤ 0) of a closed surface, cut by the mid-plane, its border snapped to x = 0.
Mesh right_half(const Mesh& closed) {
  Mesh half = closed;
  PMP::clip(half, CGAL::Epick::Plane_3(1.0, 0.0, 0.0, 0.0));
  half.collect_garbage();
  snap_border(half);
  require(!CGAL::is_closed(half), "open body mesher: the mid-plane does not cut the body");
  return half;
}

void snap_border(Mesh& half) {
  for (Mesh::Vertex_index v : half.vertices())
    if (half.is_border(v)) half.point(v) = Point(0.0, half.point(v).y(), half.point(v).z());
}

/// Isotropic remeshing of the half surface; its border stays on the mid-plane.
Mesh remeshed(const Mesh& half, double edge_length) {
  Mesh mesh = half;
  PMP::isotropic_remeshing(faces(mesh), edge_length, mesh, CGAL::parameters::number_of_iterations(6));
  mesh.collect_garbage();
  snap_border(mesh);
  return mesh;
}

/// The closed, exactly symmetric surface: the half surface (projected onto f = 0, border kept on
/// x = 0) and its mirror image, sharing the border vertices; mirroring reverses the faces' order.
TriangleSurface mirrored_whole(const Mesh& half, const BodyField& field) {
  const auto n = static_cast<int>(half.number_of_vertices());
  std::vector<int> partner(static_cast<std::size_t>(n), -1);  // index of each half vertex's mirror image
  int count = n;
  for (Mesh::Vertex_index v : half.vertices()) {
    const auto i = static_cast<std::size_t>(v);
    partner[i] = half.is_border(v) ? static_cast<int>(i) : count++;
  }
  TriangleSurface out;
  out.vertices.resize(count, 3);
  out.mirror.resize(static_cast<std::size_t>(count));
  for (Mesh::Vertex_index v : half.vertices()) {
    const auto i = static_cast<std::size_t>(v);
    const Point& p = half.point(v);
    Eigen::Vector3d x = project_to_surface(field, Eigen::Vector3d(p.x(), p.y(), p.z()));
    if (half.is_border(v)) x.x() = 0.0;
    x.x() = std::min(x.x(), 0.0);
    out.vertices.row(static_cast<Eigen::Index>(i)) = x.transpose();
    out.vertices.row(partner[i]) = Eigen::RowVector3d(-x.x(), x.y(), x.z());
    out.mirror[i] = partner[i];
    out.mirror[static_cast<std::size_t>(partner[i])] = static_cast<int>(i);
  }
  out.faces.resize(2 * static_cast<Eigen::Index>(half.number_of_faces()), 3);
  Eigen::Index row = 0;
  for (Mesh::Face_index f : half.faces()) {
    std::array<int, 3> t{};
    int k = 0;
    for (Mesh::Vertex_index v : CGAL::vertices_around_face(half.halfedge(f), half))
      t[static_cast<std::size_t>(k++)] = static_cast<int>(static_cast<std::size_t>(v));
    out.faces.row(row++) << t[0], t[1], t[2];
    out.faces.row(row++) << partner[static_cast<std::size_t>(t[0])], partner[static_cast<std::size_t>(t[2])],
        partner[static_cast<std::size_t>(t[1])];
  }
  return out;
}

}  // namespace

TriangleSurface mesh_body_surface(const BodyField& field, const Skeleton& skeleton, int target_vertices) {
  require(target_vertices >= 500, "open body mesher: target_vertices {} is below 500", target_vertices);
  const Mesh fine = delaunay_surface(field, skeleton);
  const double area = PMP::area(fine);
  logger()->info("open body: Delaunay surface mesh {} vertices, area {:.3f} m²", fine.number_of_vertices(), area);
  const Mesh half = right_half(fine);

  // Equilateral triangles of edge L: V ≈ 2A/(√3 L²). One trial pass calibrates the remesher's density.
  const auto whole_count = [](const Mesh& m) {
    int border = 0;
    for (Mesh::Vertex_index v : m.vertices()) border += m.is_border(v) ? 1 : 0;
    return 2 * static_cast<int>(m.number_of_vertices()) - border;
  };
  double edge = std::sqrt(2.0 * area / (std::sqrt(3.0) * target_vertices));
  Mesh mesh = remeshed(half, edge);
  edge *= std::sqrt(static_cast<double>(whole_count(mesh)) / target_vertices);
  mesh = remeshed(half, edge);
  TriangleSurface out = mirrored_whole(mesh, field);
  logger()->info("open body: remeshed to {} vertices (edge {:.4f} m, symmetric)", out.vertices.rows(), edge);
  return out;
}

}  // namespace sflsh::body::detail
