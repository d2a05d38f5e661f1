// Reading scene files (scene_file.hpp, docs/scenes.md), errors as "<file>:<line>: …".
#include <sflsh/body/body_model.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/toml_reader.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/scene/scene_file.hpp>

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>

namespace sflsh::scene {

const char* solver_name(SolverKind kind) {
  switch (kind) {
    case SolverKind::full:
      return "full";
    case SolverKind::reduced:
      return "reduced";
    case SolverKind::skinned:
      return "skinned";
  }
  return "?";
}

const char* shape_name(ShapeKind kind) {
  switch (kind) {
    case ShapeKind::plane:
      return "plane";
    case ShapeKind::sphere:
      return "sphere";
    case ShapeKind::box:
      return "box";
    case ShapeKind::capsule:
      return "capsule";
    case ShapeKind::mesh:
      return "mesh";
  }
  return "?";
}

const char* object_motion_name(ObjectMotionKind kind) {
  switch (kind) {
    case ObjectMotionKind::fixed:
      return "fixed";
    case ObjectMotionKind::prescribed:
      return "prescribed";
    case ObjectMotionKind::free:
      return "free";
  }
  return "?";
}

int Scene::num_frames() const {
  if (frames > 0) return frames;
  return static_cast<int>(std::floor(duration * fps + 1e-9)) + 1;
}

namespace {

// Plausible ranges of a scene's physical inputs (docs/scenes.md, "Input limits"): a body is ~2 m tall, objects
// from a tenth of a millimetre to a room, everything within a kilometre of the origin, no faster than 100 m/s.
constexpr double kPlausibleMinSize = 1e-4;        // [m]
constexpr double kPlausibleMaxSize = 100.0;       // [m]
constexpr double kPlausibleMaxPosition = 1000.0;  // [m] per component
constexpr double kPlausibleMaxSpeed = 100.0;      // [m/s] per component

class SceneReader : public TomlReader {
 public:
  using TomlReader::TomlReader;

  Scene read() const {
    const toml::table root = parse("a scene TOML file");
    check_keys(root, {"scene", "effects", "body", "object", "contact", "crowd", "output"}, "");
    Scene scene;
    scene.file = path();
    read_header(required(root, "scene", ""), scene);
    if (const toml::node* node = root.get("effects")) read_effects(*node, scene.effects);
    if (const toml::node* node = root.get("contact")) read_contact(*node, scene.contact);
    if (const toml::node* node = root.get("output")) read_output(*node, scene.output);
    std::set<std::string> names;
    if (const toml::node* node = root.get("body")) {
      const toml::array* list = node->as_array();
      require(list != nullptr, "{}: 'body' must be an array of tables ([[body]])", at(*node));
      for (std::size_t i = 0; i < list->size(); ++i) {
        scene.bodies.push_back(read_body((*list)[i], i));
        require(names.insert(scene.bodies.back().name).second, "{}: the name '{}' is used twice", at((*list)[i]),
                scene.bodies.back().name);
      }
    }
    if (const toml::node* node = root.get("object")) {
      const toml::array* list = node->as_array();
      require(list != nullptr, "{}: 'object' must be an array of tables ([[object]])", at(*node));
      for (std::size_t i = 0; i < list->size(); ++i) {
        scene.objects.push_back(read_object((*list)[i], i));
        require(names.insert(scene.objects.back().name).second, "{}: the name '{}' is used twice", at((*list)[i]),
                scene.objects.back().name);
      }
    }
    if (const toml::node* node = root.get("crowd")) scene.crowd = read_crowd(*node);
    check_scene(root, scene);
    return scene;
  }

 private:
  std::string relative(const std::string& file) const {
    const std::filesystem::path p(file);
    return p.is_absolute() ? file : (path().parent_path() / p).lexically_normal().string();
  }

  /// A file named by `key`: "<scene>:<line>: <key><context>: <path>: is a directory, expected …" when it cannot be
  /// read.
  void input_file(const toml::node& node, std::string_view key, std::string_view context, const std::string& file,
                  std::string_view what) const {
    try {
      require_input_file(file, what);
    } catch (const Error& e) {
      fail(node, fmt::format("{}{}", key, context), "{}", e.what());
    }
  }

  int count(const toml::node& node, std::string_view key, std::string_view context, int minimum) const {
    const std::int64_t v = integer(node, key, context);
    require(v >= minimum && v <= 1'000'000, "{}: '{}'{} = {} must be an integer in [{}, 10⁶]", at(node), key, context,
            v, minimum);
    return static_cast<int>(v);
  }

