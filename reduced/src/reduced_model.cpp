#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/npz.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/material/layer_material.hpp>
#include <sflsh/material/orthotropic_fung.hpp>
#include <sflsh/meshing/layer_cache.hpp>
#include <sflsh/reduced/reduced_model.hpp>

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstring>

namespace sflsh::reduced {

namespace {

/// Bump when what a cache entry holds changes (2: the key hashes the attached nodes, the skin's rim is attached,
/// per-function cubature coverage; 3: point handles avoid the nodes next to the rim; 4: the cubature records its
/// stiffness coverage and auto K grows until the subspace is covered).
constexpr int kReducedFormat = 4;

std::uint64_t fnv1a(std::uint64_t hash, const void* data, std::size_t bytes) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t k = 0; k < bytes; ++k) {
    hash ^= p[k];
    hash *= 1099511628211ULL;
  }
  return hash;
}

/// Hash of what the handles, basis and cubature are built from: template nodes and tets, the attached
/// (Dirichlet) components — they make the bone handles and where every basis function vanishes — and the options.
std::string cache_key(const meshing::LayerMesh& mesh, const model::Dirichlet& dirichlet,
                      const ReducedModelOptions& options) {
  std::uint64_t h = 1469598103934665603ULL;
  h = fnv1a(h, mesh.nodes.data(), sizeof(double) * static_cast<std::size_t>(mesh.nodes.size()));
  h = fnv1a(h, mesh.tets.data(), sizeof(int) * static_cast<std::size_t>(mesh.tets.size()));
  const std::vector<char> attached = dirichlet.mask(mesh.num_nodes());
  h = fnv1a(h, attached.data(), attached.size());
  const std::string settings =
      fmt::format("v{} P{} K{} cover{} w{} drop{} max{} affine{} len{}", kReducedFormat, options.point_handles,
                  options.cubature, options.cubature_auto ? options.coverage_ratio : 0.0,
                  options.weighting == CubatureWeighting::nnls ? "nnls" : "voronoi", options.basis.drop_below,
                  options.basis.max_influences, options.basis.affine ? 1 : 0, options.basis.affine_length);
  h = fnv1a(h, settings.data(), settings.size());
  return fmt::format("{:016x} {}", h, settings);
}

std::filesystem::path cache_file(const std::filesystem::path& dir, const std::string& key) {
  return dir / fmt::format("reduced_{}.npz", key.substr(0, 16));
}

std::vector<std::int64_t> to_i64(const std::vector<int>& v) { return {v.begin(), v.end()}; }
std::vector<int> to_int(const std::vector<std::int64_t>& v) {
  std::vector<int> out;
  for (auto x : v) out.push_back(static_cast<int>(x));
  return out;
}

void save_model(const std::filesystem::path& path, const ReducedModel& m) {
  std::vector<std::int64_t> rows, cols;
  std::vector<double> values;
  for (int i = 0; i < m.subspace.num_nodes(); ++i)
    for (SparseRowMatrix::InnerIterator it(m.subspace.basis, i); it; ++it) {
      rows.push_back(i);
      cols.push_back(it.col());
      values.push_back(it.value());
    }
  npz::write(
      path,
      {{"key", npz::make_string(m.cache_key)},
       {"shape", npz::make_i64({2}, {m.subspace.num_nodes(), m.subspace.num_functions()})},
       {"basis_rows", npz::make_i64({rows.size()}, rows)},
       {"basis_cols", npz::make_i64({cols.size()}, cols)},
       {"basis_values", npz::make_f64({values.size()}, values)},
       {"point_nodes", npz::make_i64({m.handles.point_nodes.size()}, to_i64(m.handles.point_nodes))},
       {"point_vertices", npz::make_i64({m.handles.point_vertices.size()}, to_i64(m.handles.point_vertices))},
       {"cubature_tets", npz::make_i64({m.cubature.tets.size()}, to_i64(m.cubature.tets))},
       {"cubature_weights", npz::make_f64({m.cubature.weights.size()}, m.cubature.weights)},
       {"cubature_method", npz::make_string(m.cubature.method)},
       {"cubature_coverage", npz::make_f64({2}, {m.cubature.stiffness_ratio_min, m.cubature.stiffness_ratio_max})}});
}

