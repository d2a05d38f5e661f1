// The triangle-mesh obstacle: closest point by a CGAL AABB tree, the feature of the closest point by
// Ericson's point–triangle regions, the sign by angle-weighted pseudonormals [Bærentzen and Aanæs 2005,
// "Signed distance computation using the angle weighted pseudonormal", IEEE TVCG 11(3)]: for a closed
// mesh, sign((q − c)·N) is the inside/outside sign when N is the face normal (face region), the sum of
// the two face normals (edge region) or Σ_f α_f n_f with α_f the angle of face f at the vertex (vertex).
// Files are read with VTK's readers (IOGeometry: .obj/.stl, IOPLY: .ply).
#include "file/obj_file.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/scene/obstacle.hpp>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <Eigen/Geometry>
#include <vtkCellArray.h>
#include <vtkCleanPolyData.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkPLYReader.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSTLReader.h>
#include <vtkSmartPointer.h>
#include <vtkTriangleFilter.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <unordered_map>

namespace sflsh::scene {

namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using CgalPoint = Kernel::Point_3;
using CgalTriangle = Kernel::Triangle_3;
using TriangleIterator = std::vector<CgalTriangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using CgalTree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

CgalPoint to_cgal(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

/// Where on a triangle the closest point lies: a vertex (0, 1, 2), an edge (0 = v0v1, 1 = v1v2,
/// 2 = v2v0) or the interior.
struct TriangleFeature {
  enum Kind { vertex, edge, face } kind = face;
  int index = 0;
  Eigen::Vector3d point;
};

/// Closest point of triangle (a, b, c) to p with its Voronoi region (Ericson, Real-Time Collision
/// Detection §5.1.5).
TriangleFeature closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return {TriangleFeature::vertex, 0, a};
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return {TriangleFeature::vertex, 1, b};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return {TriangleFeature::edge, 0, a + (d1 / (d1 - d3)) * ab};
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return {TriangleFeature::vertex, 2, c};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return {TriangleFeature::edge, 2, a + (d2 / (d2 - d6)) * ac};
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
    return {TriangleFeature::edge, 1, b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b)};
  const double denom = 1.0 / (va + vb + vc);
  return {TriangleFeature::face, 0, a + ab * (vb * denom) + ac * (vc * denom)};
}

std::int64_t edge_key(int i, int j) {
  return (static_cast<std::int64_t>(std::min(i, j)) << 32) | static_cast<std::uint32_t>(std::max(i, j));
}

/// .stl and .ply through VTK's readers: polygons triangulated, coincident points merged (STL stores each
/// triangle's own), unused points dropped.
void read_with_vtk(const std::filesystem::path& path, const std::string& ext, RowMatrixX3d& vertices,
                   RowMatrixX3i& triangles) {
  vtkSmartPointer<vtkPolyDataAlgorithm> reader;
  if (ext == ".stl") {
    auto r = vtkSmartPointer<vtkSTLReader>::New();
    r->SetFileName(path.string().c_str());
    reader = r;
  } else if (ext == ".ply") {
    auto r = vtkSmartPointer<vtkPLYReader>::New();
    r->SetFileName(path.string().c_str());
    reader = r;
  } else {
    throw_error("{}: unsupported mesh format '{}' (expected .obj, .stl or .ply)", path.string(), ext);
  }
  vtkNew<vtkTriangleFilter> triangulate;  // polygons → triangles
  triangulate->SetInputConnection(reader->GetOutputPort());
  triangulate->PassLinesOff();
  triangulate->PassVertsOff();
  vtkNew<vtkCleanPolyData> clean;  // merge coincident points (STL stores each triangle's own)
  clean->SetInputConnection(triangulate->GetOutputPort());
  clean->PointMergingOn();
  clean->SetTolerance(0.0);
  clean->Update();
  vtkPolyData* poly = clean->GetOutput();
  require(poly != nullptr && poly->GetNumberOfPolys() > 0, "{}: no triangles could be read", path.string());

  vertices.resize(poly->GetNumberOfPoints(), 3);
  for (vtkIdType i = 0; i < poly->GetNumberOfPoints(); ++i) {
    double x[3];
    poly->GetPoint(i, x);
    vertices.row(i) << x[0], x[1], x[2];
  }
  triangles.resize(poly->GetNumberOfPolys(), 3);
  vtkCellArray* polys = poly->GetPolys();
  polys->InitTraversal();
  vtkNew<vtkIdList> ids;
  Eigen::Index f = 0;
  while (polys->GetNextCell(ids)) {
    if (ids->GetNumberOfIds() != 3) continue;
    triangles.row(f++) << static_cast<int>(ids->GetId(0)), static_cast<int>(ids->GetId(1)),
        static_cast<int>(ids->GetId(2));
  }
  triangles.conservativeResize(f, 3);
  require(f > 0, "{}: no triangles could be read", path.string());
}

}  // namespace

