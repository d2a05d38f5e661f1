// gmsh ASCII .msh 2.2 / 4.1 reading and writing (msh_reader.hpp; the structured box mesh is in box_mesh.cpp).
// The format references are gmsh's manual, "MSH file format" (4.1) and "Legacy formats" (2.2).
#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/fullspace/msh_reader.hpp>

#include <Eigen/LU>
#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string_view>
#include <unordered_map>
#include <utility>

namespace sflsh::fullspace {

namespace {

/// Nodes per element and dimension of the gmsh element types 1 … 19 (gmsh's GmshDefines.h): lines (1, 8),
/// triangles (2, 9), quadrangles (3, 10, 16), tets (4, 11), hexahedra (5, 12, 17), prisms (6, 13, 18),
/// pyramids (7, 14, 19) and the point (15). Other types: nodes = 0.
struct ElementType {
  int nodes = 0;
  int dim = -1;
};
ElementType element_type(long long type) {
  constexpr ElementType kTypes[20] = {{},      {2, 1}, {3, 2}, {4, 2},  {4, 3},  {8, 3},  {6, 3},
                                      {5, 3},  {3, 1}, {6, 2}, {9, 2},  {10, 3}, {27, 3}, {18, 3},
                                      {14, 3}, {1, 0}, {8, 2}, {20, 3}, {15, 3}, {13, 3}};
  return type >= 1 && type < 20 ? kTypes[type] : ElementType{};
}

bool to_int(std::string_view s, long long& out) {
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && end == s.data() + s.size();
}

bool to_double(std::string_view s, double& out) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && end == s.data() + s.size() && std::isfinite(out);
}

/// The lines of a .msh file with their numbers, split into tokens, and errors that name file, line, section.
class MshLines {
 public:
  explicit MshLines(const std::filesystem::path& path) : path_(path) {
    std::ifstream in(path, std::ios::binary);
    require(in.good(), "{}: cannot open the mesh file", path.string());
    text_.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }

  /// Advances to the next non-blank line; false at the end of the file.
  bool next() {
    while (pos_ < text_.size()) {
      const std::size_t end = std::min(text_.find('\n', pos_), text_.size());
      line_ = std::string_view(text_).substr(pos_, end - pos_);
      pos_ = end + 1;
      ++number_;
      while (!line_.empty() && (line_.back() == '\r' || line_.back() == ' ' || line_.back() == '\t'))
        line_.remove_suffix(1);
      while (!line_.empty() && (line_.front() == ' ' || line_.front() == '\t')) line_.remove_prefix(1);
      if (line_.empty()) continue;
      tokens_.clear();
      std::size_t i = 0;
      while (i < line_.size()) {
        while (i < line_.size() && (line_[i] == ' ' || line_[i] == '\t')) ++i;
        std::size_t j = i;
        while (j < line_.size() && line_[j] != ' ' && line_[j] != '\t') ++j;
        if (j > i) tokens_.push_back(line_.substr(i, j - i));
        i = j;
      }
      return true;
    }
    line_ = {};
    tokens_.clear();
    return false;
  }

  /// Like next(), but the end of the file is an error.
  void need(std::string_view what) {
    if (!next()) fail_at_end(what);
  }

  std::string_view line() const { return line_; }
  const std::vector<std::string_view>& tokens() const { return tokens_; }
  int number() const { return number_; }
  void set_section(std::string_view section) { section_ = section; }

  /// The current line, shortened for messages.
  std::string quoted() const {
    return line_.size() <= 60 ? std::string(line_) : std::string(line_.substr(0, 57)) + "...";
  }

  template <typename... Args>
  [[noreturn]] void fail(fmt::format_string<Args...> format, Args&&... args) const {
    throw_error("{}:{}: {}: {}", path_.string(), number_, section_, fmt::format(format, std::forward<Args>(args)...));
  }

  [[noreturn]] void fail_at_end(std::string_view what) const {
    throw_error("{}:{}: {}: the file ends early (expected {})", path_.string(), number_, section_, what);
  }