/// Reads a cache entry into `m` (handles' bone map is recomputed by the caller). False when stale.
bool load_model(const std::filesystem::path& path, const std::string& key, ReducedModel& m) {
  const npz::Reader reader(path);
  if (reader.read("key").to_string() != key) return false;
  const auto shape = reader.read("shape").to_int64();
  require(shape.size() == 2, "{}: key 'shape' must hold 2 numbers", path.string());
  const auto rows = reader.read("basis_rows").to_int64(), cols = reader.read("basis_cols").to_int64();
  const auto values = reader.read("basis_values").to_doubles();
  require(rows.size() == cols.size() && rows.size() == values.size(), "{}: basis arrays differ in length",
          path.string());
  std::vector<Eigen::Triplet<double>> entries;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    require(rows[k] >= 0 && rows[k] < shape[0] && cols[k] >= 0 && cols[k] < shape[1], "{}: basis entry {} out of range",
            path.string(), k);
    entries.emplace_back(static_cast<int>(rows[k]), static_cast<int>(cols[k]), values[k]);
  }
  m.subspace.basis.resize(shape[0], shape[1]);
  m.subspace.basis.setFromTriplets(entries.begin(), entries.end());
  m.subspace.basis.makeCompressed();
  m.handles.point_nodes = to_int(reader.read("point_nodes").to_int64());
  m.handles.point_vertices = to_int(reader.read("point_vertices").to_int64());
  m.cubature.tets = to_int(reader.read("cubature_tets").to_int64());
  m.cubature.weights = reader.read("cubature_weights").to_doubles();
  m.cubature.method = reader.read("cubature_method").to_string();
  const std::vector<double> coverage = reader.read("cubature_coverage").to_doubles();
  require(coverage.size() == 2, "{}: key 'cubature_coverage' must hold 2 numbers", path.string());
  m.cubature.stiffness_ratio_min = coverage[0];
  m.cubature.stiffness_ratio_max = coverage[1];
  require(m.cubature.tets.size() == m.cubature.weights.size(), "{}: cubature arrays differ in length", path.string());
  return true;
}

int dominant_joint(const std::vector<std::pair<int, double>>& weights) {
  int best = -1;
  double value = -1.0;
  for (const auto& [joint, w] : weights)
    if (w > value) {
      value = w;
      best = joint;
    }
  return best;
}

}  // namespace

HandleSets BodyHandles::sets() const {
  HandleSets s;
  for (int node : point_nodes) s.handle_nodes.push_back({node});
  for (int joint : bone_joints()) {
    std::vector<int> nodes;
    for (std::size_t i = 0; i < bone_of_node.size(); ++i)
      if (bone_of_node[i] == joint) nodes.push_back(static_cast<int>(i));
    s.handle_nodes.push_back(std::move(nodes));
  }
  return s;
}

std::vector<int> BodyHandles::bone_joints() const {
  std::vector<char> used(body::kNumJoints, 0);
  for (int j : bone_of_node)
    if (j >= 0) used[static_cast<std::size_t>(j)] = 1;
  std::vector<int> out;
  for (int j = 0; j < body::kNumJoints; ++j)
    if (used[static_cast<std::size_t>(j)]) out.push_back(j);
  return out;
}

