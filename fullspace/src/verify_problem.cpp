// Verification problems (verify_problem.hpp): the TOML reader with "<file>:<line>: key: …" errors,
// muparser drives, and the full-space Problem they define.
#include <sflsh/core/error.hpp>
#include <sflsh/core/input_file.hpp>
#include <sflsh/core/toml_reader.hpp>
#include <sflsh/fullspace/verify_problem.hpp>
#include <sflsh/material/parameters.hpp>

#include <fmt/format.h>
#include <muParser.h>
#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <map>
#include <memory>
#include <mutex>
#include <numbers>
#include <string_view>

namespace sflsh::fullspace {

namespace {

/// One muparser expression u(t). mu::Parser keeps a pointer to `t` and is not thread-safe, so the
/// parser lives here once (shared by all copies of the ScalarDrive) and every evaluation locks.
struct ExpressionDrive {
  std::mutex mutex;
  double t = 0.0;
  mu::Parser parser;
  std::string expression;

  /// u(time); the caller holds the lock.
  double eval(double time) {
    t = time;
    double u = 0.0;
    try {
      u = parser.Eval();
    } catch (const mu::ParserError& e) {
      throw_error("expression '{}' at t = {}: {}", expression, time, e.GetMsg());
    }
    require(std::isfinite(u), "expression '{}' is not finite at t = {} (value {})", expression, time, u);
    return u;
  }

  double value(double time) {
    const std::lock_guard<std::mutex> lock(mutex);
    return eval(time);
  }

  /// Central difference with h = 1e-6·max(1, |t|) (see verify_problem.hpp).
  double rate(double time) {
    const std::lock_guard<std::mutex> lock(mutex);
    const double h = 1e-6 * std::max(1.0, std::abs(time));
    return (eval(time + h) - eval(time - h)) / (2.0 * h);
  }
};

constexpr std::string_view kAxes = "xyz";

constexpr std::array<VerifyProblem::Integrator, 4> kIntegrators = {
    VerifyProblem::Integrator::backward_euler, VerifyProblem::Integrator::bdf2, VerifyProblem::Integrator::newmark,
    VerifyProblem::Integrator::reference};

class Reader {
 public:
  explicit Reader(std::filesystem::path path) : path_(std::move(path)) {}

  /// "<file>:<line>" of a node ("<file>" when toml++ gives no line).
  std::string at(const toml::node& node) const {
    const auto line = node.source().begin.line;
    return line > 0 ? fmt::format("{}:{}", path_.string(), line) : path_.string();
  }

  template <typename... Args>
  [[noreturn]] void fail(const toml::node& node, std::string_view key, fmt::format_string<Args...> format,
                         Args&&... args) const {
    throw_error("{}: {}: {}", at(node), key, fmt::format(format, std::forward<Args>(args)...));
  }

  /// Every key of `table` must be one of `allowed`; `prefix` is "" or "material." etc.
  void check_keys(const toml::table& table, std::initializer_list<std::string_view> allowed,
                  const std::string& prefix) const {
    for (const auto& [key, node] : table)
      if (!is_one_of(key.str(), allowed))
        fail(node, prefix + std::string(key.str()), "unknown key (expected one of {})", joined(allowed));
  }

  const toml::node& required(const toml::table& table, std::string_view key, const std::string& prefix) const {
    const toml::node* node = table.get(key);
    if (node == nullptr) fail(table, prefix + std::string(key), "missing (required)");
    return *node;
  }

  const toml::table& table(const toml::table& root, std::string_view key) const {
    const toml::table* t = root[key].as_table();
    if (t == nullptr) {
      const toml::node* node = root.get(key);
      if (node == nullptr) throw_error("{}: [{}]: missing table (required)", path_.string(), key);
      fail(*node, key, "must be a table [{}]", key);
    }
    return *t;
  }

  std::string string(const toml::node& node, const std::string& key) const {
    const auto value = node.value_exact<std::string>();
    if (!value.has_value()) fail(node, key, "must be a string");
    if (value->empty()) fail(node, key, "must not be empty");
    return *value;
  }

  double number(const toml::node& node, const std::string& key) const {
    if (!node.is_number()) fail(node, key, "must be a number");
    const double value = *node.value<double>();
    if (!std::isfinite(value)) fail(node, key, "must be finite, got {}", value);
    return value;
  }

  double positive(const toml::node& node, const std::string& key) const {
    const double value = number(node, key);
    if (!(value > 0.0)) fail(node, key, "must be > 0, got {}", value);
    return value;
  }