  std::string choice(const toml::node& node, std::string_view key, std::initializer_list<std::string_view> allowed,
                     std::string_view context) const {
    const std::string value = string_value(node, key);
    std::string list;
    for (const std::string_view a : allowed) {
      if (value == a) return value;
      list += (list.empty() ? "" : " | ") + std::string(a);
    }
    throw_error("{}: '{}'{} = '{}' is not one of {}", at(node), key, context, value, list);
  }

  model::Integrator integrator(const toml::node& node, std::string_view context) const {
    return model::parse_integrator(choice(node, "integrator", {"backward_euler", "bdf2", "newmark"}, context),
                                   "integrator");
  }
  model::MassKind mass(const toml::node& node, std::string_view context) const {
    return model::parse_mass_kind(choice(node, "mass", {"lumped", "consistent"}, context), "mass");
  }

  SolverKind solver(const toml::node& node, std::string_view context) const {
    const std::string s = choice(node, "solver", {"full", "reduced", "skinned"}, context);
    return s == "full" ? SolverKind::full : s == "reduced" ? SolverKind::reduced : SolverKind::skinned;
  }

  void read_header(const toml::node& node, Scene& scene) const {
    const toml::table& t = table(node, "scene");
    check_keys(t, {"name", "fps", "frames", "duration", "substeps"}, " in [scene]");
    scene.name = t.get("name") ? string_value(*t.get("name"), "name") : path().stem().string();
    if (const toml::node* n = t.get("fps")) scene.fps = positive(*n, "fps", " in [scene]");
    if (const toml::node* n = t.get("frames")) scene.frames = count(*n, "frames", " in [scene]", 1);
    if (const toml::node* n = t.get("duration")) {
      scene.duration = positive(*n, "duration", " in [scene]");
      number_in(*n, "duration", " in [scene]", 0.0, kMaxSceneDuration, "s");
    }
    if (const toml::node* n = t.get("substeps")) scene.substeps = count(*n, "substeps", " in [scene]", 1);
    require(scene.fps <= 10000.0, "{}: 'fps' = {} is beyond 10000", at(t), scene.fps);
  }

  void read_effects(const toml::node& node, Effects& effects) const {
    const toml::table& t = table(node, "effects");
    check_keys(t, {"inertia", "gravity", "gravity_direction", "object_contact", "body_contact", "self_contact"},
               " in [effects]");
    if (const toml::node* n = t.get("inertia")) effects.inertia = boolean(*n, "inertia", " in [effects]");
    if (const toml::node* n = t.get("gravity")) effects.gravity = boolean(*n, "gravity", " in [effects]");
    if (const toml::node* n = t.get("gravity_direction")) {
      const Eigen::Vector3d d = vector3(*n, "gravity_direction", " in [effects]");
      require(d.norm() > 1e-12, "{}: 'gravity_direction' in [effects] must not be zero", at(*n));
      effects.gravity_direction = d.normalized();
    }
    if (const toml::node* n = t.get("object_contact"))
      effects.object_contact = boolean(*n, "object_contact", " in [effects]");
    if (const toml::node* n = t.get("body_contact"))
      effects.body_contact = boolean(*n, "body_contact", " in [effects]");
    if (const toml::node* n = t.get("self_contact")) {
      require(!boolean(*n, "self_contact", " in [effects]"),
              "{}: 'self_contact' = true is not available: a body's layer against its own other parts is not simulated "
              "(docs/scenes.md); remove it or set it to false",
              at(*n));
    }
  }

