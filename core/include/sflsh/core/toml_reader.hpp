#pragma once
// Reading TOML input files with errors as "<file>:<line>: …" (material, shape-model and scene files): the checks
// every reader needs (unknown keys, missing keys, types, finite numbers, fixed-size arrays, control-point
// vertices), on toml++; and the two value formatters their writers share.
#include <sflsh/core/error.hpp>
#include <sflsh/core/input_file.hpp>

#include <Eigen/Core>
#include <toml++/toml.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace sflsh {

/// Whether `key` is one of `allowed` (a table's known keys).
inline bool is_one_of(std::string_view key, std::initializer_list<std::string_view> allowed) {
  for (const std::string_view a : allowed)
    if (key == a) return true;
  return false;
}

/// `allowed` as "a, b, c" for an error message.
inline std::string joined(std::initializer_list<std::string_view> allowed) {
  std::string list;
  for (const std::string_view a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
  return list;
}

class TomlReader {
 public:
  explicit TomlReader(std::filesystem::path path) : path_(std::move(path)) {}

  const std::filesystem::path& path() const { return path_; }

  /// Parses the file; a missing, unreadable or directory path or a syntax error is one line naming the file
  /// (and line). `what` names the kind with its article ("a material TOML file").
  toml::table parse(std::string_view what) const {
    require_input_file(path_, what);
    try {
      return toml::parse_file(path_.string());
    } catch (const toml::parse_error& e) {
      throw_error("{}:{}: {}", path_.string(), e.source().begin.line, e.description());
    }
  }

  std::string at(const toml::node& node) const {
    return fmt::format("{}:{}", path_.string(), node.source().begin.line);
  }

  /// Throws "<file>:<line>: <field>: <what>" — the project's one-line error convention.
  template <typename... Args>
  [[noreturn]] void fail(const toml::node& node, std::string_view field, fmt::format_string<Args...> format,
                         Args&&... args) const {
    throw_error("{}: {}: {}", at(node), field, fmt::format(format, std::forward<Args>(args)...));
  }

  /// A number in the closed range [min, max]; outside: "<file>:<line>: <key><context>: <value> <unit> is outside
  /// [min, max] <unit>". `unit` is "" or e.g. "s", "Pa".
  double number_in(const toml::node& node, std::string_view key, std::string_view context, double min, double max,
                   std::string_view unit = "") const {
    const double value = number(node, key, context);
    const std::string u = unit.empty() ? std::string() : fmt::format(" {}", unit);
    if (!(value >= min && value <= max))
      fail(node, fmt::format("{}{}", key, context), "{:.6g}{} is outside [{:.6g}, {:.6g}]{}", value, u, min, max, u);
    return value;
  }

  /// A file's `version` node must be the integer `expected` (the reader's format).
  void check_version(const toml::node& version, std::int64_t expected) const {
    const auto value = version.value_exact<std::int64_t>();
    require(value.has_value() && *value == expected, "{}: 'version' must be the integer {} (this reader's format)",
            at(version), expected);
  }

  /// Every key of `table` must be one of `allowed`.
  void check_keys(const toml::table& table, std::initializer_list<std::string_view> allowed,
                  std::string_view context) const {
    for (const auto& [key, node] : table)
      if (!is_one_of(key.str(), allowed))
        throw_error("{}: unknown key '{}'{} (expected {})", at(node), key.str(), context, joined(allowed));
  }

  const toml::node& required(const toml::table& table, std::string_view key, std::string_view context) const {
    const toml::node* node = table.get(key);
    require(node != nullptr, "{}: missing key '{}'{}", at(table), key, context);
    return *node;
  }

  const toml::table& table(const toml::node& node, std::string_view key) const {
    const toml::table* t = node.as_table();
    require(t != nullptr, "{}: '{}' must be a table", at(node), key);
    return *t;
  }

  std::string string_value(const toml::node& node, std::string_view key, std::string_view context = "") const {
    const auto value = node.value_exact<std::string>();
    require(value.has_value(), "{}: '{}'{} must be a string", at(node), key, context);
    require(!value->empty(), "{}: '{}'{} must not be empty", at(node), key, context);
    return *value;
  }

  std::vector<std::string> strings(const toml::node& node, std::string_view key, std::string_view context) const {
    const toml::array* array = node.as_array();
    require(array != nullptr, "{}: '{}'{} must be an array of strings", at(node), key, context);
    std::vector<std::string> out;
    for (const toml::node& item : *array) out.push_back(string_value(item, key, context));
    return out;
  }

  bool boolean(const toml::node& node, std::string_view key, std::string_view context) const {
    const auto value = node.value_exact<bool>();
    require(value.has_value(), "{}: '{}'{} must be true or false", at(node), key, context);
    return *value;
  }

  std::int64_t integer(const toml::node& node, std::string_view key, std::string_view context) const {
    const auto value = node.value_exact<std::int64_t>();
    require(value.has_value(), "{}: '{}'{} must be an integer", at(node), key, context);
    return *value;
  }

  double number(const toml::node& node, std::string_view key, std::string_view context) const {
    require(node.is_number(), "{}: '{}'{} must be a number", at(node), key, context);
    const double value = *node.value<double>();
    require(std::isfinite(value), "{}: '{}'{} is not finite", at(node), key, context);
    return value;
  }

  std::vector<double> numbers(const toml::node& node, std::string_view key, std::size_t count,
                              std::string_view context) const {
    const toml::array* array = node.as_array();
    require(array != nullptr && array->size() == count, "{}: '{}'{} must be an array of {} numbers", at(node), key,
            context, count);
    std::vector<double> out;
    for (const toml::node& item : *array) out.push_back(number(item, key, context));
    return out;
  }

  double positive(const toml::node& node, std::string_view key, std::string_view context) const {
    const double v = number(node, key, context);
    require(v > 0.0, "{}: '{}'{} = {} must be positive", at(node), key, context, v);
    return v;
  }

  /// A physical quantity within its plausible range [lo, hi] (docs/scenes.md, "Input limits"): values outside
  /// it are typing errors (a scene radius of 10⁹ m used to reach the solver, which then failed naming no key).
  double bounded(const toml::node& node, std::string_view key, std::string_view context, double lo, double hi,
                 std::string_view unit) const {
    const double v = number(node, key, context);
    require(v >= lo && v <= hi, "{}: '{}'{} = {} must be in [{}, {}] {}", at(node), key, context, v, lo, hi, unit);
    return v;
  }

  /// A vector whose components each lie in [−bound, bound] (positions, velocities).
  Eigen::Vector3d bounded3(const toml::node& node, std::string_view key, std::string_view context, double bound,
                           std::string_view unit) const {
    const Eigen::Vector3d v = vector3(node, key, context);
    require(v.cwiseAbs().maxCoeff() <= bound, "{}: '{}'{} = [{}, {}, {}] must have components in [-{}, {}] {}",
            at(node), key, context, v.x(), v.y(), v.z(), bound, bound, unit);
    return v;
  }

  double non_negative(const toml::node& node, std::string_view key, std::string_view context) const {
    const double v = number(node, key, context);
    require(v >= 0.0, "{}: '{}'{} = {} must not be negative", at(node), key, context, v);
    return v;
  }

  Eigen::Vector3d vector3(const toml::node& node, std::string_view key, std::string_view context) const {
    const std::vector<double> v = numbers(node, key, 3, context);
    return {v[0], v[1], v[2]};
  }

  /// The 'vertex' of a [[control_point]] table (a body vertex index ≥ 0 that no earlier entry used: `seen`
  /// maps vertex → entry index) and its optional 'position' [m].
  int control_vertex(const toml::table& table, std::size_t index, std::string_view context,
                     std::map<int, std::size_t>& seen, std::optional<Eigen::Vector3d>& position) const {
    const toml::node& vertex = required(table, "vertex", context);
    const auto v = vertex.value_exact<std::int64_t>();
    require(v.has_value(), "{}: 'vertex'{} must be an integer", at(vertex), context);
    require(*v >= 0 && *v <= std::numeric_limits<int>::max(), "{}: 'vertex'{} = {} must be a vertex index >= 0",
            at(vertex), context, *v);
    const int id = static_cast<int>(*v);
    const auto [first, inserted] = seen.emplace(id, index);
    require(inserted, "{}: 'vertex'{} repeats vertex {} of control_point #{}", at(vertex), context, id, first->second);
    if (const toml::node* p = table.get("position")) {
      const std::vector<double> xyz = numbers(*p, "position", 3, context);
      position = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
    }
    return id;
  }

 private:
  std::filesystem::path path_;
};

/// Shortest round-trip decimal, always with a '.' or exponent so TOML reads it back as a float.
inline std::string toml_float(double value) {
  std::string s = fmt::format("{}", value);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s;
}

/// A TOML basic string (quoted and escaped by toml++).
inline std::string toml_string(const std::string& value) {
  std::ostringstream out;
  out << toml::value<std::string>(value);
  return out.str();
}

}  // namespace sflsh
