// gmsh backend (gmsh 4.8 C++ API). The input triangles become discrete surfaces (one per patch) that
// gmsh keeps as they are; the volume on their surface loop is meshed with HXT and optimized. So every
// input vertex stays a node (docs/build.md, "Volume meshing between triangulated surfaces").
//
// gmsh is process-global state: one mesher at a time (mutex), initialize/finalize around each call,
// and its errors (thrown as std::string in 4.8) become sflsh::Error.
#include "backends.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/scoped_seconds.hpp>

#include <gmsh.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <mutex>
#include <unordered_map>
#include <vector>

namespace sflsh::meshing::detail {
namespace {

// Surface edges longer than kSubdivideRatio · edge_length are halved (1→4 subdivision), so that after
// subdivision the mean edge lies in [1/√2, √2] · edge_length unless the input is already finer.
const double kSubdivideRatio = std::sqrt(2.0);
constexpr int kMaxSubdivisions = 4;  // 256 triangles per input triangle at most

// Temporary tuning knob (environment) while calibrating; removed once the constants are fixed.
double knob(const char* name, double fallback) {
  const char* value = std::getenv(name);
  return value ? std::atof(value) : fallback;
}

struct Boundary {
  RowMatrixX3d vertices;  ///< the input vertices first, then midpoints
  RowMatrixX3i triangles;
  std::vector<NodeKind> patch;
  int levels = 0;
};

double mean_edge(const RowMatrixX3d& vertices, const RowMatrixX3i& triangles) {
  double sum = 0.0;
  for (Eigen::Index t = 0; t < triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k) sum += (vertices.row(triangles(t, k)) - vertices.row(triangles(t, (k + 1) % 3))).norm();
  return sum / static_cast<double>(3 * triangles.rows());
}

// One 1→4 subdivision with flat midpoints (they lie on the same piecewise-linear surface); midpoints
// are shared by the two triangles of an edge and appended after the existing vertices.
void subdivide_once(Boundary& boundary) {
  const Eigen::Index count = boundary.vertices.rows(), faces = boundary.triangles.rows();
  std::unordered_map<std::uint64_t, int> midpoint;
  std::vector<Eigen::Vector3d> added;
  const auto middle = [&](int a, int b) {
    const std::uint64_t key =
        (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
    auto [it, inserted] = midpoint.emplace(key, static_cast<int>(count + static_cast<Eigen::Index>(added.size())));
    if (inserted) added.push_back(0.5 * (boundary.vertices.row(a) + boundary.vertices.row(b)).transpose());
    return it->second;
  };
  RowMatrixX3i triangles(4 * faces, 3);
  std::vector<NodeKind> patch(static_cast<std::size_t>(4 * faces));
  for (Eigen::Index t = 0; t < faces; ++t) {
    const int a = boundary.triangles(t, 0), b = boundary.triangles(t, 1), c = boundary.triangles(t, 2);
    const int ab = middle(a, b), bc = middle(b, c), ca = middle(c, a);
    triangles.row(4 * t) << a, ab, ca;
    triangles.row(4 * t + 1) << ab, b, bc;
    triangles.row(4 * t + 2) << ca, bc, c;
    triangles.row(4 * t + 3) << ab, bc, ca;
    for (int k = 0; k < 4; ++k)
      patch[static_cast<std::size_t>(4 * t + k)] = boundary.patch[static_cast<std::size_t>(t)];
  }
  boundary.vertices.conservativeResize(count + static_cast<Eigen::Index>(added.size()), 3);
  for (std::size_t i = 0; i < added.size(); ++i)
    boundary.vertices.row(count + static_cast<Eigen::Index>(i)) = added[i].transpose();
  boundary.triangles = std::move(triangles);
  boundary.patch = std::move(patch);
  ++boundary.levels;
}

Boundary refined_boundary(const ClosedSurface& surface, double edge_length) {
  Boundary boundary{surface.vertices, surface.triangles, surface.patch, 0};
  if (boundary.patch.size() != static_cast<std::size_t>(surface.triangles.rows()))
    boundary.patch.assign(static_cast<std::size_t>(surface.triangles.rows()), NodeKind::outer);
  while (boundary.levels < kMaxSubdivisions &&
         mean_edge(boundary.vertices, boundary.triangles) > kSubdivideRatio * edge_length)
    subdivide_once(boundary);
  return boundary;
}

std::mutex& gmsh_mutex() {
  static std::mutex mutex;
  return mutex;
}

/// gmsh::initialize now, gmsh::finalize on every way out of the scope.
struct GmshSession {
  GmshSession() {
    gmsh::initialize(0, nullptr, /*readConfigFiles=*/false);
    gmsh::option::setNumber("General.Terminal", 0);
    gmsh::logger::start();
  }
  ~GmshSession() {
    try {
      gmsh::logger::stop();
      gmsh::finalize();
    } catch (...) {  // nothing sensible to do in a destructor; gmsh stays usable for the next call
    }
  }
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;
};

std::string last_gmsh_error() {
  std::string error;
  try {
    gmsh::logger::getLastError(error);
  } catch (...) {
  }
  return error.empty() ? std::string("no error message") : error;
}

TetMesh run_gmsh(const Boundary& boundary, int input_count, const SizeControl& size) {
  gmsh::model::add("sflsh_layer");
  // One thread by default: HXT on several threads is not deterministic, and under load it returned
  // meshes with unpaired boundary edges in CI (SFLSH_GMSH_THREADS overrides, e.g. for benchmarks).
  gmsh::option::setNumber("General.NumThreads", 1);
  gmsh::option::setNumber("Mesh.MaxNumThreads3D", knob("SFLSH_GMSH_THREADS", 1));
  gmsh::option::setNumber("Mesh.Algorithm3D", knob("SFLSH_GMSH_ALGO", 10));  // 10 HXT, 1 Delaunay
  gmsh::option::setNumber("Mesh.MeshSizeMax", size.edge_length);
  gmsh::option::setNumber("Mesh.Optimize", 1);
  gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", knob("SFLSH_GMSH_EXTEND", 1));
  gmsh::option::setNumber("Mesh.Renumber", 0);  // keep our node tags: tag − 1 is the boundary vertex index

  // One discrete surface per patch; a node is classified on the first patch that uses it.
  const auto n = static_cast<std::size_t>(boundary.vertices.rows());
  std::vector<int> owner(n, -1);
  std::vector<int> surfaces;
  for (NodeKind kind : {NodeKind::outer, NodeKind::inner, NodeKind::side, NodeKind::interior}) {
    std::vector<std::size_t> triangle_nodes, node_tags;
    std::vector<double> coords;
    for (Eigen::Index t = 0; t < boundary.triangles.rows(); ++t) {
      if (boundary.patch[static_cast<std::size_t>(t)] != kind) continue;
      for (int k = 0; k < 3; ++k) triangle_nodes.push_back(static_cast<std::size_t>(boundary.triangles(t, k)) + 1);
    }
    if (triangle_nodes.empty()) continue;
    const int tag = gmsh::model::addDiscreteEntity(2);
    for (std::size_t node : triangle_nodes) {
      int& o = owner[node - 1];
      if (o >= 0) continue;
      o = tag;
      node_tags.push_back(node);
      for (int c = 0; c < 3; ++c) coords.push_back(boundary.vertices(static_cast<Eigen::Index>(node - 1), c));
    }
    gmsh::model::mesh::addNodes(2, tag, node_tags, coords);
    gmsh::model::mesh::addElementsByType(tag, 2, {}, triangle_nodes);  // type 2: 3-node triangle
    surfaces.push_back(tag);
  }
  const int loop = gmsh::model::geo::addSurfaceLoop(surfaces);
  gmsh::model::geo::addVolume({loop});
  gmsh::model::geo::synchronize();
  gmsh::model::mesh::generate(3);

  std::vector<std::size_t> node_tags, tet_tags, tet_nodes;
  std::vector<double> coords, parametric;
  gmsh::model::mesh::getNodes(node_tags, coords, parametric, -1, -1, false, false);
  gmsh::model::mesh::getElementsByType(4, tet_tags, tet_nodes);  // type 4: 4-node tet
  require(!tet_nodes.empty(), "gmsh: no tets generated ({})", last_gmsh_error());

  TetMesh mesh;
  std::size_t max_tag = 0;
  for (std::size_t tag : node_tags) max_tag = std::max(max_tag, tag);
  std::vector<int> index(max_tag + 1, -1);
  mesh.nodes.resize(static_cast<Eigen::Index>(node_tags.size()), 3);
  mesh.input_vertex.assign(node_tags.size(), -1);
  for (std::size_t i = 0; i < node_tags.size(); ++i) {
    index[node_tags[i]] = static_cast<int>(i);
    for (int c = 0; c < 3; ++c)
      mesh.nodes(static_cast<Eigen::Index>(i), c) = coords[3 * i + static_cast<std::size_t>(c)];
    if (node_tags[i] >= 1 && node_tags[i] <= static_cast<std::size_t>(input_count)) {
      const int vertex = static_cast<int>(node_tags[i] - 1);
      require((mesh.nodes.row(static_cast<Eigen::Index>(i)) - boundary.vertices.row(vertex)).norm() == 0.0,
              "gmsh: node {} moved away from input vertex {}", node_tags[i], vertex);
      mesh.input_vertex[i] = vertex;
    }
  }
  mesh.tets.resize(static_cast<Eigen::Index>(tet_tags.size()), 4);
  for (std::size_t e = 0; e < tet_tags.size(); ++e)
    for (int k = 0; k < 4; ++k) {
      const std::size_t tag = tet_nodes[4 * e + static_cast<std::size_t>(k)];
      require(tag <= max_tag && index[tag] >= 0, "gmsh: tet {} uses unknown node {}", tet_tags[e], tag);
      mesh.tets(static_cast<Eigen::Index>(e), k) = index[tag];
    }
  return mesh;
}

}  // namespace

TetMesh mesh_with_gmsh(const ClosedSurface& surface, const SizeControl& size) {
  const auto start = std::chrono::steady_clock::now();
  const Boundary boundary = refined_boundary(surface, size.edge_length);
  const int input_count = static_cast<int>(surface.vertices.rows());

  TetMesh mesh;
  {
    const std::lock_guard<std::mutex> lock(gmsh_mutex());
    try {
      const GmshSession session;
      mesh = run_gmsh(boundary, input_count, size);
    } catch (const std::string& message) {
      throw_error("gmsh: {}", message);
    } catch (const Error&) {
      throw;
    } catch (const std::exception& e) {
      throw_error("gmsh: {}", e.what());
    }
  }
  logger()->debug("gmsh: {} tets, {} nodes in {:.2f} s ({} boundary triangles, {} subdivisions of the input)",
                  mesh.tets.rows(), mesh.nodes.rows(), seconds_since(start), boundary.triangles.rows(),
                  boundary.levels);
  return mesh;
}

}  // namespace sflsh::meshing::detail
