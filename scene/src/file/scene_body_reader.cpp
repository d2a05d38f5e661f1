// Reading a scene's [[body]] entries, their skeleton and joint keys (scene_reader.hpp, docs/scenes.md).
#include "file/scene_reader.hpp"

#include <sflsh/body/body_model.hpp>
#include <sflsh/core/error.hpp>

#include <algorithm>
#include <map>
#include <string>

namespace sflsh::scene::detail {

namespace {

/// One of SMPL's joint names other than the root's.
bool below_the_root(const std::string& name) {
  return name != body::kJointNames[0] &&
         std::find(body::kJointNames.begin(), body::kJointNames.end(), name) != body::kJointNames.end();
}

}  // namespace

/// skeleton = "prescribed" | "tracking", tracking_stiffness [N/m], tracking_damping [N·s/m], root = "tracked" |
/// "free"; the tracking keys need skeleton = "tracking", which needs the reduced solver, lumped masses and
/// backward Euler.
void SceneReader::read_skeleton(const toml::table& t, const std::string& context, BodySpec& b) const {
  if (const toml::node* n = t.get("skeleton"))
    b.tracking = choice(*n, "skeleton", {"prescribed", "tracking"}, context) == "tracking";
  for (const char* key : {"tracking_stiffness", "tracking_damping", "root", "tracked_joints", "joint_frequency",
                          "joint_damping_ratio", "joint_limit", "joint_stiffness", "joint_damping", "joint_limits"}) {
    const toml::node* n = t.get(key);
    require(n == nullptr || b.tracking, "{}: '{}'{} needs skeleton = \"tracking\"", n ? at(*n) : std::string(), key,
            context);
  }
  if (const toml::node* n = t.get("tracking_stiffness"))
    b.tracking_stiffness = number_in(*n, "tracking_stiffness", context, 0.0, 1e6, "N/m");
  if (const toml::node* n = t.get("tracking_damping"))
    b.tracking_damping = number_in(*n, "tracking_damping", context, 0.0, 1e5, "N·s/m");
  if (const toml::node* n = t.get("root")) b.free_root = choice(*n, "root", {"tracked", "free"}, context) == "free";
  read_joints(t, context, b);
  if (!b.tracking) return;
  // The tracking skeleton is solved with backward Euler and lumped masses only (reduced_solver_root.cpp): a body
  // that names neither takes the paper's pair instead of the default BDF2 + consistent.
  if (t.get("integrator") == nullptr) b.integrator = model::kPaperIntegrator;
  if (t.get("mass") == nullptr) b.mass = model::kPaperMassKind;
  const toml::node& at_node = *t.get("skeleton");
  require(b.solver == SolverKind::reduced,
          "{}: skeleton = \"tracking\"{} needs solver = \"reduced\" (the full-space solver keeps prescribed bones)",
          at(at_node), context);
  require(b.mass == model::MassKind::lumped, "{}: skeleton = \"tracking\"{} needs mass = \"lumped\"", at(at_node),
          context);
  require(b.integrator == model::Integrator::backward_euler,
          "{}: skeleton = \"tracking\"{} needs integrator = \"backward_euler\"", at(at_node), context);
}

/// tracked_joints = "all" | "root" | [names], joint_frequency [Hz], joint_damping_ratio, joint_limit [rad] and the
/// per-joint tables joint_stiffness [N·m/rad], joint_damping [N·m·s/rad], joint_limits [rad].
void SceneReader::read_joints(const toml::table& t, const std::string& context, BodySpec& b) const {
  if (const toml::node* n = t.get("tracked_joints")) {
    if (const toml::array* list = n->as_array()) {
      b.all_joints = false;
      for (const toml::node& item : *list) b.tracked_joints.push_back(joint_name(item, "tracked_joints", context));
    } else {
      b.all_joints = choice(*n, "tracked_joints", {"all", "root"}, context) == "all";
    }
  }
  if (const toml::node* n = t.get("joint_frequency"))
    b.joint_frequency = number_in(*n, "joint_frequency", context, 0.05, 50.0, "Hz");
  if (const toml::node* n = t.get("joint_damping_ratio"))
    b.joint_damping_ratio = number_in(*n, "joint_damping_ratio", context, 0.0, 10.0, "");
  if (const toml::node* n = t.get("joint_limit"))
    b.joint_limit = number_in(*n, "joint_limit", context, 0.01, 3.0, "rad");
  const auto per_joint = [&](const char* key, double low, double high, const char* unit,
                             std::map<std::string, double>& out) {
    const toml::node* n = t.get(key);
    if (!n) return;
    const toml::table* entries = n->as_table();
    require(entries != nullptr, "{}: '{}'{} must be a table {{ joint_name = value, … }}", at(*n), key, context);
    for (const auto& [name, value] : *entries) {
      const std::string joint(name.str());
      require(below_the_root(joint),
              "{}: '{}'{}: '{}' is not a joint below the root (spine1, left_hip, …: docs/scenes.md)", at(value), key,
              context, joint);
      out[joint] = number_in(value, key, context, low, high, unit);
    }
  };
  per_joint("joint_stiffness", 0.0, 1e6, "N·m/rad", b.joint_stiffness);
  per_joint("joint_damping", 0.0, 1e5, "N·m·s/rad", b.joint_damping);
  per_joint("joint_limits", 0.01, 3.0, "rad", b.joint_limits);
}

std::string SceneReader::joint_name(const toml::node& node, std::string_view key, const std::string& context) const {
  const std::string name = string_value(node, key, context);
  require(below_the_root(name), "{}: '{}'{}: '{}' is not a joint below the root (spine1, left_hip, …: docs/scenes.md)",
          at(node), key, context, name);
  return name;
}

BodySpec SceneReader::read_body(const toml::node& node, std::size_t index) const {
  const toml::table* t = node.as_table();
  require(t != nullptr, "{}: 'body' must be an array of tables ([[body]])", at(node));
  const std::string context = fmt::format(" in body #{}", index);
  check_keys(*t,
             {"name",
              "body",
              "subject",
              "betas",
              "motion",
              "motion_offset",
              "approach",
              "placement",
              "solver",
              "mesh",
              "material",
              "control_points",
              "handles",
              "cubature",
              "density",
              "stiffness_scale",
              "integrator",
              "mass",
              "skeleton",
              "tracking_stiffness",
              "tracking_damping",
              "root",
              "tracked_joints",
              "joint_frequency",
              "joint_damping_ratio",
              "joint_limit",
              "joint_stiffness",
              "joint_damping",
              "joint_limits"},
             context);
  BodySpec b;
  b.line = static_cast<int>(t->source().begin.line);
  b.name = t->get("name") ? string_value(*t->get("name"), "name") : fmt::format("body{}", index);
  if (const toml::node* n = t->get("body")) b.body_path = relative(string_value(*n, "body"));
  if (const toml::node* n = t->get("subject")) b.subject = string_value(*n, "subject");
  if (const toml::node* n = t->get("betas")) {
    const toml::array* a = n->as_array();
    require(a != nullptr && !a->empty() && a->size() <= 10, "{}: 'betas'{} must be an array of 1 to 10 numbers", at(*n),
            context);
    std::vector<double> beta;
    for (const toml::node& v : *a) beta.push_back(number(v, "betas", context));
    b.betas = beta;
  }
  require(b.subject.empty() || !b.betas, "{}: give 'subject' or 'betas'{}, not both", at(node), context);
  if (const toml::node* n = t->get("motion")) {
    b.motion = string_value(*n, "motion");
    if (b.motion.ends_with(".npz")) b.motion = relative(b.motion);
  }
  if (const toml::node* n = t->get("motion_offset"))
    b.motion_offset = number_in(*n, "motion_offset", context, 0.0, kMaxMotionOffset, "s");
  if (const toml::node* n = t->get("approach")) b.approach = keyframes(*n, "approach", context, false);
  if (const toml::node* n = t->get("placement")) b.placement = placement(*n, context);
  if (const toml::node* n = t->get("solver")) b.solver = solver(*n, context);
  if (const toml::node* n = t->get("mesh")) b.mesh = choice(*n, "mesh", {"coarse", "default", "fine"}, context);
  if (const toml::node* n = t->get("material")) b.material = relative(string_value(*n, "material"));
  if (const toml::node* n = t->get("control_points")) b.control_points = count(*n, "control_points", context, 1);
  if (const toml::node* n = t->get("handles")) b.handles = count(*n, "handles", context, 1);
  if (const toml::node* n = t->get("cubature")) b.cubature = count(*n, "cubature", context, -1);
  if (const toml::node* n = t->get("density")) b.density = number_in(*n, "density", context, 1.0, 1e5, "kg/m³");
  if (const toml::node* n = t->get("stiffness_scale"))
    b.stiffness_scale = number_in(*n, "stiffness_scale", context, 1e-3, 1e3);
  if (const toml::node* n = t->get("integrator")) b.integrator = integrator(*n, context);
  if (const toml::node* n = t->get("mass")) b.mass = mass(*n, context);
  read_skeleton(*t, context, b);
  if (!b.body_path.empty()) input_file(*t->get("body"), "body", context, b.body_path, "a body model .npz file");
  if (!b.material.empty()) input_file(*t->get("material"), "material", context, b.material, "a material TOML file");
  if (b.motion.ends_with(".npz"))
    input_file(*t->get("motion"), "motion", context, b.motion, "an AMASS motion .npz file");
  return b;
}

}  // namespace sflsh::scene::detail
