// Reading a scene's [[object]] entries: shapes, their sizes and motions (scene_reader.hpp, docs/scenes.md).
#include "file/scene_reader.hpp"

#include <sflsh/core/error.hpp>

#include <string>
#include <utility>

namespace sflsh::scene::detail {

ObjectSpec SceneReader::read_object(const toml::node& node, std::size_t index) const {
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

}  // namespace sflsh::scene::detail
