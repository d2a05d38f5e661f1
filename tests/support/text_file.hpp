#pragma once
// Writes a text file (replacing it) and returns its path.
#include <filesystem>
#include <fstream>
#include <string>

namespace sflsh::testing {

inline std::filesystem::path write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::trunc) << text;
  return path;
}

}  // namespace sflsh::testing
