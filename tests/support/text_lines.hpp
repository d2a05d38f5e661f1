#pragma once
// The lines of a text file (an empty list when it cannot be read).
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace sflsh::testing {

inline std::vector<std::string> lines_of(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

}  // namespace sflsh::testing