struct TriangleMesh::Tree {
  std::vector<CgalTriangle> triangles;
  CgalTree tree;
};

TriangleMesh::TriangleMesh(const RowMatrixX3d& vertices, const RowMatrixX3i& triangles)
    : vertices_(vertices), triangles_(triangles), tree_(std::make_unique<Tree>()) {
  require(vertices.rows() >= 3 && triangles.rows() >= 1, "triangle mesh: needs ≥ 3 vertices and ≥ 1 triangle");
  require(vertices.allFinite(), "triangle mesh: vertex positions must be finite");
  require(triangles.minCoeff() >= 0 && triangles.maxCoeff() < vertices.rows(),
          "triangle mesh: triangle indices must lie in [0, {})", vertices.rows());
  // Edge ids, and closedness: each undirected edge twice, each directed edge once.
  std::unordered_map<std::int64_t, int> edge_id;
  std::unordered_map<std::int64_t, int> directed;
  std::vector<int> edge_uses;
  triangle_edges_.resize(triangles.rows(), 3);
  for (Eigen::Index f = 0; f < triangles.rows(); ++f)
    for (int e = 0; e < 3; ++e) {
      const int i = triangles(f, e), j = triangles(f, (e + 1) % 3);
      require(i != j, "triangle mesh: triangle {} repeats vertex {}", f, i);
      const auto [it, inserted] = edge_id.try_emplace(edge_key(i, j), static_cast<int>(edge_uses.size()));
      if (inserted) edge_uses.push_back(0);
      ++edge_uses[static_cast<std::size_t>(it->second)];
      ++directed[(static_cast<std::int64_t>(i) << 32) | static_cast<std::uint32_t>(j)];
      triangle_edges_(f, e) = it->second;
    }
  closed_ = std::all_of(edge_uses.begin(), edge_uses.end(), [](int n) { return n == 2; }) &&
            std::all_of(directed.begin(), directed.end(), [](const auto& kv) { return kv.second == 1; });
  edge_normal_.resize(edge_uses.size());
  face_normal_.resize(static_cast<std::size_t>(triangles.rows()));
  vertex_normal_.resize(static_cast<std::size_t>(vertices.rows()));
  tree_->triangles.resize(static_cast<std::size_t>(triangles.rows()));
  rebuild();
}

TriangleMesh::~TriangleMesh() = default;

void TriangleMesh::set_vertices(const RowMatrixX3d& vertices) {
  require(vertices.rows() == vertices_.rows(), "triangle mesh: set_vertices expects {} vertices (got {})",
          vertices_.rows(), vertices.rows());
  require(vertices.allFinite(), "triangle mesh: set_vertices got non-finite positions");
  vertices_ = vertices;
  rebuild();
}

void TriangleMesh::rebuild() {
  // Pseudonormals. A degenerate (zero-area) triangle gets a zero normal and contributes nothing.
  std::fill(edge_normal_.begin(), edge_normal_.end(), Eigen::Vector3d::Zero());
  std::fill(vertex_normal_.begin(), vertex_normal_.end(), Eigen::Vector3d::Zero());
  bounds_ = Aabb{};
  for (Eigen::Index v = 0; v < vertices_.rows(); ++v) bounds_.extend(vertices_.row(v).transpose());
  for (Eigen::Index f = 0; f < triangles_.rows(); ++f) {
    const Eigen::Vector3d x[3] = {vertices_.row(triangles_(f, 0)).transpose(),
                                  vertices_.row(triangles_(f, 1)).transpose(),
                                  vertices_.row(triangles_(f, 2)).transpose()};
    const Eigen::Vector3d cross = (x[1] - x[0]).cross(x[2] - x[0]);
    const double twice_area = cross.norm();
    const Eigen::Vector3d n = twice_area > 0.0 ? Eigen::Vector3d(cross / twice_area) : Eigen::Vector3d::Zero();
    face_normal_[static_cast<std::size_t>(f)] = n;
    for (int k = 0; k < 3; ++k) {
      edge_normal_[static_cast<std::size_t>(triangle_edges_(f, k))] += n;
      const Eigen::Vector3d e1 = x[(k + 1) % 3] - x[k], e2 = x[(k + 2) % 3] - x[k];
      const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));  // interior angle at corner k
      vertex_normal_[static_cast<std::size_t>(triangles_(f, k))] += angle * n;
    }
    tree_->triangles[static_cast<std::size_t>(f)] = CgalTriangle(to_cgal(x[0]), to_cgal(x[1]), to_cgal(x[2]));
  }
  // rebuild() builds the hierarchy; the distance-query search tree (a KD-tree of primitive reference
  // points, for the first guess of each query: ~10× faster queries near the surface, measured) is built
  // now too, not lazily at the first (possibly concurrent) query.
  tree_->tree.rebuild(tree_->triangles.cbegin(), tree_->triangles.cend());
  tree_->tree.accelerate_distance_queries();
}