  void read_contact(const toml::node& node, ContactSpec& contact) const {
    const toml::table& t = table(node, "contact");
    check_keys(
        t,
        {"stiffness", "tolerance", "margin", "max_refinements", "max_exchanges", "exchange_tolerance", "body_exchange",
         "object_coupling", "local_resolution", "local_spacing", "local_depth", "local_reach", "local_free_objects"},
        " in [contact]");
    if (const toml::node* n = t.get("stiffness")) contact.stiffness = non_negative(*n, "stiffness", " in [contact]");
    if (const toml::node* n = t.get("tolerance")) contact.tolerance = positive(*n, "tolerance", " in [contact]");
    if (const toml::node* n = t.get("margin")) contact.margin = non_negative(*n, "margin", " in [contact]");
    if (const toml::node* n = t.get("max_refinements"))
      contact.max_refinements = count(*n, "max_refinements", " in [contact]", 0);
    if (const toml::node* n = t.get("max_exchanges"))
      contact.max_exchanges = count(*n, "max_exchanges", " in [contact]", 1);
    if (const toml::node* n = t.get("body_exchange"))
      contact.body_exchange = boolean(*n, "body_exchange", " in [contact]");
    if (const toml::node* n = t.get("exchange_tolerance"))
      contact.exchange_tolerance = positive(*n, "exchange_tolerance", " in [contact]");
    if (const toml::node* n = t.get("object_coupling"))
      contact.object_coupling = choice(*n, "object_coupling", {"monolithic", "staggered"}, " in [contact]");
    if (const toml::node* n = t.get("local_resolution"))
      contact.local_resolution = boolean(*n, "local_resolution", " in [contact]");
    if (const toml::node* n = t.get("local_spacing"))
      contact.local_spacing = non_negative(*n, "local_spacing", " in [contact]");
    if (const toml::node* n = t.get("local_depth"))
      contact.local_depth = non_negative(*n, "local_depth", " in [contact]");
    if (const toml::node* n = t.get("local_reach"))
      contact.local_reach = non_negative(*n, "local_reach", " in [contact]");
    if (const toml::node* n = t.get("local_free_objects"))
      contact.local_free_objects = boolean(*n, "local_free_objects", " in [contact]");
    if (const toml::node* n = t.get("local_max_nodes"))
      contact.local_max_nodes = count(*n, "local_max_nodes", " in [contact]", 0);
  }

  void read_output(const toml::node& node, OutputSpec& output) const {
    const toml::table& t = table(node, "output");
    check_keys(t, {"layer", "frames", "every", "fields", "compression", "format", "precision"}, " in [output]");
    if (const toml::node* n = t.get("layer")) output.layer = boolean(*n, "layer", " in [output]");
    if (const toml::node* n = t.get("frames")) output.frames = boolean(*n, "frames", " in [output]");
    if (const toml::node* n = t.get("every")) output.every = count(*n, "every", " in [output]", 1);
    if (const toml::node* n = t.get("fields")) {
      std::vector<std::string> names;
      const toml::array* list = n->as_array();
      require(list != nullptr, "{}: 'fields' in [output] must be an array of strings", at(*n));
      for (const toml::node& item : *list) names.push_back(string_value(item, "fields", " in [output]"));
      output.fields = model::resolve_frame_fields(names, at(*n), " in 'fields' of [output]");
    }
    if (const toml::node* n = t.get("compression")) {  // asked for: every frame file, the layer's too
      output.compression =
          vtk::parse_compression(choice(*n, "compression", {"lz4", "zlib", "none"}, " in [output]"), "compression");
      output.layer_compression = output.series_compression = output.compression;
    }
    if (const toml::node* n = t.get("format")) output.format = choice(*n, "format", {"vtk", "xdmf"}, " in [output]");
    if (const toml::node* n = t.get("compression"); n && output.format == "xdmf")
      require(output.compression != vtk::Compression::lz4,
              "{}: 'compression' in [output]: lz4 is not available for the HDF5 datasets of format xdmf (expected zlib "
              "or none)",
              at(*n));
    if (const toml::node* n = t.get("precision"))
      output.precision =
          xdmf::parse_precision(choice(*n, "precision", {"float64", "float32"}, " in [output]"), "precision");
  }

  std::vector<SceneKeyframe> keyframes(const toml::node& node, std::string_view key, std::string_view context,
                                       bool with_rotation) const {
    const toml::array* list = node.as_array();
    require(list != nullptr && list->size() >= 2,
            "{}: '{}'{} must be an array of at least two tables {{ t = …, position = [x, y, z] }}", at(node), key,
            context);
    std::vector<SceneKeyframe> out;
    for (const toml::node& item : *list) {
      const toml::table* k = item.as_table();
      require(k != nullptr, "{}: each entry of '{}'{} must be a table {{ t = …, position = […] }}", at(item), key,
              context);
      if (with_rotation)
        check_keys(*k, {"t", "position", "rotation"}, fmt::format(" in '{}'{}", key, context));
      else
        check_keys(*k, {"t", "position"}, fmt::format(" in '{}'{}", key, context));
      SceneKeyframe f;
      f.t = non_negative(required(*k, "t", context), "t", context);
      f.position = bounded3(required(*k, "position", context), "position", context, kPlausibleMaxPosition, "m");
      if (const toml::node* r = k->get("rotation")) f.rotation = vector3(*r, "rotation", context);
      require(out.empty() || f.t > out.back().t, "{}: keyframe times in '{}'{} must increase ({} after {})", at(item),
              key, context, f.t, out.empty() ? 0.0 : out.back().t);
      out.push_back(f);
    }
    return out;
  }

