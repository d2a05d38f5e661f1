// Reading scene files (scene_file.hpp, docs/scenes.md), errors as "<file>:<line>: …": the file, its [scene],
// [effects], [contact], [output] and [crowd] sections and the checks across them ([[body]] and [[object]]:
// scene_body_reader.cpp, scene_object_reader.cpp).
#include "file/scene_reader.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/scene/scene_file.hpp>

#include <cmath>
#include <set>

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

namespace detail {

Scene SceneReader::read() const {
  const toml::table root = parse("a scene TOML file");
  check_keys(root, {"scene", "effects", "body", "object", "contact", "crowd", "output"}, "");
  Scene scene;
  scene.file = path();
  read_header(required(root, "scene", ""), scene);
  if (const toml::node* node = root.get("effects")) read_effects(*node, scene.effects);
  if (const toml::node* node = root.get("contact")) read_contact(*node, scene.contact);
  if (const toml::node* node = root.get("output")) read_output(*node, scene.output);
  // Bodies and objects share one name space.
  std::set<std::string> names;
  const auto read_named = [&](const char* key, auto reader, auto& out) {
    const toml::node* node = root.get(key);
    if (!node) return;
    const toml::array* list = node->as_array();
    require(list != nullptr, "{}: '{}' must be an array of tables ([[{}]])", at(*node), key, key);
    for (std::size_t i = 0; i < list->size(); ++i) {
      out.push_back((this->*reader)((*list)[i], i));
      require(names.insert(out.back().name).second, "{}: the name '{}' is used twice", at((*list)[i]), out.back().name);
    }
  };
  read_named("body", &SceneReader::read_body, scene.bodies);
  read_named("object", &SceneReader::read_object, scene.objects);
  if (const toml::node* node = root.get("crowd")) scene.crowd = read_crowd(*node);
  check_scene(root, scene);
  return scene;
}

std::string SceneReader::relative(const std::string& file) const {
  const std::filesystem::path p(file);
  return p.is_absolute() ? file : (path().parent_path() / p).lexically_normal().string();
}

/// A file named by `key`: "<scene>:<line>: <key><context>: <path>: is a directory, expected …" when it cannot be
/// read.
void SceneReader::input_file(const toml::node& node, std::string_view key, std::string_view context,
                             const std::string& file, std::string_view what) const {
  try {
    require_input_file(file, what);
  } catch (const Error& e) {
    fail(node, fmt::format("{}{}", key, context), "{}", e.what());
  }
}

int SceneReader::count(const toml::node& node, std::string_view key, std::string_view context, int minimum) const {
  const std::int64_t v = integer(node, key, context);
  require(v >= minimum && v <= 1'000'000, "{}: '{}'{} = {} must be an integer in [{}, 10⁶]", at(node), key, context, v,
          minimum);
  return static_cast<int>(v);
}

std::string SceneReader::choice(const toml::node& node, std::string_view key,
                                std::initializer_list<std::string_view> allowed, std::string_view context) const {
  const std::string value = string_value(node, key);
  std::string list;
  for (const std::string_view a : allowed) {
    if (value == a) return value;
    list += (list.empty() ? "" : " | ") + std::string(a);
  }
  throw_error("{}: '{}'{} = '{}' is not one of {}", at(node), key, context, value, list);
}

model::Integrator SceneReader::integrator(const toml::node& node, std::string_view context) const {
  return model::parse_integrator(choice(node, "integrator", {"backward_euler", "bdf2", "newmark"}, context),
                                 "integrator");
}

model::MassKind SceneReader::mass(const toml::node& node, std::string_view context) const {
  return model::parse_mass_kind(choice(node, "mass", {"lumped", "consistent"}, context), "mass");
}

SolverKind SceneReader::solver(const toml::node& node, std::string_view context) const {
  const std::string s = choice(node, "solver", {"full", "reduced", "skinned"}, context);
  return s == "full" ? SolverKind::full : s == "reduced" ? SolverKind::reduced : SolverKind::skinned;
}

void SceneReader::read_header(const toml::node& node, Scene& scene) const {
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

void SceneReader::read_effects(const toml::node& node, Effects& effects) const {
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
  if (const toml::node* n = t.get("body_contact")) effects.body_contact = boolean(*n, "body_contact", " in [effects]");
  if (const toml::node* n = t.get("self_contact")) {
    require(!boolean(*n, "self_contact", " in [effects]"),
            "{}: 'self_contact' = true is not available: a body's layer against its own other parts is not simulated "
            "(docs/scenes.md); remove it or set it to false",
            at(*n));
  }
}

void SceneReader::read_contact(const toml::node& node, ContactSpec& contact) const {
  const toml::table& t = table(node, "contact");
  check_keys(t,
             {"stiffness", "tolerance", "margin", "max_refinements", "max_exchanges", "exchange_tolerance",
              "body_exchange", "object_coupling", "local_resolution", "local_spacing", "local_depth", "local_reach",
              "local_free_objects", "local_max_nodes"},
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

void SceneReader::read_output(const toml::node& node, OutputSpec& output) const {
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

std::vector<SceneKeyframe> SceneReader::keyframes(const toml::node& node, std::string_view key,
                                                  std::string_view context, bool with_rotation) const {
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

Placement SceneReader::placement(const toml::node& node, std::string_view context) const {
  const toml::table& t = table(node, "placement");
  check_keys(t, {"position", "yaw"}, fmt::format(" in 'placement'{}", context));
  Placement p;
  if (const toml::node* n = t.get("position"))
    p.position = bounded3(*n, "position", context, kPlausibleMaxPosition, "m");
  if (const toml::node* n = t.get("yaw")) p.yaw_degrees = number(*n, "yaw", context);
  return p;
}

CrowdSpec SceneReader::read_crowd(const toml::node& node) const {
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
void SceneReader::check_scene(const toml::table& root, const Scene& scene) const {
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
    require(scene.crowd->solver != SolverKind::full, "{}:{}: a [crowd] runs the reduced solver or skinning, not 'full'",
            path().string(), scene.crowd->line);
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

}  // namespace detail

Scene load_scene(const std::filesystem::path& path) { return detail::SceneReader(path).read(); }

}  // namespace sflsh::scene