BodyHandles place_body_handles(const model::BodyLayer& layer, int point_handles) {
  const meshing::LayerMesh& mesh = *layer.mesh;
  const int n = mesh.num_nodes();
  BodyHandles h;
  h.bone_of_node.assign(static_cast<std::size_t>(n), -1);
  const std::vector<char> attached = layer.problem.dirichlet.mask(n);
  for (int i = 0; i < n; ++i)
    if (attached[static_cast<std::size_t>(3 * i)])
      h.bone_of_node[static_cast<std::size_t>(i)] = dominant_joint(layer.trajectory->node_weights(i));
  if (point_handles == 0) return h;
  require(point_handles > 0 && point_handles <= max_point_handles(layer),
          "reduced: {} point handles requested; the layer allows 1 to {}", point_handles, max_point_handles(layer));
  // Sites: the material control-point placement (nested, symmetric, denser on the torso), then the free node
  // nearest below each site at mid-depth.
  const std::vector<int> sites = material::layer_control_points(*layer.model, mesh, point_handles);
  const meshing::RowMatrixX3d skin = mesh.skin_positions(mesh.nodes);
  std::vector<char> taken(static_cast<std::size_t>(n), 0);
  // Nodes sharing a tet with the skin's rim are taken last: a handle there drags one ring of skin against
  // the attached rim (the first free ring would carry the whole handle displacement in one edge).
  std::vector<char> by_rim(static_cast<std::size_t>(n), 0);
  {
    std::vector<char> rim(static_cast<std::size_t>(n), 0);
    for (int v : mesh.rim_nodes()) rim[static_cast<std::size_t>(v)] = 1;
    for (Eigen::Index e = 0; e < mesh.tets.rows(); ++e) {
      bool touches = false;
      for (int a = 0; a < 4; ++a) touches = touches || rim[static_cast<std::size_t>(mesh.tets(e, a))];
      if (touches)
        for (int a = 0; a < 4; ++a) by_rim[static_cast<std::size_t>(mesh.tets(e, a))] = 1;
    }
  }
  for (int v : sites) {
    const int r = mesh.region_surface.local_of[static_cast<std::size_t>(v)];
    const Eigen::RowVector3d s = skin.row(r);
    int best = -1;
    double best_d = std::numeric_limits<double>::infinity();
    for (int pass = 0; pass < 3 && best < 0; ++pass) {
      for (int i = 0; i < n; ++i) {
        if (attached[static_cast<std::size_t>(3 * i)] || taken[static_cast<std::size_t>(i)]) continue;
        if (pass < 2 && by_rim[static_cast<std::size_t>(i)]) continue;
        const double depth = layer.depth[i];
        if (pass == 0 && (depth < 0.3 || depth > 0.7))
          continue;  // mid-depth first, any free node, then next to the rim
        const double d = (mesh.nodes.row(i) - s).squaredNorm();
        if (d < best_d) {
          best_d = d;
          best = i;
        }
      }
    }
    require(best >= 0, "reduced: no free node left for point handle {} of {}", h.point_nodes.size(), point_handles);
    taken[static_cast<std::size_t>(best)] = 1;
    h.point_nodes.push_back(best);
    h.point_vertices.push_back(v);
  }
  return h;
}

model::Problem template_problem(const model::BodyLayer& layer) {
  model::Problem p;
  p.rest = layer.mesh->nodes;
  p.tets = layer.mesh->tets;
  material::SkinMaterial m;
  const material::Kappa kappa = material::default_kappa();
  m.young_tangent = kappa.young_tangent;
  m.young_normal = kappa.young_tangent;  // isotropic: the fit must not depend on per-subject normals
  m.poisson = layer.material.poisson;
  m.saturation = layer.material.saturation;
  p.tet_material.assign(static_cast<std::size_t>(p.num_tets()),
                        material::make_orthotropic_fung(m, Eigen::Vector3d::UnitZ()));
  p.dirichlet = layer.problem.dirichlet;
  p.mass = model::lumped_masses(p.rest, p.tets, layer.problem.density > 0 ? layer.problem.density : 1000.0);
  p.validate();
  return p;
}