  Placement placement(const toml::node& node, std::string_view context) const {
    const toml::table& t = table(node, "placement");
    check_keys(t, {"position", "yaw"}, fmt::format(" in 'placement'{}", context));
    Placement p;
    if (const toml::node* n = t.get("position"))
      p.position = bounded3(*n, "position", context, kPlausibleMaxPosition, "m");
    if (const toml::node* n = t.get("yaw")) p.yaw_degrees = number(*n, "yaw", context);
    return p;
  }

  /// skeleton = "prescribed" | "tracking", tracking_stiffness [N/m], tracking_damping [N·s/m], root = "tracked" |
  /// "free"; the tracking keys need skeleton = "tracking", which needs the reduced solver, lumped masses and
  /// backward Euler.
  void read_skeleton(const toml::table& t, const std::string& context, BodySpec& b) const {
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
  void read_joints(const toml::table& t, const std::string& context, BodySpec& b) const {
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

  /// One of SMPL's joint names other than the root's.
  static bool below_the_root(const std::string& name) {
    return name != body::kJointNames[0] &&
           std::find(body::kJointNames.begin(), body::kJointNames.end(), name) != body::kJointNames.end();
  }

  std::string joint_name(const toml::node& node, std::string_view key, const std::string& context) const {
    const std::string name = string_value(node, key, context);
    require(below_the_root(name),
            "{}: '{}'{}: '{}' is not a joint below the root (spine1, left_hip, …: docs/scenes.md)", at(node), key,
            context, name);
    return name;
  }

  BodySpec read_body(const toml::node& node, std::size_t index) const {
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
      require(a != nullptr && !a->empty() && a->size() <= 10, "{}: 'betas'{} must be an array of 1 to 10 numbers",
              at(*n), context);
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

  ObjectSpec read_object(const toml::node& node, std::size_t index) const {
    const toml::table* t = node.as_table();
    require(t != nullptr, "{}: 'object' must be an array of tables ([[object]])", at(node));
    const std::string context = fmt::format(" in object #{}", index);
    check_keys(*t,
               {"name", "shape", "radius", "length", "half_extents", "normal", "file", "scale", "position", "rotation",
                "motion", "keyframes", "smooth", "mass", "velocity", "density", "angular_velocity", "friction"},
               context);
    ObjectSpec o;
    o.line = static_cast<int>(t->source().begin.line);
    o.name = t->get("name") ? string_value(*t->get("name"), "name") : fmt::format("object{}", index);
    const std::string shape =
        choice(required(*t, "shape", context), "shape", {"plane", "sphere", "box", "capsule", "mesh"}, context);
    o.shape = shape == "plane"     ? ShapeKind::plane
              : shape == "sphere"  ? ShapeKind::sphere
              : shape == "box"     ? ShapeKind::box
              : shape == "capsule" ? ShapeKind::capsule
                                   : ShapeKind::mesh;
    auto only_for = [&](std::string_view key, std::initializer_list<ShapeKind> kinds) {
      const toml::node* n = t->get(key);
      if (!n) return n;
      bool ok = false;
      for (ShapeKind k : kinds) ok = ok || k == o.shape;
      require(ok, "{}: '{}'{} does not apply to a {}", at(*n), key, context, shape);
      return n;
    };
    if (const toml::node* n = only_for("radius", {ShapeKind::sphere, ShapeKind::capsule}))
      o.radius = bounded(*n, "radius", context, kPlausibleMinSize, kPlausibleMaxSize, "m");
    if (const toml::node* n = only_for("length", {ShapeKind::capsule}))
      o.length = bounded(*n, "length", context, kPlausibleMinSize, kPlausibleMaxSize, "m");
    if (const toml::node* n = only_for("half_extents", {ShapeKind::box})) {
      o.half_extents = vector3(*n, "half_extents", context);
      require(o.half_extents.minCoeff() >= kPlausibleMinSize && o.half_extents.maxCoeff() <= kPlausibleMaxSize,
              "{}: 'half_extents'{} = [{}, {}, {}] must have components in [{}, {}] m", at(*n), context,
              o.half_extents.x(), o.half_extents.y(), o.half_extents.z(), kPlausibleMinSize, kPlausibleMaxSize);
    }
    if (const toml::node* n = only_for("normal", {ShapeKind::plane})) {
      o.normal = vector3(*n, "normal", context);
      require(o.normal.norm() > 1e-12, "{}: 'normal'{} must not be zero", at(*n), context);
      o.normal.normalize();
    }
    if (const toml::node* n = only_for("file", {ShapeKind::mesh})) {
      o.mesh_path = relative(string_value(*n, "file"));
      input_file(*n, "file", context, o.mesh_path, "a triangle mesh file (.obj, .stl, .ply)");
    }
    if (const toml::node* n = only_for("scale", {ShapeKind::mesh}))
      o.scale = bounded(*n, "scale", context, 1e-6, 1e3, "(a factor)");
    require(o.shape != ShapeKind::mesh || !o.mesh_path.empty(), "{}: a mesh object needs 'file'{}", at(node), context);
    // The size of every shape is given, never a silent default (docs/scenes.md).
    const std::pair<ShapeKind, const char*> needed[] = {{ShapeKind::sphere, "radius"},
                                                        {ShapeKind::capsule, "radius"},
                                                        {ShapeKind::capsule, "length"},
                                                        {ShapeKind::box, "half_extents"},
                                                        {ShapeKind::plane, "normal"}};
    for (const auto& [kind, key] : needed)
      if (o.shape == kind && t->get(key) == nullptr)
        fail(node, fmt::format("{}{}", key, context), "missing (a {} needs it)", shape);
    if (const toml::node* n = t->get("position"))
      o.position = bounded3(*n, "position", context, kPlausibleMaxPosition, "m");
    if (const toml::node* n = t->get("rotation")) o.rotation = vector3(*n, "rotation", context);
    if (const toml::node* n = t->get("motion")) {
      const std::string m = choice(*n, "motion", {"fixed", "prescribed", "free"}, context);
      o.motion = m == "fixed"        ? ObjectMotionKind::fixed
                 : m == "prescribed" ? ObjectMotionKind::prescribed
                                     : ObjectMotionKind::free;
    }
    const toml::node* keys = t->get("keyframes");
    if (o.motion == ObjectMotionKind::prescribed) {
      require(keys != nullptr, "{}: a prescribed object needs 'keyframes'{}", at(node), context);
      o.keyframes = keyframes(*keys, "keyframes", context, true);
    } else {
      require(keys == nullptr, "{}: 'keyframes'{} need motion = \"prescribed\"", keys ? at(*keys) : at(node), context);
    }
    if (const toml::node* n = t->get("smooth")) o.smooth = boolean(*n, "smooth", context);
    for (const char* key : {"mass", "velocity", "density", "angular_velocity", "friction"}) {
      const toml::node* n = t->get(key);
      require(n == nullptr || o.motion == ObjectMotionKind::free, "{}: '{}'{} needs motion = \"free\"",
              n ? at(*n) : at(node), key, context);
    }
    if (const toml::node* n = t->get("mass")) o.mass = bounded(*n, "mass", context, 1e-6, 1e4, "kg");
    if (const toml::node* n = t->get("velocity"))
      o.velocity = bounded3(*n, "velocity", context, kPlausibleMaxSpeed, "m/s");
    if (const toml::node* n = t->get("density")) {
      require(t->get("mass") == nullptr, "{}: give 'mass' [kg] or 'density' [kg/m³]{}, not both", at(*n), context);
      o.density = bounded(*n, "density", context, 1.0, 1e5, "kg/m^3");
    }
    if (const toml::node* n = t->get("angular_velocity"))
      o.angular_velocity = bounded3(*n, "angular_velocity", context, 1e3, "rad/s");
    if (const toml::node* n = t->get("friction")) {
      o.friction = number(*n, "friction", context);
      require(o.friction >= 0.0 && o.friction <= 10.0, "{}: 'friction'{} = {} must be in [0, 10] (Coulomb μ)", at(*n),
              context, o.friction);
    }
    require(o.motion != ObjectMotionKind::free || o.shape != ShapeKind::plane, "{}: a plane cannot be free{}", at(node),
            context);
    return o;
  }

  CrowdSpec read_crowd(const toml::node& node) const {
    const toml::table& t = table(node, "crowd");
    const std::string_view context = " in [crowd]";
    check_keys(t,
               {"count", "seed", "shape_sigma", "motion", "max_offset", "spacing", "columns", "shape_model", "solver",
                "mesh", "handles", "cubature", "integrator", "mass"},
               context);
    CrowdSpec c;
    c.line = static_cast<int>(t.source().begin.line);
    if (const toml::node* n = t.get("count")) c.count = count(*n, "count", context, 1);
    if (const toml::node* n = t.get("seed")) c.seed = static_cast<std::uint64_t>(count(*n, "seed", context, 0));
    if (const toml::node* n = t.get("shape_sigma")) c.shape_sigma = non_negative(*n, "shape_sigma", context);
    if (const toml::node* n = t.get("motion")) {
      c.motion = string_value(*n, "motion");
      if (c.motion.ends_with(".npz")) {
        c.motion = relative(c.motion);
        input_file(*n, "motion", context, c.motion, "an AMASS motion .npz file");
      }
    }
    if (const toml::node* n = t.get("max_offset"))
      c.max_offset = number_in(*n, "max_offset", context, 0.0, kMaxMotionOffset, "s");
    if (const toml::node* n = t.get("spacing"))
      c.spacing = bounded(*n, "spacing", context, kPlausibleMinSize, kPlausibleMaxSize, "m");
    if (const toml::node* n = t.get("columns")) c.columns = count(*n, "columns", context, 1);
    if (const toml::node* n = t.get("shape_model")) {
      c.shape_model = relative(string_value(*n, "shape_model"));
      input_file(*n, "shape_model", context, c.shape_model, "a shape-model TOML file");
    }
    if (const toml::node* n = t.get("solver")) c.solver = solver(*n, context);
    if (const toml::node* n = t.get("mesh")) c.mesh = choice(*n, "mesh", {"coarse", "default", "fine"}, context);
    if (const toml::node* n = t.get("handles")) c.handles = count(*n, "handles", context, 1);
    if (const toml::node* n = t.get("cubature")) c.cubature = count(*n, "cubature", context, -1);
    if (const toml::node* n = t.get("integrator")) c.integrator = integrator(*n, context);
    if (const toml::node* n = t.get("mass")) c.mass = mass(*n, context);
    return c;
  }

  // Effects that cannot act, and combinations the simulator does not offer.
  void check_scene(const toml::table& root, const Scene& scene) const {
    const toml::node& where = root.get("effects") ? *root.get("effects") : static_cast<const toml::node&>(root);
    require(!scene.bodies.empty() || scene.crowd, "{}: the scene has no [[body]] and no [crowd]", path().string());
    require(!scene.effects.object_contact || !scene.objects.empty(),
            "{}: 'object_contact' is on but the scene has no [[object]]", at(where));
    const std::size_t bodies = scene.bodies.size() + (scene.crowd ? static_cast<std::size_t>(scene.crowd->count) : 0);
    require(!scene.effects.body_contact || bodies >= 2,
            "{}: 'body_contact' is on but the scene has fewer than two bodies", at(where));
    if (scene.crowd) {
      require(
          !scene.effects.body_contact && !scene.effects.object_contact,
          "{}:{}: a [crowd] runs without contact (its avatars stand apart); switch object_contact and body_contact off",
          path().string(), scene.crowd->line);
      require(scene.crowd->solver != SolverKind::full,
              "{}:{}: a [crowd] runs the reduced solver or skinning, not 'full'", path().string(), scene.crowd->line);
    }
    for (const BodySpec& b : scene.bodies)
      require(!b.tracking || scene.effects.inertia,
              "{}:{}: body '{}' has skeleton = \"tracking\", which needs [effects] inertia = true (the skeleton's "
              "inertia)",
              path().string(), b.line, b.name);
    for (const ObjectSpec& o : scene.objects) {
      require(o.motion != ObjectMotionKind::free || scene.effects.object_contact,
              "{}:{}: object '{}' is free, which needs object_contact (nothing else acts on it but gravity)",
              path().string(), o.line, o.name);
    }
  }
};

}  // namespace

Scene load_scene(const std::filesystem::path& path) { return SceneReader(path).read(); }

}  // namespace sflsh::scene
