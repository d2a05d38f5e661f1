// Reading material files (material_file.hpp, docs/material_file.md), errors as "<file>:<line>: …".
#include <sflsh/core/error.hpp>
#include <sflsh/core/toml_reader.hpp>
#include <sflsh/material/material_file.hpp>

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <map>

namespace sflsh::material {

namespace {

class Reader : public TomlReader {
 public:
  using TomlReader::TomlReader;

  void read_bounds(const toml::node& node, ParameterBounds& bounds) const {
    const toml::table* table = node.as_table();
    require(table != nullptr, "{}: 'bounds' must be a table", at(node));
    check_keys(*table, {"thickness", "young_tangent", "young_normal"}, " in [bounds]");
    ParameterRange* ranges[kNumKappa] = {&bounds.thickness, &bounds.young_tangent, &bounds.young_normal};
    for (int c = 0; c < kNumKappa; ++c) {
      const std::string_view name = kKappaNames[static_cast<std::size_t>(c)];
      const toml::node* entry = table->get(name);
      if (entry == nullptr) continue;
      const std::vector<double> range = numbers(*entry, name, 2, " in [bounds]");
      *ranges[c] = {range[0], range[1]};
      try {
        validate(bounds);
      } catch (const Error& e) {
        throw_error("{}: {}", at(*entry), e.what());
      }
    }
  }

  MaterialControlPoint read_point(const toml::node& node, std::size_t index, const ParameterBounds& bounds,
                                  std::map<int, std::size_t>& seen) const {
    const toml::table* table = node.as_table();
    require(table != nullptr, "{}: 'control_point' must be an array of tables ([[control_point]])", at(node));
    const std::string context = fmt::format(" in control_point #{}", index);
    check_keys(*table, {"vertex", "position", "thickness", "young_tangent", "young_normal"}, context);
    MaterialControlPoint point;
    point.line = static_cast<int>(table->source().begin.line);
    point.vertex = control_vertex(*table, index, context, seen, point.position);
    double* values[kNumKappa] = {&point.kappa.thickness, &point.kappa.young_tangent, &point.kappa.young_normal};
    for (int c = 0; c < kNumKappa; ++c) {
      const std::string_view name = kKappaNames[static_cast<std::size_t>(c)];
      const toml::node& field = required(*table, name, context);
      *values[c] = number(field, name, context);
      const ParameterRange& range = bounds[c];
      require(*values[c] >= range.min && *values[c] <= range.max, "{}: '{}'{} = {} is outside the bounds [{}, {}]{}",
              at(field), name, context, *values[c], range.min, range.max, c == kThickness ? "" : " Pa");
    }
    return point;
  }

  MaterialFile read() const {
    const toml::table root = parse("a material TOML file");
    check_keys(root, {"version", "body", "subject", "betas", "poisson", "saturation", "bounds", "control_point"}, "");
    MaterialFile file;
    file.source = path().string();
    if (const toml::node* version = root.get("version")) check_version(*version, kMaterialFileVersion);
    file.body = string_value(required(root, "body", ""), "body");
    file.subject = string_value(required(root, "subject", ""), "subject");
    if (const toml::node* betas = root.get("betas")) {
      const std::vector<double> values = numbers(*betas, "betas", kNumBetasInFile, "");
      file.betas.emplace();
      std::copy(values.begin(), values.end(), file.betas->begin());
    }
    const toml::node& poisson = required(root, "poisson", "");
    file.poisson = number(poisson, "poisson", "");
    require(file.poisson > -1.0 && file.poisson < 0.5, "{}: 'poisson' = {} is outside (-1, 0.5)", at(poisson),
            file.poisson);
    const toml::node& saturation = required(root, "saturation", "");
    file.saturation = number(saturation, "saturation", "");
    if (!(file.saturation > 0.0 && file.saturation <= kSaturationMax))
      fail(saturation, "saturation", "{} is outside (0, {}] (the Fung saturation; docs/material.md)", file.saturation,
           kSaturationMax);
    if (const toml::node* bounds = root.get("bounds")) read_bounds(*bounds, file.bounds);

    const toml::node* list = root.get("control_point");
    require(list != nullptr, "{}: no [[control_point]] tables", path().string());
    const toml::array* points = list->as_array();
    require(points != nullptr && !points->empty(), "{}: 'control_point' must be a non-empty array of tables",
            at(*list));
    std::map<int, std::size_t> seen;  // vertex → its first control point
    for (std::size_t i = 0; i < points->size(); ++i)
      file.control_points.push_back(read_point((*points)[i], i, file.bounds, seen));
    validate(file, path().string());  // everything again (with each point's table line); nothing should be left
    return file;
  }
};

}  // namespace

MaterialFile load_material_file(const std::filesystem::path& path) { return Reader(path).read(); }

}  // namespace sflsh::material