double TriangleMesh::local_distance(const Eigen::Vector3d& q, Eigen::Vector3d* gradient,
                                    Eigen::Matrix3d* hessian) const {
  const auto hit = tree_->tree.closest_point_and_primitive(to_cgal(q));
  const auto f = static_cast<Eigen::Index>(hit.second - tree_->triangles.cbegin());
  const Eigen::Vector3d a = vertices_.row(triangles_(f, 0)).transpose();
  const Eigen::Vector3d b = vertices_.row(triangles_(f, 1)).transpose();
  const Eigen::Vector3d c = vertices_.row(triangles_(f, 2)).transpose();
  const TriangleFeature feature = closest_on_triangle(q, a, b, c);
  Eigen::Vector3d pseudonormal;
  Eigen::Vector3d edge_direction = Eigen::Vector3d::Zero();
  switch (feature.kind) {
    case TriangleFeature::face:
      pseudonormal = face_normal_[static_cast<std::size_t>(f)];
      break;
    case TriangleFeature::edge: {
      pseudonormal = edge_normal_[static_cast<std::size_t>(triangle_edges_(f, feature.index))];
      const int i = triangles_(f, feature.index), j = triangles_(f, (feature.index + 1) % 3);
      edge_direction = (vertices_.row(j) - vertices_.row(i)).transpose().normalized();
      break;
    }
    case TriangleFeature::vertex:
      pseudonormal = vertex_normal_[static_cast<std::size_t>(triangles_(f, feature.index))];
      break;
  }
  const Eigen::Vector3d v = q - feature.point;
  const double d = v.norm();
  if (d < 1e-12) {  // on the surface: ∇φ is the pseudonormal direction, the curvature is not defined
    if (gradient) *gradient = pseudonormal.normalized();
    if (hessian) hessian->setZero();
    return 0.0;
  }
  const double sign = v.dot(pseudonormal) >= 0.0 ? 1.0 : -1.0;
  const Eigen::Vector3d n = v / d;
  if (gradient) *gradient = sign * n;
  if (hessian) {
    // φ = s |q − c(q)|: c fixed at a vertex, sliding along the edge, sliding in the plane of a face.
    // A point on the boundary of the face's region (q − c along the face normal, e.g. exactly above
    // the shared edge of two coplanar triangles) takes the face's one-sided value 0.
    const bool on_face_region = std::abs(n.dot(face_normal_[static_cast<std::size_t>(f)])) > 1.0 - 1e-12;
    switch (on_face_region ? TriangleFeature::face : feature.kind) {
      case TriangleFeature::face:
        hessian->setZero();
        break;
      case TriangleFeature::edge:
        *hessian =
            sign / d * (Eigen::Matrix3d::Identity() - n * n.transpose() - edge_direction * edge_direction.transpose());
        break;
      case TriangleFeature::vertex:
        *hessian = sign / d * (Eigen::Matrix3d::Identity() - n * n.transpose());
        break;
    }
  }
  return sign * d;
}

Surface TriangleMesh::local_surface(int /*n_segments*/) const { return {vertices_, triangles_}; }

std::unique_ptr<TriangleMesh> TriangleMesh::load(const std::filesystem::path& path, double scale) {
  require(std::isfinite(scale) && scale > 0.0, "{}: mesh scale must be positive (got {})", path.string(), scale);
  require(std::filesystem::is_regular_file(path), "{}: mesh file not found", path.string());
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  RowMatrixX3d vertices;
  RowMatrixX3i triangles;
  if (ext == ".obj") {
    detail::ObjMesh obj = detail::read_obj(path);  // strict: bad indices and non-finite vertices are errors
    vertices = scale * obj.vertices;
    triangles = std::move(obj.triangles);
  } else {
    read_with_vtk(path, ext, vertices, triangles);
    vertices *= scale;
  }
  const Eigen::Index f = triangles.rows();
  require(vertices.allFinite(), "{}: non-finite vertex coordinates", path.string());

  // A closed mesh stored inward (negative enclosed volume) is flipped so that φ < 0 inside.
  double volume = 0.0;
  for (Eigen::Index t = 0; t < f; ++t) {
    const Eigen::Vector3d a = vertices.row(triangles(t, 0)).transpose(), b = vertices.row(triangles(t, 1)).transpose(),
                          c = vertices.row(triangles(t, 2)).transpose();
    volume += a.dot(b.cross(c)) / 6.0;
  }
  if (volume < 0.0) triangles.col(1).swap(triangles.col(2));
  return std::make_unique<TriangleMesh>(vertices, triangles);
}

}  // namespace sflsh::scene
