// Reading shape-model files (shape_model_file.hpp), errors as "<file>:<line>: …".
#include <sflsh/core/error.hpp>
#include <sflsh/core/toml_reader.hpp>
#include <sflsh/meshing/region.hpp>
#include <sflsh/reduced/shape_model_file.hpp>

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <map>

namespace sflsh::reduced {

namespace {

class Reader : public TomlReader {
 public:
  using TomlReader::TomlReader;

  void read_bounds(const toml::node& node, material::ParameterBounds& bounds) const {
    const toml::table& table = TomlReader::table(node, "bounds");
    check_keys(table, {"thickness", "young_tangent", "young_normal"}, " in [bounds]");
    material::ParameterRange* ranges[material::kNumKappa] = {&bounds.thickness, &bounds.young_tangent,
                                                             &bounds.young_normal};
    for (int c = 0; c < material::kNumKappa; ++c) {
      const std::string_view name = material::kKappaNames[static_cast<std::size_t>(c)];
      const toml::node* entry = table.get(name);
      if (entry == nullptr) continue;
      const std::vector<double> range = numbers(*entry, name, 2, " in [bounds]");
      *ranges[c] = {range[0], range[1]};
      try {
        material::validate(bounds);
      } catch (const Error& e) {
        throw_error("{}: {}", at(*entry), e.what());
      }
    }
  }

  void read_basis(const toml::node& node, ShapeModelFile& file) const {
    const toml::table& table = TomlReader::table(node, "basis");
    check_keys(table, {"kind", "region", "mesh"}, " in [basis]");
    const toml::node& kind = required(table, "kind", " in [basis]");
    const std::string k = string_value(kind, "kind", " in [basis]");
    require(k == kShapeModelBasisKind, "{}: 'kind' in [basis] = '{}' (the only basis is '{}')", at(kind), k,
            kShapeModelBasisKind);
    file.basis_line = static_cast<int>(table.source().begin.line);
    if (const toml::node* region = table.get("region")) {
      // Names of meshing::known_region_names joined by '+' (meshing::region_key), stored in key order.
      const std::string value = string_value(*region, "region", " in [basis]");
      std::vector<std::string> names;
      std::string csv = value;
      std::replace(csv.begin(), csv.end(), '+', ',');
      try {
        names = meshing::parse_region_names(csv);
      } catch (const Error& e) {
        fail(*region, "region in [basis]", "'{}' is not a layer region ({})", value, e.what());
      }
      file.region = meshing::region_key(names);
    }
    if (const toml::node* mesh = table.get("mesh")) {
      file.mesh = string_value(*mesh, "mesh", " in [basis]");
      if (file.mesh != "coarse" && file.mesh != "default" && file.mesh != "fine")
        fail(*mesh, "mesh in [basis]", "'{}' is not a mesh preset (expected coarse, default or fine)", file.mesh);
    }
  }

  ShapeModelFit read_fit(const toml::node& node) const {
    const toml::table& table = TomlReader::table(node, "fit");
    check_keys(table, {"regularizer", "lambda", "subjects", "motions"}, " in [fit]");
    ShapeModelFit fit;
    const toml::node& reg = required(table, "regularizer", " in [fit]");
    const std::string r = string_value(reg, "regularizer", " in [fit]");
    fit.regularizer = parse_regularizer(r, fmt::format("{}: 'regularizer' in [fit]", at(reg)));
    const toml::node& lambda = required(table, "lambda", " in [fit]");
    fit.lambda = number(lambda, "lambda", " in [fit]");
    require(fit.lambda >= 0.0, "{}: 'lambda' in [fit] = {} must be >= 0", at(lambda), fit.lambda);
    if (const toml::node* s = table.get("subjects")) fit.subjects = strings(*s, "subjects", " in [fit]");
    if (const toml::node* m = table.get("motions")) fit.motions = strings(*m, "motions", " in [fit]");
    return fit;
  }

  ShapeModelControlPoint read_point(const toml::node& node, std::size_t index, std::map<int, std::size_t>& seen) const {
    const toml::table* table = node.as_table();
    require(table != nullptr, "{}: 'control_point' must be an array of tables ([[control_point]])", at(node));
    const std::string context = fmt::format(" in control_point #{}", index);
    check_keys(*table, {"vertex", "position", "b", "A"}, context);
    ShapeModelControlPoint point;
    point.line = static_cast<int>(table->source().begin.line);
    point.vertex = control_vertex(*table, index, context, seen, point.position);
    const std::vector<double> b = numbers(required(*table, "b", context), "b", material::kNumKappa, context);
    point.b = Eigen::RowVector3d(b[0], b[1], b[2]);
    const toml::node& a = required(*table, "A", context);
    const toml::array* rows = a.as_array();
    require(rows != nullptr && rows->size() == static_cast<std::size_t>(body::kNumBetas),
            "{}: 'A'{} must be an array of {} rows (one per β) of {} numbers (h, Y_t, Y_n)", at(a), context,
            body::kNumBetas, material::kNumKappa);
    for (int k = 0; k < body::kNumBetas; ++k) {
      const std::vector<double> row = numbers((*rows)[static_cast<std::size_t>(k)], "A", material::kNumKappa,
                                              fmt::format("{} (row {})", context, k));
      for (int c = 0; c < material::kNumKappa; ++c) point.A(k, c) = row[static_cast<std::size_t>(c)];
    }
    return point;
  }

  ShapeModelFile read() const {
    const toml::table root = parse("a shape-model TOML file");
    check_keys(root, {"version", "body", "poisson", "saturation", "bounds", "basis", "fit", "control_point"}, "");
    ShapeModelFile file;
    file.source = path().string();
    check_version(required(root, "version", ""), kShapeModelFileVersion);
    file.body = string_value(required(root, "body", ""), "body");
    const toml::node& poisson = required(root, "poisson", "");
    file.poisson = number(poisson, "poisson", "");
    require(file.poisson > -1.0 && file.poisson < 0.5, "{}: 'poisson' = {} is outside (-1, 0.5)", at(poisson),
            file.poisson);
    const toml::node& saturation = required(root, "saturation", "");
    file.saturation = number(saturation, "saturation", "");
    if (!(file.saturation > 0.0 && file.saturation <= material::kSaturationMax))
      fail(saturation, "saturation", "{} is outside (0, {}] (the Fung saturation; docs/material.md)", file.saturation,
           material::kSaturationMax);
    if (const toml::node* bounds = root.get("bounds")) read_bounds(*bounds, file.bounds);
    read_basis(required(root, "basis", ""), file);
    if (const toml::node* fit = root.get("fit")) file.fit = read_fit(*fit);

    const toml::node* list = root.get("control_point");
    require(list != nullptr, "{}: no [[control_point]] tables", path().string());
    const toml::array* points = list->as_array();
    require(points != nullptr && !points->empty(), "{}: 'control_point' must be a non-empty array of tables",
            at(*list));
    std::map<int, std::size_t> seen;  // vertex → its first control point
    for (std::size_t i = 0; i < points->size(); ++i) file.control_points.push_back(read_point((*points)[i], i, seen));
    validate(file, path().string());  // everything again (with each point's table line); nothing should be left
    return file;
  }
};

}  // namespace

ShapeModelFile load_shape_model_file(const std::filesystem::path& path) { return Reader(path).read(); }

}  // namespace sflsh::reduced