  /// Parses every token of the current line as an integer; `what` names the expected line contents.
  const std::vector<long long>& ints(std::size_t count, std::string_view what, bool at_least = false) {
    ints_.resize(tokens_.size());
    bool ok = at_least ? tokens_.size() >= count : tokens_.size() == count;
    for (std::size_t k = 0; ok && k < tokens_.size(); ++k) ok = to_int(tokens_[k], ints_[k]);
    if (!ok) fail("expected {}, got '{}'", what, quoted());
    return ints_;
  }

  /// Reads the next line as exactly `count` integers.
  const std::vector<long long>& next_ints(std::size_t count, std::string_view what, bool at_least = false) {
    need(what);
    return ints(count, what, at_least);
  }

  /// A non-negative count that fits an int and that the rest of the file can hold: every counted entry takes
  /// at least a character and a line break, so a header announcing more cannot be true. Reading never
  /// reserves or loops on a count the file does not back (memory and time stay bounded by the file's size).
  int count(long long value, std::string_view what) const {
    if (value < 0 || value > 2'000'000'000) fail("{} = {} is not a valid count", what, value);
    const std::size_t rest = pos_ < text_.size() ? text_.size() - pos_ : 0;
    if (static_cast<std::size_t>(value) > rest / 2)
      fail("{} = {} is more than the rest of the file ({} bytes) can hold", what, value, rest);
    return static_cast<int>(value);
  }

  /// Reads the closing "$End<name>" line.
  void end_section(std::string_view name) {
    const std::string end = fmt::format("$End{}", name);
    need(end);
    if (line_ != end) fail("expected {}, got '{}'", end, quoted());
  }

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  std::string text_;
  std::size_t pos_ = 0;
  int number_ = 0;
  std::string_view line_;
  std::string_view section_ = "(top level)";
  std::vector<std::string_view> tokens_;
  std::vector<long long> ints_;
};

using DimTag = std::pair<int, long long>;

/// Everything read from the file before groups are named and tets are checked.
struct RawMesh {
  MshVersion version = MshVersion::v41;
  std::vector<Eigen::Vector3d> nodes;
  std::unordered_map<long long, int> node_index;              // node tag → 0-based index
  std::map<DimTag, std::string> physical_names;               // (dim, physical tag) → name
  std::map<DimTag, std::vector<long long>> entity_physicals;  // 4.1: (dim, entity tag) → physical tags
  std::map<DimTag, std::vector<int>> entity_nodes;            // 4.1: (dim, entity tag) → element nodes
  std::map<DimTag, std::vector<int>> physical_nodes;          // 2.2: (dim, physical tag) → element nodes
  std::vector<std::array<int, 4>> tets;
  std::vector<int> tet_lines;
};

void read_format(MshLines& in, RawMesh& raw) {
  in.need("the format line 'version file-type data-size'");
  const auto& t = in.tokens();
  if (t.size() != 3) in.fail("expected 'version file-type data-size', got '{}'", in.quoted());
  if (t[1] == "1") in.fail("binary .msh not supported, save as ASCII (gmsh: Mesh.Binary = 0)");
  if (t[1] != "0") in.fail("file-type must be 0 (ASCII), got '{}'", t[1]);
  if (t[0] == "2.2") {
    raw.version = MshVersion::v22;
  } else if (t[0] == "4.1") {
    raw.version = MshVersion::v41;
  } else {
    in.fail("format version {} is not supported (supported: 2.2 and 4.1; gmsh: Mesh.MshFileVersion = 4.1)", t[0]);
  }
  in.end_section("MeshFormat");
}

void read_physical_names(MshLines& in, RawMesh& raw) {
  const int n = in.count(in.next_ints(1, "the number of physical names")[0], "number of physical names");
  for (int k = 0; k < n; ++k) {
    in.need("'dim tag \"name\"'");
    const auto& t = in.tokens();
    long long dim = 0, tag = 0;
    const std::size_t open = in.line().find('"');
    if (t.size() < 3 || !to_int(t[0], dim) || !to_int(t[1], tag) || dim < 0 || dim > 3 ||
        open == std::string_view::npos || in.line().size() < open + 2 || in.line().back() != '"') {
      in.fail("expected 'dim tag \"name\"' with dim 0…3, got '{}'", in.quoted());
    }
    const std::string_view name = in.line().substr(open + 1, in.line().size() - open - 2);
    raw.physical_names[{static_cast<int>(dim), tag}] = std::string(name);
  }
  in.end_section("PhysicalNames");
}

void read_entities(MshLines& in, RawMesh& raw) {
  const auto counts = in.next_ints(4, "'numPoints numCurves numSurfaces numVolumes'");
  const std::array<long long, 4> n{counts[0], counts[1], counts[2], counts[3]};
  for (int dim = 0; dim < 4; ++dim) {
    for (long long k = 0, m = in.count(n[dim], "entity count"); k < m; ++k) {
      const std::string_view what =
          dim == 0 ? "'tag x y z numPhysicalTags physicalTag…'"
                   : "'tag minX minY minZ maxX maxY maxZ numPhysicalTags physicalTag… numBounding tag…'";
      in.need(what);
      const auto& t = in.tokens();
      const std::size_t coords = dim == 0 ? 3 : 6;
      long long tag = 0, num_physical = 0;
      bool ok = t.size() >= coords + 2 && to_int(t[0], tag) && to_int(t[coords + 1], num_physical) &&
                num_physical >= 0 && t.size() >= coords + 2 + static_cast<std::size_t>(num_physical);
      for (std::size_t c = 1; ok && c <= coords; ++c) {
        double value = 0.0;
        ok = to_double(t[c], value);
      }
      std::vector<long long> physicals(ok ? static_cast<std::size_t>(num_physical) : 0);
      for (std::size_t p = 0; ok && p < physicals.size(); ++p) ok = to_int(t[coords + 2 + p], physicals[p]);
      if (ok && dim > 0) {  // the bounding entities: a count and that many (signed) tags
        const std::size_t at = coords + 2 + physicals.size();
        long long num_bounding = 0;
        ok = t.size() > at && to_int(t[at], num_bounding) && num_bounding >= 0 &&
             t.size() == at + 1 + static_cast<std::size_t>(num_bounding);
      } else if (ok) {
        ok = t.size() == coords + 2 + physicals.size();
      }
      if (!ok) in.fail("expected {} (dimension {} entity), got '{}'", what, dim, in.quoted());
      raw.entity_physicals[{dim, tag}] = std::move(physicals);
    }
  }
  in.end_section("Entities");
}

void add_node(MshLines& in, RawMesh& raw, long long tag, const Eigen::Vector3d& x) {
  const auto [it, inserted] = raw.node_index.emplace(tag, static_cast<int>(raw.nodes.size()));
  if (!inserted) in.fail("node tag {} appears twice", tag);
  raw.nodes.push_back(x);
}

Eigen::Vector3d read_xyz(MshLines& in, std::size_t first, std::string_view what) {
  Eigen::Vector3d x;
  for (int c = 0; c < 3; ++c) {
    if (!to_double(in.tokens()[first + static_cast<std::size_t>(c)], x[c]))
      in.fail("expected {}, got '{}'", what, in.quoted());
  }
  return x;
}

/// $Nodes ("tag x y z") or, with `parametric`, $ParametricNodes ("tag x y z dim entity [u [v]]").
void read_nodes_v22(MshLines& in, RawMesh& raw, bool parametric) {
  const int n = in.count(in.next_ints(1, "the number of nodes")[0], "number of nodes");
  raw.nodes.reserve(static_cast<std::size_t>(n));
  const std::string_view what = parametric ? "6 to 8 numbers (tag x y z dim entity u v)" : "4 numbers (tag x y z)";
  for (int k = 0; k < n; ++k) {
    in.need(what);
    long long tag = 0;
    const std::size_t size = in.tokens().size();
    const bool count_ok = parametric ? size >= 6 && size <= 8 : size == 4;
    if (!count_ok || !to_int(in.tokens()[0], tag)) in.fail("expected {}, got '{}'", what, in.quoted());
    add_node(in, raw, tag, read_xyz(in, 1, what));
  }
  in.end_section(parametric ? "ParametricNodes" : "Nodes");
}

void read_nodes_v41(MshLines& in, RawMesh& raw) {
  const auto head = in.next_ints(4, "'numEntityBlocks numNodes minNodeTag maxNodeTag'");
  const int blocks = in.count(head[0], "numEntityBlocks");
  const int total = in.count(head[1], "numNodes");
  raw.nodes.reserve(static_cast<std::size_t>(total));
  std::vector<long long> tags;
  for (int b = 0; b < blocks; ++b) {
    const auto block = in.next_ints(4, "'entityDim entityTag parametric numNodesInBlock'");
    const long long dim = block[0];
    if (dim < 0 || dim > 3 || (block[2] != 0 && block[2] != 1)) {
      in.fail("expected entityDim 0…3 and parametric 0 or 1, got '{}'", in.quoted());
    }
    const int count = in.count(block[3], "numNodesInBlock");
    tags.resize(static_cast<std::size_t>(count));
    for (auto& tag : tags) tag = in.next_ints(1, "a node tag")[0];
    const std::size_t numbers = 3 + (block[2] != 0 ? static_cast<std::size_t>(dim) : 0);
    const std::string what =
        numbers == 3 ? "3 numbers (x y z)" : fmt::format("{} numbers (x y z and parameters)", numbers);
    for (const long long tag : tags) {
      in.need(what);
      if (in.tokens().size() != numbers) in.fail("expected {}, got '{}'", what, in.quoted());
      add_node(in, raw, tag, read_xyz(in, 0, what));
    }
  }
  if (static_cast<int>(raw.nodes.size()) != total)
    in.fail("the header announces {} nodes, the blocks hold {}", total, raw.nodes.size());
  in.end_section("Nodes");
}

/// One element's node tags → indices; a tet also goes into raw.tets.
void add_element(MshLines& in, RawMesh& raw, long long type, std::size_t first, std::size_t count,
                 std::vector<int>& group) {
  std::array<int, 4> tet{};
  for (std::size_t k = 0; k < count; ++k) {
    long long tag = 0;
    if (!to_int(in.tokens()[first + k], tag)) in.fail("node tag '{}' is not an integer", in.tokens()[first + k]);
    const auto it = raw.node_index.find(tag);
    if (it == raw.node_index.end()) in.fail("element refers to node tag {}, which $Nodes does not define", tag);
    group.push_back(it->second);
    if (type == 4) tet[k] = it->second;
  }
  if (type == 4) {
    raw.tets.push_back(tet);
    raw.tet_lines.push_back(in.number());
  }
}

void read_elements_v22(MshLines& in, RawMesh& raw) {
  const int n = in.count(in.next_ints(1, "the number of elements")[0], "number of elements");
  std::vector<int> scratch;
  constexpr std::string_view what = "'tag type numTags tag… node…'";
  for (int k = 0; k < n; ++k) {
    const auto& v = in.next_ints(3, what, true);
    const long long type = v[1];
    const ElementType et = element_type(type);
    if (et.nodes == 0) in.fail("element type {} is not supported", type);
    const long long num_tags = v[2];
    if (num_tags < 0 ||
        in.tokens().size() != 3 + static_cast<std::size_t>(num_tags) + static_cast<std::size_t>(et.nodes)) {
      in.fail("expected {} with {} nodes for element type {}, got '{}'", what, et.nodes, type, in.quoted());
    }
    const long long physical = num_tags > 0 ? v[3] : 0;
    std::vector<int>& group = physical != 0 ? raw.physical_nodes[{et.dim, physical}] : scratch;
    add_element(in, raw, type, 3 + static_cast<std::size_t>(num_tags), static_cast<std::size_t>(et.nodes), group);
    scratch.clear();
  }
  in.end_section("Elements");
}

void read_elements_v41(MshLines& in, RawMesh& raw) {
  const auto head = in.next_ints(4, "'numEntityBlocks numElements minElementTag maxElementTag'");
  const int blocks = in.count(head[0], "numEntityBlocks");
  const int total = in.count(head[1], "numElements");
  int seen = 0;
  for (int b = 0; b < blocks; ++b) {
    const auto block = in.next_ints(4, "'entityDim entityTag elementType numElementsInBlock'");
    const long long dim = block[0];
    const long long type = block[2];
    if (dim < 0 || dim > 3) in.fail("entityDim {} is not 0…3", dim);
    const ElementType et = element_type(type);
    if (et.nodes > 0 && et.dim != dim) in.fail("element type {} has dimension {}, not {}", type, et.dim, dim);
    const int count = in.count(block[3], "numElementsInBlock");
    std::vector<int>& group = raw.entity_nodes[{static_cast<int>(dim), block[1]}];
    const std::string what = et.nodes > 0 ? fmt::format("{} integers (tag and {} node tags)", et.nodes + 1, et.nodes)
                                          : std::string("'tag node…'");
    for (int k = 0; k < count; ++k) {
      in.next_ints(et.nodes > 0 ? static_cast<std::size_t>(et.nodes) + 1 : 2, what, et.nodes == 0);
      add_element(in, raw, type, 1, in.tokens().size() - 1, group);
    }
    seen += count;
  }
  if (seen != total) in.fail("the header announces {} elements, the blocks hold {}", total, seen);
  in.end_section("Elements");
}

/// Names the groups, orients the tets and checks them.
MshMesh finish(const MshLines& in, RawMesh&& raw) {
  MshMesh mesh;
  mesh.version = raw.version;
  mesh.nodes.resize(static_cast<Eigen::Index>(raw.nodes.size()), 3);
  for (std::size_t k = 0; k < raw.nodes.size(); ++k)
    mesh.nodes.row(static_cast<Eigen::Index>(k)) = raw.nodes[k].transpose();

  auto name_of = [&](const DimTag& physical) {
    const auto it = raw.physical_names.find(physical);
    return it != raw.physical_names.end() ? it->second : std::to_string(physical.second);
  };
  auto add_group = [&](const DimTag& physical, const std::vector<int>& nodes) {
    const std::string name = name_of(physical);
    auto& group = mesh.node_groups[name];
    group.insert(group.end(), nodes.begin(), nodes.end());
    auto [it, inserted] = mesh.group_dimension.emplace(name, physical.first);
    if (!inserted) it->second = std::max(it->second, physical.first);
  };
  for (const auto& [physical, name] : raw.physical_names) add_group(physical, {});
  for (const auto& [physical, nodes] : raw.physical_nodes) add_group(physical, nodes);
  for (const auto& [entity, nodes] : raw.entity_nodes) {
    const auto it = raw.entity_physicals.find(entity);
    if (it == raw.entity_physicals.end()) continue;  // an entity without physical groups
    for (const long long tag : it->second) add_group({entity.first, tag}, nodes);
  }
  for (auto& [name, nodes] : mesh.node_groups) {
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  }

  require(!raw.tets.empty(), "{}: no 4-node tetrahedra (gmsh element type 4) in $Elements", in.path().string());
  mesh.tets.resize(static_cast<Eigen::Index>(raw.tets.size()), 4);
  for (std::size_t e = 0; e < raw.tets.size(); ++e) {
    std::array<int, 4>& t = raw.tets[e];
    Eigen::Matrix3d dm;
    double longest = 0.0;
    for (int a = 0; a < 4; ++a) {
      for (int b = a + 1; b < 4; ++b) longest = std::max(longest, (raw.nodes[t[b]] - raw.nodes[t[a]]).norm());
    }
    for (int c = 0; c < 3; ++c) dm.col(c) = raw.nodes[t[c + 1]] - raw.nodes[t[0]];
    const double det = dm.determinant();
    // The same degeneracy test as material::make_tet_rest: 6V against the cube of the longest edge.
    if (!(std::abs(det) > 1e-12 * longest * longest * longest)) {
      throw_error("{}:{}: $Elements: degenerate tetrahedron (volume {:.3g} m³, longest edge {:.3g} m)",
                  in.path().string(), raw.tet_lines[e], det / 6.0, longest);
    }
    if (det < 0.0) {
      std::swap(t[2], t[3]);
      ++mesh.flipped_tets;
    }
    for (int a = 0; a < 4; ++a) mesh.tets(static_cast<Eigen::Index>(e), a) = t[a];
  }
  return mesh;
}

std::string physical_names_section(const std::map<std::string, std::vector<int>>& node_groups) {
  std::string s = fmt::format("$PhysicalNames\n{}\n", node_groups.size() + 1);
  int tag = 1;
  for (const auto& [name, nodes] : node_groups) s += fmt::format("0 {} \"{}\"\n", tag++, name);
  s += fmt::format("3 {} \"volume\"\n$EndPhysicalNames\n", tag);
  return s;
}

void write_v22(std::ostream& out, const meshing::RowMatrixX3d& nodes, const meshing::RowMatrixX4i& tets,
               const std::map<std::string, std::vector<int>>& groups) {
  out << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n" << physical_names_section(groups);
  out << fmt::format("$Nodes\n{}\n", nodes.rows());
  for (Eigen::Index v = 0; v < nodes.rows(); ++v)
    out << fmt::format("{} {} {} {}\n", v + 1, nodes(v, 0), nodes(v, 1), nodes(v, 2));
  std::size_t points = 0;
  for (const auto& [name, members] : groups) points += members.size();
  out << fmt::format("$EndNodes\n$Elements\n{}\n", points + static_cast<std::size_t>(tets.rows()));
  // Each point element lives on its own elementary point entity (tags 1, 2, …), like a gmsh point.
  std::size_t element = 0;
  int physical = 0;
  for (const auto& [name, members] : groups) {
    ++physical;
    for (const int v : members) {
      ++element;
      out << fmt::format("{} 15 2 {} {} {}\n", element, physical, element, v + 1);
    }
  }
  for (Eigen::Index e = 0; e < tets.rows(); ++e) {
    out << fmt::format("{} 4 2 {} 1 {} {} {} {}\n", ++element, physical + 1, tets(e, 0) + 1, tets(e, 1) + 1,
                       tets(e, 2) + 1, tets(e, 3) + 1);
  }
  out << "$EndElements\n";
}

void write_v41(std::ostream& out, const meshing::RowMatrixX3d& nodes, const meshing::RowMatrixX4i& tets,
               const std::map<std::string, std::vector<int>>& groups) {
  out << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n" << physical_names_section(groups);
  std::size_t points = 0;
  for (const auto& [name, members] : groups) points += members.size();
  const Eigen::Vector3d lo = nodes.rows() > 0 ? Eigen::Vector3d(nodes.colwise().minCoeff()) : Eigen::Vector3d::Zero();
  const Eigen::Vector3d hi = nodes.rows() > 0 ? Eigen::Vector3d(nodes.colwise().maxCoeff()) : Eigen::Vector3d::Zero();
  // One gmsh point entity per group member (a gmsh point holds one node) carrying the group's physical
  // tag, and one volume entity holding every node and every tet.
  out << fmt::format("$Entities\n{} 0 0 1\n", points);
  std::size_t entity = 0;
  int physical = 0;
  for (const auto& [name, members] : groups) {
    ++physical;
    for (const int v : members)
      out << fmt::format("{} {} {} {} 1 {}\n", ++entity, nodes(v, 0), nodes(v, 1), nodes(v, 2), physical);
  }
  out << fmt::format("1 {} {} {} {} {} {} 1 {} 0\n$EndEntities\n", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2],
                     physical + 1);
  out << fmt::format("$Nodes\n1 {} 1 {}\n3 1 0 {}\n", nodes.rows(), nodes.rows(), nodes.rows());
  for (Eigen::Index v = 0; v < nodes.rows(); ++v) out << v + 1 << '\n';
  for (Eigen::Index v = 0; v < nodes.rows(); ++v)
    out << fmt::format("{} {} {}\n", nodes(v, 0), nodes(v, 1), nodes(v, 2));
  const std::size_t elements = points + static_cast<std::size_t>(tets.rows());
  out << fmt::format("$EndNodes\n$Elements\n{} {} 1 {}\n", points + 1, elements, elements);
  std::size_t element = 0;
  for (const auto& [name, members] : groups) {
    for (const int v : members) {
      ++element;
      out << fmt::format("0 {} 15 1\n{} {}\n", element, element, v + 1);
    }
  }
  out << fmt::format("3 1 4 {}\n", tets.rows());
  for (Eigen::Index e = 0; e < tets.rows(); ++e) {
    out << fmt::format("{} {} {} {} {}\n", ++element, tets(e, 0) + 1, tets(e, 1) + 1, tets(e, 2) + 1, tets(e, 3) + 1);
  }
  out << "$EndElements\n";
}

}  // namespace