  /// A number in [min, max] (both > 0 for a physical range) with its unit in the message.
  double in_range(const toml::node& node, const std::string& key, double min, double max, std::string_view unit) const {
    const double value = number(node, key);
    if (!(value >= min && value <= max))
      fail(node, key, "{:.6g}{} is outside [{:.6g}, {:.6g}]{}", value, unit, min, max, unit);
    return value;
  }

  Eigen::Vector3d vector3(const toml::node& node, const std::string& key) const {
    const toml::array* array = node.as_array();
    if (array == nullptr || array->size() != 3) fail(node, key, "must be an array of 3 numbers");
    Eigen::Vector3d v;
    for (int c = 0; c < 3; ++c) v[c] = number(*array->get(static_cast<std::size_t>(c)), key);
    return v;
  }

  /// The tables of an optional array of tables ([[name]]).
  std::vector<const toml::table*> tables(const toml::table& root, std::string_view key) const {
    std::vector<const toml::table*> out;
    const toml::node* node = root.get(key);
    if (node == nullptr) return out;
    const toml::array* array = node->as_array();
    if (array == nullptr) fail(*node, key, "must be an array of tables [[{}]]", key);
    for (const toml::node& item : *array) {
      if (!item.is_table()) fail(item, key, "must be an array of tables [[{}]]", key);
      out.push_back(item.as_table());
    }
    return out;
  }

  /// The nodes of a mesh group, which must exist and be non-empty.
  const std::vector<int>& group(const MshMesh& mesh, const toml::node& node, const std::string& key) const {
    const std::string name = string(node, key);
    const auto it = mesh.node_groups.find(name);
    if (it == mesh.node_groups.end()) {
      std::string list;
      for (const auto& [g, nodes] : mesh.node_groups) list += (list.empty() ? "'" : ", '") + g + "'";
      fail(node, key, "no node group '{}' in the mesh (it has {})", name, list.empty() ? "no physical groups" : list);
    }
    if (it->second.empty()) fail(node, key, "node group '{}' has no nodes", name);
    return it->second;
  }

  void read_material(const toml::table& root, VerifyProblem& p) const {
    const toml::table& m = table(root, "material");
    check_keys(m, {"young_tangent", "young_normal", "poisson", "saturation", "normal", "fung_scale", "overflow"},
               "material.");
    // The physical ranges of material files (parameters.hpp): no run starts with a modulus or saturation that
    // overflows the energy.
    const material::ParameterRange young = material::kYoungModulusLimits;
    p.material.young_tangent =
        in_range(required(m, "young_tangent", "material."), "material.young_tangent", young.min, young.max, " Pa");
    p.material.young_normal =
        in_range(required(m, "young_normal", "material."), "material.young_normal", young.min, young.max, " Pa");
    if (const toml::node* n = m.get("poisson")) {
      p.material.poisson = number(*n, "material.poisson");
      if (!(p.material.poisson > -1.0 && p.material.poisson < 0.5)) {
        fail(*n, "material.poisson", "must be in (-1, 0.5), got {}", p.material.poisson);
      }
    }
    if (const toml::node* n = m.get("saturation")) {
      p.material.saturation = positive(*n, "material.saturation");
      if (p.material.saturation > material::kSaturationMax)
        fail(*n, "material.saturation", "{} is outside (0, {}]", p.material.saturation, material::kSaturationMax);
    }
    if (const toml::node* n = m.get("normal")) {
      p.normal = vector3(*n, "material.normal");
      if (!(p.normal.norm() > 0.0)) fail(*n, "material.normal", "must be a non-zero vector");
      p.normal.normalize();
    }
    if (const toml::node* n = m.get("fung_scale")) {
      const std::string s = string(*n, "material.fung_scale");
      if (s == "tangent_over_saturation") {
        p.material.fung_scale = material::FungScale::kTangentOverSaturation;
      } else if (s == "tangent_times_saturation") {
        p.material.fung_scale = material::FungScale::kTangentTimesSaturation;
      } else if (s == "none") {
        p.material.fung_scale = material::FungScale::kNone;
      } else {
        fail(*n, "material.fung_scale",
             "expected \"tangent_over_saturation\", \"tangent_times_saturation\" or \"none\", got \"{}\"", s);
      }
    }
    if (const toml::node* n = m.get("overflow")) {
      const std::string s = string(*n, "material.overflow");
      if (s == "throw") {
        p.material.overflow = material::ExponentOverflow::kThrow;
      } else if (s == "continue_linearly") {
        p.material.overflow = material::ExponentOverflow::kContinueLinearly;
      } else {
        fail(*n, "material.overflow", "expected \"throw\" or \"continue_linearly\", got \"{}\"", s);
      }
    }
  }