Cubature cubature_outside(const model::BodyLayer& layer, const Subspace& subspace, const ReducedModelOptions& requested,
                          const std::vector<int>& excluded) {
  const meshing::LayerMesh& mesh = *layer.mesh;
  std::vector<char> out(static_cast<std::size_t>(mesh.num_tets()), 0);
  for (int e : excluded) {
    require(e >= 0 && e < mesh.num_tets(), "reduced: excluded tet {} is not a tet of the layer", e);
    out[static_cast<std::size_t>(e)] = 1;
  }
  std::vector<int> kept;  // the problem's tet k is the layer's tet kept[k]
  for (int e = 0; e < mesh.num_tets(); ++e)
    if (!out[static_cast<std::size_t>(e)]) kept.push_back(e);
  Cubature c;
  if (requested.cubature == 0 || kept.empty()) {
    c.tets = kept;
    c.weights.assign(kept.size(), 1.0);
    c.stiffness_ratio_max = c.stiffness_ratio_min = 1.0;
    return c;
  }
  model::Problem full = template_problem(layer);
  model::Problem p;
  p.rest = full.rest;
  p.tets.resize(static_cast<Eigen::Index>(kept.size()), 4);
  CubatureOptions co;
  co.count = std::min(resolved_cubature_count(requested), static_cast<int>(kept.size()));
  co.weighting = requested.weighting;
  for (std::size_t k = 0; k < kept.size(); ++k) {
    p.tets.row(static_cast<Eigen::Index>(k)) = full.tets.row(kept[k]);
    p.tet_material.push_back(full.tet_material[static_cast<std::size_t>(kept[k])]);
    co.density.push_back(
        mesh.tet_part[static_cast<std::size_t>(kept[k])] == meshing::Part::torso ? material::kTorsoDensity : 1.0);
  }
  p.dirichlet = full.dirichlet;
  p.mass = model::lumped_masses(p.rest, p.tets, layer.problem.density > 0 ? layer.problem.density : 1000.0);
  p.validate();
  c = requested.cubature == -1 ? select_covering_cubature(p, subspace, co, requested.coverage_ratio)
                               : select_cubature(p, subspace, co);
  for (int& t : c.tets) t = kept[static_cast<std::size_t>(t)];
  return c;
}

int max_point_handles(const model::BodyLayer& layer) { return layer.mesh->region_surface.num_vertices() / 4; }

int resolved_cubature_count(const ReducedModelOptions& options) {
  if (options.cubature >= 0) return options.cubature;
  const int coordinates = options.point_handles * (options.basis.affine ? 12 : 3);
  return std::max(200, static_cast<int>(std::ceil(0.8 * coordinates)));
}

