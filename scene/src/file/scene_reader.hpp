#pragma once
// Internal to scene-file reading: the reader of one scene TOML file, a reader per section (scene_file.cpp: the
// header, effects, contact, output and crowd sections and the shared checks; scene_body_reader.cpp: [[body]];
// scene_object_reader.cpp: [[object]]).
#include <sflsh/core/toml_reader.hpp>
#include <sflsh/model/mass.hpp>
#include <sflsh/model/time_integrator.hpp>
#include <sflsh/scene/scene_file.hpp>

#include <cstddef>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

namespace sflsh::scene::detail {

// Plausible ranges of a scene's physical inputs (docs/scenes.md, "Input limits"): a body is ~2 m tall, objects
// from a tenth of a millimetre to a room, everything within a kilometre of the origin, no faster than 100 m/s.
inline constexpr double kPlausibleMinSize = 1e-4;        // [m]
inline constexpr double kPlausibleMaxSize = 100.0;       // [m]
inline constexpr double kPlausibleMaxPosition = 1000.0;  // [m] per component
inline constexpr double kPlausibleMaxSpeed = 100.0;      // [m/s] per component

class SceneReader : public TomlReader {
 public:
  using TomlReader::TomlReader;

  Scene read() const;

 private:
  // Values every section reads (scene_file.cpp).
  std::string relative(const std::string& file) const;
  void input_file(const toml::node& node, std::string_view key, std::string_view context, const std::string& file,
                  std::string_view what) const;
  int count(const toml::node& node, std::string_view key, std::string_view context, int minimum) const;
  std::string choice(const toml::node& node, std::string_view key, std::initializer_list<std::string_view> allowed,
                     std::string_view context) const;
  model::Integrator integrator(const toml::node& node, std::string_view context) const;
  model::MassKind mass(const toml::node& node, std::string_view context) const;
  SolverKind solver(const toml::node& node, std::string_view context) const;
  std::vector<SceneKeyframe> keyframes(const toml::node& node, std::string_view key, std::string_view context,
                                       bool with_rotation) const;
  Placement placement(const toml::node& node, std::string_view context) const;

  // The sections (scene_file.cpp).
  void read_header(const toml::node& node, Scene& scene) const;
  void read_effects(const toml::node& node, Effects& effects) const;
  void read_contact(const toml::node& node, ContactSpec& contact) const;
  void read_output(const toml::node& node, OutputSpec& output) const;
  CrowdSpec read_crowd(const toml::node& node) const;
  void check_scene(const toml::table& root, const Scene& scene) const;

  // [[body]] (scene_body_reader.cpp).
  BodySpec read_body(const toml::node& node, std::size_t index) const;
  void read_skeleton(const toml::table& t, const std::string& context, BodySpec& b) const;
  void read_joints(const toml::table& t, const std::string& context, BodySpec& b) const;
  std::string joint_name(const toml::node& node, std::string_view key, const std::string& context) const;

  // [[object]] (scene_object_reader.cpp).
  ObjectSpec read_object(const toml::node& node, std::size_t index) const;
};

}  // namespace sflsh::scene::detail
