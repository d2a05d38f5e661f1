// Strict .obj reading (obj_file.hpp).
#include "file/obj_file.hpp"

#include <sflsh/core/error.hpp>

#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace sflsh::scene::detail {

namespace {

struct Face {
  std::vector<long long> index;  // 0-based into the file's vertices (relative indices resolved)
  int line = 0;
};

bool parse_number(const std::string& token, double& out) {
  const char* begin = token.data();
  if (!token.empty() && token.front() == '+') ++begin;
  const auto [end, ec] = std::from_chars(begin, token.data() + token.size(), out);
  return ec == std::errc() && end == token.data() + token.size();
}

}  // namespace

ObjMesh read_obj(const std::filesystem::path& path) {
  std::ifstream in(path);
  require(in.good(), "{}: cannot be read, expected a .obj mesh file", path.string());
  const std::string file = path.string();
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Face> faces;
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    if (const std::size_t hash = text.find('#'); hash != std::string::npos) text.resize(hash);
    std::istringstream tokens(text);
    std::string keyword;
    if (!(tokens >> keyword)) continue;
    if (keyword == "v") {
      Eigen::Vector3d x;
      for (int c = 0; c < 3; ++c) {
        std::string token;
        double value = 0.0;
        if (!(tokens >> token) || !parse_number(token, value) || !std::isfinite(value))
          throw_error("{}:{}: v: coordinate {} is '{}', expected a finite number", file, line, c + 1, token);
        // Within a kilometre of the file's origin even in millimetres (files in mm come with scale = 0.001):
        // ±10⁶ file units (docs/scenes.md, "Input limits").
        if (std::abs(value) > 1e6)
          throw_error("{}:{}: v: coordinate {} is {}, expected a number in [-1e6, 1e6] (file units, before 'scale')",
                      file, line, c + 1, token);
        x[c] = value;
      }
      vertices.push_back(x);
    } else if (keyword == "f") {
      Face face;
      face.line = line;
      for (std::string token; tokens >> token;) {
        long long i = 0;
        const std::string first = token.substr(0, token.find('/'));
        const auto [end, ec] = std::from_chars(first.data(), first.data() + first.size(), i);
        if (ec != std::errc() || end != first.data() + first.size() || i == 0)
          throw_error("{}:{}: f: '{}' is not a vertex index (1-based, or negative counting back)", file, line, token);
        // Negative indices count back from the vertices read so far.
        face.index.push_back(i > 0 ? i - 1 : static_cast<long long>(vertices.size()) + i);
      }
      if (face.index.size() < 3)
        throw_error("{}:{}: f: a face needs at least 3 vertices, got {}", file, line, face.index.size());
      faces.push_back(std::move(face));
    }
  }
  require(!faces.empty(), "{}: f: no faces, expected a closed triangle mesh", file);
  const auto count = static_cast<long long>(vertices.size());
  for (const Face& f : faces)
    for (const long long i : f.index)
      if (i < 0 || i >= count)
        throw_error("{}:{}: f: vertex index {} is outside the file's {} vertices", file, f.line,
                    i >= 0 ? i + 1 : i - count, count);

  // Merge exactly coincident vertices (files that repeat a vertex per face), keep only used ones.
  std::map<std::array<double, 3>, int> merged;
  std::vector<Eigen::Vector3d> kept;
  std::vector<std::array<int, 3>> triangles;
  auto id = [&](long long i) {
    const Eigen::Vector3d& x = vertices[static_cast<std::size_t>(i)];
    const auto [it, inserted] = merged.try_emplace({x.x(), x.y(), x.z()}, static_cast<int>(kept.size()));
    if (inserted) kept.push_back(x);
    return it->second;
  };
  for (const Face& f : faces) {
    for (std::size_t k = 1; k + 1 < f.index.size(); ++k) {  // a fan around the first vertex
      const std::array<int, 3> t = {id(f.index[0]), id(f.index[k]), id(f.index[k + 1])};
      if (t[0] != t[1] && t[1] != t[2] && t[2] != t[0]) triangles.push_back(t);
    }
  }
  require(!triangles.empty(), "{}: f: every face is degenerate (repeats a vertex)", file);
  ObjMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(kept.size()), 3);
  for (std::size_t v = 0; v < kept.size(); ++v) mesh.vertices.row(static_cast<Eigen::Index>(v)) = kept[v].transpose();
  mesh.triangles.resize(static_cast<Eigen::Index>(triangles.size()), 3);
  for (std::size_t t = 0; t < triangles.size(); ++t)
    mesh.triangles.row(static_cast<Eigen::Index>(t)) << triangles[t][0], triangles[t][1], triangles[t][2];
  return mesh;
}

}  // namespace sflsh::scene::detail