ReducedModel build_reduced_model(const model::BodyLayer& layer, const ReducedModelOptions& requested) {
  const auto start = std::chrono::steady_clock::now();
  const meshing::LayerMesh& mesh = *layer.mesh;
  require(requested.point_handles > 0 && requested.point_handles <= max_point_handles(layer),
          "reduced: {} point handles requested; the layer allows 1 to {}", requested.point_handles,
          max_point_handles(layer));
  ReducedModelOptions options = requested;
  options.cubature = std::min(resolved_cubature_count(requested), mesh.num_tets());
  options.cubature_auto = requested.cubature == -1;
  const int coordinates = options.point_handles * (options.basis.affine ? 12 : 3);
  if (options.cubature > 0 && options.cubature < 0.75 * coordinates)
    logger()->warn(
        "reduced: {} cubature tets for {} coordinates: below ≈ 0.75 per coordinate unsampled tets can leave the "
        "material's range (docs/reduced.md)",
        options.cubature, coordinates);
  require(requested.cubature >= -1 && requested.cubature <= mesh.num_tets(),
          "reduced: --cubature {} must be between 0 (exact) and {} tets, or −1 (auto)", requested.cubature,
          mesh.num_tets());
  ReducedModel m;
  m.cache_key = cache_key(mesh, layer.problem.dirichlet, options);
  const std::filesystem::path dir = options.cache_dir.empty() ? meshing::default_cache_dir() : options.cache_dir;
  const std::filesystem::path path = cache_file(dir, m.cache_key);
  bool loaded = false;
  if (options.use_cache && std::filesystem::exists(path)) {
    try {
      loaded = load_model(path, m.cache_key, m);
      if (!loaded) logger()->info("reduced: cache entry {} is stale; rebuilding", path.string());
    } catch (const Error& e) {
      logger()->warn("reduced: cache entry unreadable ({}); rebuilding", e.what());
    }
  }
  if (loaded) {
    require(m.subspace.num_nodes() == mesh.num_nodes(), "reduced: cache entry {} has {} nodes, the mesh {}",
            path.string(), m.subspace.num_nodes(), mesh.num_nodes());
    const BodyHandles placed = place_body_handles(layer, 0);  // bone map only (cheap)
    m.handles.bone_of_node = placed.bone_of_node;
    m.cache_outcome = "hit";
  } else {
    m.handles = place_body_handles(layer, options.point_handles);
    const Eigen::MatrixXd weights =
        handle_weights(mesh.nodes, mesh.tets, m.handles.sets(), static_cast<int>(m.handles.point_nodes.size()));
    const std::vector<char> mask = layer.problem.dirichlet.mask(mesh.num_nodes());
    std::vector<char> attached(static_cast<std::size_t>(mesh.num_nodes()));
    for (int i = 0; i < mesh.num_nodes(); ++i)
      attached[static_cast<std::size_t>(i)] = mask[static_cast<std::size_t>(3 * i)];
    m.subspace = point_handle_subspace(weights, attached, mesh.nodes, m.handles.point_nodes, options.basis);
    if (options.cubature == 0) {
      m.cubature = exact_cubature(mesh.num_tets());
      m.cubature.stiffness_ratio_max = m.cubature.stiffness_ratio_min = 1.0;
    } else {
      CubatureOptions co;
      co.count = options.cubature;
      co.weighting = options.weighting;
      co.density.resize(static_cast<std::size_t>(mesh.num_tets()));
      for (int e = 0; e < mesh.num_tets(); ++e)
        co.density[static_cast<std::size_t>(e)] =
            mesh.tet_part[static_cast<std::size_t>(e)] == meshing::Part::torso ? material::kTorsoDensity : 1.0;
      const model::Problem problem = template_problem(layer);
      if (options.cubature_auto) {
        m.cubature = select_covering_cubature(problem, m.subspace, co, options.coverage_ratio);
      } else {
        m.cubature = select_cubature(problem, m.subspace, co);
        const CubatureCoverage coverage =
            cubature_coverage(rest_stiffness(problem, m.subspace, exact_cubature(problem.num_tets())),
                              rest_stiffness(problem, m.subspace, m.cubature));
        m.cubature.stiffness_ratio_max = coverage.max_ratio;
        m.cubature.stiffness_ratio_min = coverage.min_ratio;
      }
    }
    m.cache_outcome = options.use_cache ? "built" : "off";
    if (options.use_cache) {
      try {
        std::filesystem::create_directories(dir);
        remove_stale_temporaries(path);  // left by writers killed before their rename
        save_model(path, m);
      } catch (const std::exception& e) {
        logger()->warn("reduced: could not write the cache entry {} ({})", path.string(), e.what());
      }
    }
  }
  m.build_seconds = seconds_since(start);
  logger()->info(
      "reduced model: {} point handles ({} coordinates), {} bone handles, {} cubature tets ({}; exact / cubature rest "
      "stiffness in [{:.3g}, {:.3g}]), cache {}, {:.2f} s",
      m.handles.point_nodes.size(), m.subspace.num_dofs(), m.handles.bone_joints().size(), m.cubature.size(),
      m.cubature.method, m.cubature.stiffness_ratio_min, m.cubature.stiffness_ratio_max, m.cache_outcome,
      m.build_seconds);
  if (!options.cubature_auto && m.cubature.stiffness_ratio_max > options.coverage_ratio)
    logger()->warn(
        "reduced: with {} cubature tets a direction of the subspace is {:.3g}× stiffer than the cubature sees (auto "
        "cubature grows until ≤ {}); tets outside the set are guarded while solving (docs/reduced.md)",
        m.cubature.size(), m.cubature.stiffness_ratio_max, options.coverage_ratio);
  return m;
}

}  // namespace sflsh::reduced
