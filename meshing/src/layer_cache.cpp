// The on-disk cache of template layer meshes.
#include "layered_mesh.hpp"

#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/npz.hpp>
#include <sflsh/meshing/layer_cache.hpp>

#include <fmt/format.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>

namespace sflsh::meshing {
namespace {

// FNV-1a over raw bytes: stable across runs and platforms of the same endianness.
struct Fnv {
  std::uint64_t hash = 1469598103934665603ULL;
  void add(const void* data, std::size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) {
      hash ^= bytes[i];
      hash *= 1099511628211ULL;
    }
  }
  template <typename Matrix>
  void add_matrix(const Matrix& m) {
    const Eigen::Index rows = m.rows(), cols = m.cols();
    add(&rows, sizeof rows);
    add(&cols, sizeof cols);
    for (Eigen::Index i = 0; i < rows; ++i)
      for (Eigen::Index j = 0; j < cols; ++j) {
        const auto value = m(i, j);
        add(&value, sizeof value);
      }
  }
};

std::vector<std::size_t> shape2(Eigen::Index rows, Eigen::Index cols) {
  return {static_cast<std::size_t>(rows), static_cast<std::size_t>(cols)};
}

template <typename Vector>
npz::Array ints(const Vector& values) {
  std::vector<std::int64_t> data;
  for (const auto& v : values) data.push_back(static_cast<std::int64_t>(v));
  return npz::make_i64({data.size()}, data);
}

npz::Array int_matrix(const Eigen::Ref<const Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>& m) {
  std::vector<std::int64_t> data(m.data(), m.data() + m.size());
  return npz::make_i64(shape2(m.rows(), m.cols()), data);
}

// Reading with shape checks: every failure names the file and the array.
class Loader {
 public:
  explicit Loader(const std::filesystem::path& path) : reader_(path), path_(path) {}
  npz::Array get(const std::string& key, std::size_t rank, std::size_t cols = 0) const {
    require(reader_.has(key), "{}: corrupt layer mesh cache: array '{}' is missing", path_.string(), key);
    npz::Array array = reader_.read(key);
    require(array.shape.size() == rank && (cols == 0 || array.shape.back() == cols),
            "{}: corrupt layer mesh cache: array '{}' has shape {}, expected rank {}{}", path_.string(), key,
            array.shape_string(), rank, cols ? fmt::format(" with {} columns", cols) : "");
    return array;
  }
  std::string text(const std::string& key) const { return reader_.read(key).to_string(); }
  std::vector<std::int64_t> ints(const std::string& key, std::size_t expected) const {
    auto values = get(key, 1).to_int64();
    require(expected == 0 || values.size() == expected,
            "{}: corrupt layer mesh cache: array '{}' has {} entries, expected {}", path_.string(), key, values.size(),
            expected);
    return values;
  }
  double scalar(const std::string& key) const {
    require(reader_.has(key), "{}: corrupt layer mesh cache: value '{}' is missing", path_.string(), key);
    const auto values = reader_.read(key).to_doubles();
    require(values.size() == 1, "{}: corrupt layer mesh cache: '{}' is not a scalar", path_.string(), key);
    return values[0];
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  npz::Reader reader_;
  std::filesystem::path path_;
};

void check_index(const Loader& loader, const char* what, std::int64_t value, std::int64_t bound) {
  require(value >= 0 && value < bound, "{}: corrupt layer mesh cache: {} index {} outside [0, {})",
          loader.path().string(), what, value, bound);
}

}  // namespace

std::string body_fingerprint(const body::BodyModel& model) {
  Fnv fnv;
  fnv.add_matrix(model.v_template);
  fnv.add_matrix(model.faces);
  fnv.add_matrix(model.weights);
  fnv.add_matrix(model.shapedirs.leftCols(std::min<Eigen::Index>(model.shapedirs.cols(), body::kNumBetas)));
  fnv.add_matrix(Eigen::MatrixXd(model.joint_regressor));
  return fmt::format("{:016x}", fnv.hash);
}

namespace {

/// A layered mesh with a prism-layer count other than its size preset's.
bool explicit_layers(const LayerMeshOptions& options) {
  return options.mesher == Mesher::layered && options.layers > 0 &&
         options.layers != detail::layered_layers(options.size);
}

}  // namespace

std::string layer_cache_key(const body::BodyModel& model, const LayerMeshOptions& options) {
  const auto names = options.region_names.empty() ? default_region_names() : options.region_names;
  // An explicit prism-layer count (layered only) joins the key; the presets' keys stay as they were.
  const std::string layers = explicit_layers(options) ? fmt::format(" layers={}", options.layers) : std::string();
  return fmt::format("body={} format={} region={} mesher={} size={} h={:.6f}{}", body_fingerprint(model),
                     kLayerMeshFormat, region_key(names), mesher_name(options.mesher), size_preset_name(options.size),
                     options.template_thickness, layers);
}

std::filesystem::path default_cache_dir() {
  if (const char* dir = std::getenv("SFLSH_CACHE"); dir && *dir) return dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::filesystem::path(xdg) / "sflsh";
  if (const char* home = std::getenv("HOME"); home && *home) return std::filesystem::path(home) / ".cache" / "sflsh";
  return std::filesystem::temp_directory_path() / "sflsh-cache";
}

std::filesystem::path layer_cache_path(const std::filesystem::path& dir, const body::BodyModel& model,
                                       const LayerMeshOptions& options) {
  std::string body_name = model.name.empty() ? "body" : model.name;
  for (char& c : body_name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
  const auto names = options.region_names.empty() ? default_region_names() : options.region_names;
  const std::string layers = explicit_layers(options) ? fmt::format("-L{}", options.layers) : std::string();
  return dir / fmt::format("layer-{}-{}-{}-{}{}-h{:.3f}.npz", body_name, region_key(names), mesher_name(options.mesher),
                           size_preset_name(options.size), layers, options.template_thickness);
}

void save_layer_mesh(const std::filesystem::path& path, const LayerMesh& mesh, const std::string& key) {
  const Region& region = mesh.region_surface;
  std::vector<std::int64_t> loop_sizes, loop_vertices;
  for (const auto& loop : region.boundary_loops) {
    loop_sizes.push_back(static_cast<std::int64_t>(loop.size()));
    loop_vertices.insert(loop_vertices.end(), loop.begin(), loop.end());
  }
  std::string names;
  for (const auto& n : region.names) names += (names.empty() ? "" : ",") + n;
  const int n = mesh.num_nodes();
  Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor> anchor_vertex(n, 3);
  Eigen::MatrixXd anchor_weight(n, 3), skin_bary(region.num_vertices(), 4);
  Eigen::VectorXd anchor_depth(n);
  for (int i = 0; i < n; ++i) {
    const auto& a = mesh.anchor[static_cast<std::size_t>(i)];
    for (int k = 0; k < 3; ++k) anchor_vertex(i, k) = a.vertex[k];
    anchor_weight.row(i) = a.weight.transpose();
    anchor_depth(i) = a.depth;
  }
  for (int v = 0; v < region.num_vertices(); ++v)
    skin_bary.row(v) = mesh.skin.bary[static_cast<std::size_t>(v)].transpose();
  std::vector<int> kind, node_part, tet_part, part;
  for (auto k : mesh.kind) kind.push_back(static_cast<int>(k));
  for (auto p : mesh.node_part) node_part.push_back(static_cast<int>(p));
  for (auto p : mesh.tet_part) tet_part.push_back(static_cast<int>(p));
  for (auto p : region.part) part.push_back(static_cast<int>(p));

  npz::write(path,
             {
                 {"key", npz::make_string(key)},
                 {"body_name", npz::make_string(mesh.body_name)},
                 {"region", npz::make_string(mesh.region)},
                 {"region_names", npz::make_string(names)},
                 {"mesher", npz::make_string(mesher_name(mesh.mesher))},
                 {"size", npz::make_string(size_preset_name(mesh.size))},
                 {"template_thickness", npz::make_scalar(mesh.template_thickness)},
                 {"edge_length", npz::make_scalar(mesh.edge_length)},
                 {"meshing_seconds", npz::make_scalar(mesh.meshing_seconds)},
                 {"body_vertices", npz::make_scalar(static_cast<double>(region.local_of.size()))},
                 {"region_vertices", ints(region.vertices)},
                 {"region_faces", int_matrix(region.faces)},
                 {"region_body_faces", ints(region.body_faces)},
                 {"region_part", ints(part)},
                 {"loop_sizes", ints(loop_sizes)},
                 {"loop_vertices", ints(loop_vertices)},
                 {"correspondence", npz::make_f64(Eigen::MatrixXd(mesh.correspondence.joint_weights))},
                 {"nodes", npz::make_f64(Eigen::MatrixXd(mesh.nodes))},
                 {"tets", int_matrix(mesh.tets)},
                 {"kind", ints(kind)},
                 {"anchor_vertex", int_matrix(anchor_vertex)},
                 {"anchor_weight", npz::make_f64(anchor_weight)},
                 {"anchor_depth", npz::make_f64({static_cast<std::size_t>(n)},
                                                std::vector<double>(anchor_depth.data(), anchor_depth.data() + n))},
                 {"node_part", ints(node_part)},
                 {"tet_part", ints(tet_part)},
                 {"skin_node", ints(mesh.skin.node)},
                 {"skin_tet", ints(mesh.skin.tet)},
                 {"skin_bary", npz::make_f64(skin_bary)},
             });
}

namespace {

// How many nodes and tets the cached volume mesh has.
struct CacheVolumeSize {
  std::int64_t nodes = 0;
  std::size_t tets = 0;
};

// Reads the cache's key (when asked for) and the mesh's descriptive fields; returns the body's vertex count.
std::int64_t cache_read_metadata(const Loader& in, LayerMesh& mesh, std::string* key) {
  if (key) *key = in.text("key");
  mesh.body_name = in.text("body_name");
  mesh.region = in.text("region");
  mesh.mesher = parse_mesher(in.text("mesher"));
  mesh.size = parse_size_preset(in.text("size"));
  mesh.template_thickness = in.scalar("template_thickness");
  mesh.edge_length = in.scalar("edge_length");
  mesh.meshing_seconds = in.scalar("meshing_seconds");
  return static_cast<std::int64_t>(in.scalar("body_vertices"));
}

// Reads the region's names, vertices, faces, body faces and parts, checking every index.
void cache_read_region_surface(const Loader& in, Region& region, std::int64_t body_vertices) {
  region.names = parse_region_names(in.text("region_names"));
  for (auto v : in.ints("region_vertices", 0)) {
    check_index(in, "region vertex", v, body_vertices);
    region.vertices.push_back(static_cast<int>(v));
  }
  const auto count = static_cast<std::int64_t>(region.vertices.size());
  region.local_of.assign(static_cast<std::size_t>(body_vertices), -1);
  for (std::size_t i = 0; i < region.vertices.size(); ++i)
    region.local_of[static_cast<std::size_t>(region.vertices[i])] = static_cast<int>(i);
  const auto faces = in.get("region_faces", 2, 3);
  const auto face_values = faces.to_int64();
  region.faces.resize(static_cast<Eigen::Index>(faces.shape[0]), 3);
  for (std::size_t i = 0; i < face_values.size(); ++i) {
    check_index(in, "region face vertex", face_values[i], count);
    region.faces.data()[i] = static_cast<int>(face_values[i]);
  }
  for (auto f : in.ints("region_body_faces", faces.shape[0])) region.body_faces.push_back(static_cast<int>(f));
  for (auto p : in.ints("region_part", static_cast<std::size_t>(count))) {
    check_index(in, "part", p, kNumParts);
    region.part.push_back(static_cast<Part>(p));
  }
}

// Reads the region's boundary loops, stored as their sizes and their concatenated local vertices.
void cache_read_boundary_loops(const Loader& in, Region& region, std::int64_t count) {
  const auto loop_vertices = in.ints("loop_vertices", 0);
  std::size_t offset = 0;
  for (auto size : in.ints("loop_sizes", 0)) {
    require(size > 0 && offset + static_cast<std::size_t>(size) <= loop_vertices.size(),
            "{}: corrupt layer mesh cache: boundary loop sizes do not match 'loop_vertices'", in.path().string());
    std::vector<int> loop;
    for (std::int64_t k = 0; k < size; ++k) {
      check_index(in, "loop vertex", loop_vertices[offset], count);
      loop.push_back(static_cast<int>(loop_vertices[offset++]));
    }
    region.boundary_loops.push_back(std::move(loop));
  }
}

// Reads the joint weights of the `count` region vertices.
void cache_read_correspondence(const Loader& in, LayerMesh& mesh, std::int64_t count) {
  const auto correspondence = in.get("correspondence", 2, body::kNumJoints);
  require(static_cast<std::int64_t>(correspondence.shape[0]) == count,
          "{}: corrupt layer mesh cache: 'correspondence' has {} rows, expected {}", in.path().string(),
          correspondence.shape[0], count);
  const auto c = correspondence.to_doubles();
  mesh.correspondence.joint_weights =
      Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(c.data(), count,
                                                                                               body::kNumJoints)
          .sparseView(1e-12);
}

// Reads the volume mesh's nodes, tets and node kinds.
CacheVolumeSize cache_read_volume(const Loader& in, LayerMesh& mesh) {
  const auto nodes = in.get("nodes", 2, 3);
  const auto n = static_cast<std::int64_t>(nodes.shape[0]);
  const auto node_values = nodes.to_doubles();
  mesh.nodes = Eigen::Map<const RowMatrixX3d>(node_values.data(), n, 3);
  require(mesh.nodes.allFinite(), "{}: corrupt layer mesh cache: 'nodes' has non-finite values", in.path().string());
  const auto tets = in.get("tets", 2, 4);
  const auto tet_values = tets.to_int64();
  mesh.tets.resize(static_cast<Eigen::Index>(tets.shape[0]), 4);
  for (std::size_t i = 0; i < tet_values.size(); ++i) {
    check_index(in, "tet node", tet_values[i], n);
    mesh.tets.data()[i] = static_cast<int>(tet_values[i]);
  }
  for (auto k : in.ints("kind", static_cast<std::size_t>(n))) {
    check_index(in, "node kind", k, 4);
    mesh.kind.push_back(static_cast<NodeKind>(k));
  }
  return {n, tets.shape[0]};
}

// Reads each node's anchor on the region surface; every boundary node must have one.
void cache_read_anchors(const Loader& in, LayerMesh& mesh, std::int64_t n, std::int64_t count) {
  const auto anchor_vertex = in.get("anchor_vertex", 2, 3).to_int64();
  const auto anchor_weight = in.get("anchor_weight", 2, 3).to_doubles();
  const auto anchor_depth = in.get("anchor_depth", 1).to_doubles();
  require(anchor_vertex.size() == static_cast<std::size_t>(3 * n) && anchor_weight.size() == anchor_vertex.size() &&
              anchor_depth.size() == static_cast<std::size_t>(n),
          "{}: corrupt layer mesh cache: anchor arrays do not have one row per node", in.path().string());
  mesh.anchor.resize(static_cast<std::size_t>(n));
  for (std::int64_t i = 0; i < n; ++i) {
    auto& a = mesh.anchor[static_cast<std::size_t>(i)];
    for (int k = 0; k < 3; ++k) {
      const auto v = anchor_vertex[static_cast<std::size_t>(3 * i + k)];
      if (v >= 0) check_index(in, "anchor vertex", v, count);
      a.vertex[k] = static_cast<int>(v);
      a.weight(k) = anchor_weight[static_cast<std::size_t>(3 * i + k)];
    }
    a.depth = anchor_depth[static_cast<std::size_t>(i)];
    require(a.valid() || mesh.kind[static_cast<std::size_t>(i)] == NodeKind::interior,
            "{}: corrupt layer mesh cache: boundary node {} has no anchor", in.path().string(), i);
  }
}

// Reads the body part of each node and of each tet.
void cache_read_parts(const Loader& in, LayerMesh& mesh, const CacheVolumeSize& volume) {
  for (auto p : in.ints("node_part", static_cast<std::size_t>(volume.nodes))) {
    check_index(in, "node part", p, kNumParts);
    mesh.node_part.push_back(static_cast<Part>(p));
  }
  for (auto p : in.ints("tet_part", volume.tets)) {
    check_index(in, "tet part", p, kNumParts);
    mesh.tet_part.push_back(static_cast<Part>(p));
  }
}

// Reads the embedding of the `count` region vertices in the volume mesh (node, tet, barycentric coordinates).
void cache_read_skin(const Loader& in, LayerMesh& mesh, const CacheVolumeSize& volume, std::int64_t count) {
  for (auto v : in.ints("skin_node", static_cast<std::size_t>(count))) {
    if (v >= 0) check_index(in, "skin node", v, volume.nodes);
    mesh.skin.node.push_back(static_cast<int>(v));
  }
  for (auto t : in.ints("skin_tet", static_cast<std::size_t>(count))) {
    check_index(in, "skin tet", t, static_cast<std::int64_t>(volume.tets));
    mesh.skin.tet.push_back(static_cast<int>(t));
  }
  const auto bary = in.get("skin_bary", 2, 4).to_doubles();
  require(bary.size() == static_cast<std::size_t>(4 * count), "{}: corrupt layer mesh cache: 'skin_bary' rows",
          in.path().string());
  for (std::int64_t v = 0; v < count; ++v)
    mesh.skin.bary.emplace_back(bary[static_cast<std::size_t>(4 * v)], bary[static_cast<std::size_t>(4 * v + 1)],
                                bary[static_cast<std::size_t>(4 * v + 2)], bary[static_cast<std::size_t>(4 * v + 3)]);
}

}  // namespace

LayerMesh load_layer_mesh(const std::filesystem::path& path, std::string* key) {
  const Loader in(path);
  LayerMesh mesh;
  const std::int64_t body_vertices = cache_read_metadata(in, mesh, key);

  Region& region = mesh.region_surface;
  cache_read_region_surface(in, region, body_vertices);
  const auto count = static_cast<std::int64_t>(region.vertices.size());
  cache_read_boundary_loops(in, region, count);

  cache_read_correspondence(in, mesh, count);

  const CacheVolumeSize volume = cache_read_volume(in, mesh);
  cache_read_anchors(in, mesh, volume.nodes, count);
  cache_read_parts(in, mesh, volume);
  cache_read_skin(in, mesh, volume, count);
  return mesh;
}

const char* cache_outcome_name(CacheOutcome outcome) {
  switch (outcome) {
    case CacheOutcome::hit:
      return "hit";
    case CacheOutcome::built:
      return "built";
    case CacheOutcome::rebuilt_stale:
      return "rebuilt_stale";
    case CacheOutcome::rebuilt_forced:
      return "rebuilt_forced";
  }
  return "built";
}

LayerMesh cached_layer_mesh(const body::BodyModel& model, const LayerMeshOptions& options,
                            const std::filesystem::path& dir, bool rebuild, CacheOutcome* outcome) {
  const std::filesystem::path path = layer_cache_path(dir, model, options);
  const std::string key = layer_cache_key(model, options);
  CacheOutcome result = rebuild ? CacheOutcome::rebuilt_forced : CacheOutcome::built;
  if (const int stale = remove_stale_temporaries(path); stale > 0)  // writers killed before their rename
    logger()->info("layer mesh cache {}: removed {} temporary file(s) of killed writers", path.string(), stale);
  if (!rebuild && std::filesystem::exists(path)) {
    std::string stored;
    LayerMesh mesh;
    try {
      mesh = load_layer_mesh(path, &stored);
    } catch (const Error& e) {
      throw_error("{} (delete the file or pass --rebuild-cache)", e.what());
    }
    if (stored == key) {
      if (outcome) *outcome = CacheOutcome::hit;
      logger()->info("layer mesh from cache {}", path.string());
      return mesh;
    }
    logger()->warn("layer mesh cache {} is stale (stored key '{}', expected '{}'): rebuilding", path.string(), stored,
                   key);
    result = CacheOutcome::rebuilt_stale;
  }
  LayerMesh mesh = build_layer_mesh(model, options);
  ensure_directory(dir);
  save_layer_mesh(path, mesh, key);
  if (outcome) *outcome = result;
  return mesh;
}

}  // namespace sflsh::meshing