  void read_time(const toml::table& root, VerifyProblem& p) const {
    const toml::table& t = table(root, "time");
    check_keys(t, {"duration", "step", "integrator", "rtol", "atol"}, "time.");
    p.duration = positive(required(t, "duration", "time."), "time.duration");
    p.step = positive(required(t, "step", "time."), "time.step");
    if (p.step > p.duration * (1.0 + 1e-12))
      fail(*t.get("step"), "time.step", "must not exceed time.duration = {}", p.duration);
    if (const toml::node* n = t.get("integrator")) {
      const std::string s = string(*n, "time.integrator");
      const auto known = std::find_if(kIntegrators.begin(), kIntegrators.end(),
                                      [&](VerifyProblem::Integrator i) { return to_string(i) == s; });
      if (known == kIntegrators.end()) {
        fail(*n, "time.integrator",
             "expected one of \"backward_euler\", \"bdf2\", \"newmark\", \"reference\", got \"{}\"", s);
      }
      p.integrator = *known;
      if (p.density == 0.0 && p.integrator != VerifyProblem::Integrator::backward_euler) {
        fail(*n, "time.integrator",
             "\"{}\" needs a dynamic problem (density > 0); a static problem takes "
             "\"backward_euler\" (or no integrator)",
             s);
      }
    }
    // Tolerances of the reference integrator: tighter than these, CVODE's steps shrink towards round-off and
    // the run does not end.
    if (const toml::node* n = t.get("rtol")) p.rtol = in_range(*n, "time.rtol", 1e-12, 0.1, "");
    if (const toml::node* n = t.get("atol")) p.atol = in_range(*n, "time.atol", 1e-15, 0.1, "");
  }