MshMesh read_msh(const std::filesystem::path& path) {
  MshLines in(path);
  RawMesh raw;
  bool have_format = false, have_nodes = false, have_elements = false;
  while (in.next()) {
    const std::string_view header = in.line();
    if (header.empty() || header.front() != '$' || header.find(' ') != std::string_view::npos) {
      in.fail("expected a section header such as $Nodes, got '{}'", in.quoted());
    }
    const std::string name(header.substr(1));
    in.set_section(header);
    if (!have_format && name != "MeshFormat") in.fail("the file must start with $MeshFormat (is it a gmsh .msh file?)");
    if (name == "MeshFormat") {
      if (have_format) in.fail("a second $MeshFormat");
      read_format(in, raw);
      have_format = true;
    } else if (name == "PhysicalNames") {
      read_physical_names(in, raw);
    } else if (name == "Entities" && raw.version == MshVersion::v41) {
      read_entities(in, raw);
    } else if (name == "Nodes" || (name == "ParametricNodes" && raw.version == MshVersion::v22)) {
      if (have_nodes) in.fail("a second node section");
      raw.version == MshVersion::v22 ? read_nodes_v22(in, raw, name == "ParametricNodes") : read_nodes_v41(in, raw);
      have_nodes = true;
    } else if (name == "Elements") {
      if (have_elements) in.fail("a second $Elements section");
      raw.version == MshVersion::v22 ? read_elements_v22(in, raw) : read_elements_v41(in, raw);
      have_elements = true;
    } else {  // a section we do not need ($NodeData, $Periodic, $Comments, …)
      const std::string end = "$End" + name;
      do {
        in.need(end);
      } while (in.line() != end);
    }
    in.set_section("(top level)");
  }
  require(have_format, "{}: empty file, not a gmsh .msh file", path.string());
  require(have_nodes, "{}: no $Nodes section", path.string());
  require(have_elements, "{}: no $Elements section", path.string());
  return finish(in, std::move(raw));
}

