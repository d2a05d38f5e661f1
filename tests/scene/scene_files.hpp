#pragma once
// Scene files for the scene tests: written into a folder, and the message that loading one fails with.
#include <sflsh/core/error.hpp>
#include <sflsh/scene/scene_file.hpp>
#include <sflsh/scene/scene_runner.hpp>

#include <filesystem>
#include <fstream>
#include <string>

namespace sflsh::testing {

/// Writes `text` as dir/scene.toml (creating dir) and returns its path.
inline std::filesystem::path write_scene(const std::filesystem::path& dir, const std::string& text) {
  std::filesystem::create_directories(dir);
  const auto path = dir / "scene.toml";
  std::ofstream(path) << text;
  return path;
}

/// The message of load_scene's error ("" when it loads).
inline std::string load_error(const std::filesystem::path& path) {
  try {
    scene::load_scene(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

/// Runs `text` as dir/scene.toml on one thread with the tests' cache; writes into dir/out when `write`.
inline nlohmann::json run_scene_text(const std::filesystem::path& dir, const std::string& text, bool write = false) {
  scene::SceneRunOptions options;
  options.cache_dir = SFLSH_TEST_CACHE;
  if (write) options.out = dir / "out";
  options.threads = 1;
  return scene::run_scene(scene::load_scene(write_scene(dir, text)), options);
}

}  // namespace sflsh::testing