  void read_record_and_solver(const toml::table& root, VerifyProblem& p) const {
    const toml::table& r = table(root, "record");
    check_keys(r, {"group", "every"}, "record.");
    const toml::node& g = required(r, "group", "record.");
    group(p.mesh, g, "record.group");
    p.record_group = string(g, "record.group");
    if (const toml::node* n = r.get("every")) {
      const auto every = n->value_exact<std::int64_t>();
      if (!every.has_value() || *every < 1 || *every > 1'000'000'000)
        fail(*n, "record.every", "must be an integer >= 1");
      p.record_every = static_cast<int>(*every);
    }
    if (root.get("solver") == nullptr) return;
    const toml::table& s = table(root, "solver");
    check_keys(s, {"hessian"}, "solver.");
    if (const toml::node* n = s.get("hessian")) {
      const std::string h = string(*n, "solver.hessian");
      if (h == "projected") {
        p.projection = material::HessianProjection::kStressDerivative;
      } else if (h == "exact") {
        p.projection = material::HessianProjection::kNone;
      } else {
        fail(*n, "solver.hessian", "expected \"projected\" or \"exact\", got \"{}\"", h);
      }
    }
  }

  /// [[fix]] and [[drive]]; a component may be fixed several times but not fixed and driven, nor driven twice.
  void read_boundary(const toml::table& root, VerifyProblem& p) const {
    struct Owner {
      int drive = -1;     // −1: fixed
      std::string entry;  // "fix[1]" or "drive[2]", for messages
      int line = 0;
    };
    std::map<int, Owner> owner;  // dof → who prescribes it
    auto claim = [&](const std::vector<int>& nodes, unsigned mask, const Owner& who, const toml::node& node,
                     const std::string& key, const std::string& group_name) {
      for (const int v : nodes) {
        for (int axis = 0; axis < 3; ++axis) {
          if ((mask & (1u << axis)) == 0) continue;
          const auto [it, inserted] = owner.emplace(3 * v + axis, who);
          if (inserted || (it->second.drive < 0 && who.drive < 0)) continue;
          fail(node, key,
               "component {} of node {} (group '{}') is already prescribed by {} (line {}); a component "
               "may be fixed or driven, once",
               kAxes[static_cast<std::size_t>(axis)], v, group_name, it->second.entry, it->second.line);
        }
      }
    };
    int k = 0;
    for (const toml::table* t : tables(root, "fix")) {
      const std::string entry = fmt::format("fix[{}]", ++k);
      check_keys(*t, {"group", "components"}, entry + ".");
      const toml::node& g = required(*t, "group", entry + ".");
      const std::vector<int>& nodes = group(p.mesh, g, entry + ".group");
      const toml::node& c = required(*t, "components", entry + ".");
      const std::string components = string(c, entry + ".components");
      unsigned mask = 0;
      for (const char ch : components) {
        const std::size_t axis = kAxes.find(ch);
        if (axis == std::string_view::npos || (mask & (1u << axis)) != 0) {
          fail(c, entry + ".components", "expected a non-empty subset of \"xyz\" without repeats, got \"{}\"",
               components);
        }
        mask |= 1u << axis;
      }
      p.fixes.push_back({string(g, entry + ".group"), mask});
      claim(nodes, mask, {-1, entry, static_cast<int>(t->source().begin.line)}, c, entry + ".components",
            p.fixes.back().group);
    }
    k = 0;
    for (const toml::table* t : tables(root, "drive")) {
      const std::string entry = fmt::format("drive[{}]", ++k);
      check_keys(*t, {"group", "component", "expression"}, entry + ".");
      const toml::node& g = required(*t, "group", entry + ".");
      const std::vector<int>& nodes = group(p.mesh, g, entry + ".group");
      const toml::node& c = required(*t, "component", entry + ".");
      const std::string component = string(c, entry + ".component");
      if (component.size() != 1 || kAxes.find(component[0]) == std::string_view::npos) {
        fail(c, entry + ".component", "expected one of \"x\", \"y\", \"z\", got \"{}\"", component);
      }
      const toml::node& e = required(*t, "expression", entry + ".");
      VerifyProblem::Drive drive{string(g, entry + ".group"), static_cast<int>(kAxes.find(component[0])),
                                 string(e, entry + ".expression")};
      try {
        expression_drive(drive.expression);
      } catch (const Error& err) {
        fail(e, entry + ".expression", "{}", err.what());
      }
      p.drives.push_back(drive);
      claim(nodes, 1u << drive.axis, {k - 1, entry, static_cast<int>(t->source().begin.line)}, c, entry + ".component",
            drive.group);
    }
  }

  /// Plausibility before solving: every drive u(t), sampled at 1001 times over [0, time.duration], stays finite and
  /// within ten times the mesh's size. A boundary moved farther than that is no soft-tissue problem; a drive of
  /// 10³⁰⁰·t used to reach the solver, which then failed naming no file or key.
  void check_drive_amplitudes(const toml::table& root, const VerifyProblem& p) const {
    if (p.mesh.nodes.rows() == 0) return;
    const double size = (p.mesh.nodes.colwise().maxCoeff() - p.mesh.nodes.colwise().minCoeff()).norm();
    const double bound = 10.0 * size;
    std::size_t k = 0;
    for (const toml::table* t : tables(root, "drive")) {
      const std::string entry = fmt::format("drive[{}].expression", k + 1);
      const VerifyProblem::Drive& drive = p.drives.at(k++);
      const ScalarDrive u = expression_drive(drive.expression);
      constexpr int kSamples = 1000;
      for (int i = 0; i <= kSamples; ++i) {
        const double time = p.duration * i / kSamples;
        double value = 0.0;
        try {
          value = u.value(time);
        } catch (const Error& err) {
          fail(*t->get("expression"), entry, "{}", err.what());
        }
        if (std::abs(value) > bound)
          fail(*t->get("expression"), entry,
               "'{}' = {:.6g} m at t = {:.6g} s; expected |u| ≤ {:.3g} m over [0, time.duration = {:.6g} s] (ten "
               "times the mesh's size, {:.3g} m)",
               drive.expression, value, time, bound, p.duration, size);
      }
    }
  }

  VerifyProblem read() const {
    require_input_file(path_, "a verify problem TOML file");
    toml::table root;
    try {
      root = toml::parse_file(path_.string());
    } catch (const toml::parse_error& e) {
      throw_error("{}:{}: {}", path_.string(), e.source().begin.line, e.description());
    }
    check_keys(root, {"mesh", "density", "gravity", "mass", "material", "fix", "drive", "time", "record", "solver"},
               "");
    VerifyProblem p;
    p.file = path_;
    const toml::node& mesh = required(root, "mesh", "");
    p.mesh_path = (path_.parent_path() / string(mesh, "mesh")).lexically_normal();
    try {
      require_input_file(p.mesh_path, "a gmsh .msh file");
    } catch (const Error& err) {
      fail(mesh, "mesh", "{}", err.what());
    }
    try {
      p.mesh = read_msh(p.mesh_path);
    } catch (const Error& err) {
      fail(mesh, "mesh", "{}", err.what());
    }
    if (const toml::node* n = root.get("density")) {
      p.density = number(*n, "density");
      if (p.density < 0.0) fail(*n, "density", "must be >= 0 (0 = static), got {}", p.density);
    }
    if (const toml::node* n = root.get("gravity")) p.gravity = vector3(*n, "gravity");
    if (const toml::node* n = root.get("mass")) {
      const std::string s = string(*n, "mass");
      if (s == "lumped") {
        p.mass = model::MassKind::lumped;
      } else if (s == "consistent") {
        p.mass = model::MassKind::consistent;
      } else {
        fail(*n, "mass", "expected one of \"lumped\", \"consistent\", got \"{}\"", s);
      }
      if (p.mass == model::MassKind::consistent && p.density == 0.0) {
        fail(*n, "mass", "\"consistent\" needs density > 0 (a static problem has no inertia)");
      }
    }
    read_material(root, p);
    read_time(root, p);
    read_boundary(root, p);
    read_record_and_solver(root, p);
    check_drive_amplitudes(root, p);
    return p;
  }

 private:
  std::filesystem::path path_;
};

}  // namespace

VerifyProblem load_verify_problem(const std::filesystem::path& path) { return Reader(path).read(); }

ScalarDrive expression_drive(const std::string& expression) {
  auto drive = std::make_shared<ExpressionDrive>();
  drive->expression = expression;
  try {
    drive->parser.DefineVar("t", &drive->t);
    drive->parser.DefineConst("pi", std::numbers::pi);
    drive->parser.DefineConst("e", std::numbers::e);
    drive->parser.SetExpr(expression);
  } catch (const mu::ParserError& e) {
    throw_error("expression '{}': {}", expression, e.GetMsg());
  }
  drive->value(0.0);  // parses (muparser parses on first evaluation) and checks u(0) is finite
  return {[drive](double t) { return drive->value(t); }, [drive](double t) { return drive->rate(t); }};
}

Problem make_problem(const VerifyProblem& spec) {
  const std::string file = spec.file.string();
  Problem p;
  p.rest = spec.mesh.nodes;
  p.tets = spec.mesh.tets;
  try {
    p.tet_material.assign(static_cast<std::size_t>(p.num_tets()),
                          material::make_orthotropic_fung(spec.material, spec.normal));
  } catch (const Error& err) {
    throw_error("{}: [material]: {}", file, err.what());
  }
  p.mass = lumped_masses(p.rest, p.tets, spec.density);
  p.density = spec.density;
  p.mass_kind = spec.mass;
  p.gravity = spec.gravity;
  p.projection = spec.projection;
  auto nodes_of = [&](const std::string& group) -> const std::vector<int>& {
    const auto it = spec.mesh.node_groups.find(group);
    require(it != spec.mesh.node_groups.end(), "{}: no node group '{}' in the mesh {}", file, group,
            spec.mesh_path.string());
    return it->second;
  };
  try {
    for (const VerifyProblem::Fix& fix : spec.fixes) {
      for (const int v : nodes_of(fix.group)) p.dirichlet.add(v, fix.mask);
    }
    for (const VerifyProblem::Drive& drive : spec.drives) {
      p.dirichlet.drives.push_back(expression_drive(drive.expression));
      const int index = static_cast<int>(p.dirichlet.drives.size()) - 1;
      for (const int v : nodes_of(drive.group)) p.dirichlet.add(v, 1u << drive.axis, index);
    }
  } catch (const Error& err) {
    const std::string what = err.what();
    if (what.rfind(file, 0) == 0) throw;
    throw_error("{}: {}", file, what);
  }
  return p;
}

std::string_view to_string(VerifyProblem::Integrator integrator) {
  switch (integrator) {
    case VerifyProblem::Integrator::backward_euler:
      return "backward_euler";
    case VerifyProblem::Integrator::bdf2:
      return "bdf2";
    case VerifyProblem::Integrator::newmark:
      return "newmark";
    case VerifyProblem::Integrator::reference:
      return "reference";
  }
  return "backward_euler";
}

std::vector<int> record_nodes(const VerifyProblem& spec) {
  const auto it = spec.mesh.node_groups.find(spec.record_group);
  require(it != spec.mesh.node_groups.end(), "{}: no node group '{}' in the mesh {}", spec.file.string(),
          spec.record_group, spec.mesh_path.string());
  std::vector<int> nodes = it->second;
  std::sort(nodes.begin(), nodes.end());
  return nodes;
}

}  // namespace sflsh::fullspace