void write_msh(const std::filesystem::path& path, const meshing::RowMatrixX3d& nodes, const meshing::RowMatrixX4i& tets,
               const std::map<std::string, std::vector<int>>& node_groups, MshVersion version) {
  const int n = static_cast<int>(nodes.rows());
  require(nodes.allFinite(), "{}: write_msh: node positions are not finite", path.string());
  require(tets.size() == 0 || (tets.minCoeff() >= 0 && tets.maxCoeff() < n),
          "{}: write_msh: tet node index out of range [0, {})", path.string(), n);
  for (const auto& [name, members] : node_groups) {
    require(name != "volume", "{}: write_msh: the group name 'volume' is reserved for the tets", path.string());
    require(!name.empty() && name.find_first_of("\"\r\n") == std::string::npos,
            "{}: write_msh: group name '{}' is empty or holds a quote or line break", path.string(), name);
    for (const int v : members)
      require(v >= 0 && v < n, "{}: write_msh: group '{}' has node {} outside [0, {})", path.string(), name, v, n);
  }
  std::ostringstream out;
  version == MshVersion::v22 ? write_v22(out, nodes, tets, node_groups) : write_v41(out, nodes, tets, node_groups);
  write_text_atomically(path, out.str());
}

}  // namespace sflsh::fullspace
