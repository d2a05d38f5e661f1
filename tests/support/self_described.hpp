#pragma once
// Checks that an output file describes its arrays (docs/output.md): the field data `units` has exactly one
// entry "<name>: <unit>" per numeric array name, every unit known (not "?"); label arrays come with their
// names. Read back with VTK's own readers.
#include <sflsh/core/vtk_io.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <string>

namespace sflsh::testing {

/// The `units` field data of a .vtp/.vtu as name → unit.
inline std::map<std::string, std::string> units_of(const std::filesystem::path& path) {
  std::map<std::string, std::string> out;
  for (const std::string& entry : vtk::read_field_strings(path, "units")) {
    const std::size_t colon = entry.find(": ");
    EXPECT_NE(colon, std::string::npos) << path << ": " << entry;
    if (colon == std::string::npos) continue;
    EXPECT_FALSE(out.count(entry.substr(0, colon))) << path << ": twice " << entry;
    out[entry.substr(0, colon)] = entry.substr(colon + 2);
  }
  return out;
}

/// Every numeric array of the file has a known unit in `units`, and `units` names no other array.
inline void expect_self_described(const std::filesystem::path& path) {
  SCOPED_TRACE(path.string());
  const std::map<std::string, std::string> units = units_of(path);
  std::set<std::string> arrays;
  for (const auto& n : vtk::read_point_array_names(path)) arrays.insert(n);
  for (const auto& n : vtk::read_cell_array_names(path)) arrays.insert(n);
  for (const auto& n : vtk::read_field_array_names(path)) arrays.insert(n);
  for (const char* strings : {"units", "part_names", "node_kind_names"}) arrays.erase(strings);
  for (const std::string& name : arrays) {
    ASSERT_TRUE(units.count(name)) << "no unit for " << name;
    EXPECT_NE(units.at(name), "?") << name;
  }
  for (const auto& [name, unit] : units) EXPECT_TRUE(arrays.count(name)) << "unit of a missing array " << name;
}

/// A label array's values are 0 … size − 1 of its names `<names>` (field data).
inline void expect_labels_named(const std::filesystem::path& path, const Eigen::MatrixXd& values,
                                const std::string& names) {
  const std::vector<std::string> labels = vtk::read_field_strings(path, names);
  ASSERT_GT(values.size(), 0);
  EXPECT_GE(values.minCoeff(), 0.0) << names;
  EXPECT_LT(values.maxCoeff(), static_cast<double>(labels.size())) << names;
  for (const std::string& l : labels) EXPECT_FALSE(l.empty()) << names;
}

}  // namespace sflsh::testing
