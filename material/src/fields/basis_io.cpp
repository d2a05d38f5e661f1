// .npz cache of a biharmonic basis (biharmonic_basis.hpp: save_basis / load_basis).
#include <sflsh/core/error.hpp>
#include <sflsh/core/npz.hpp>
#include <sflsh/material/biharmonic_basis.hpp>

#include <cstdlib>

namespace sflsh::material {

namespace {

std::vector<std::int64_t> read_ints(const npz::Reader& in, const char* key, std::size_t expected) {
  const npz::Array a = in.read(key);
  require(a.shape.size() == 1 && a.shape[0] == expected, "{}: key '{}' has shape {}, expected ({},)",
          in.path().string(), key, a.shape_string(), expected);
  try {
    return a.to_int64();
  } catch (const Error& e) {
    throw_error("{}: key '{}': {}", in.path().string(), key, e.what());
  }
}

template <typename T>
std::vector<std::int64_t> as_int64(const std::vector<T>& values) {
  return {values.begin(), values.end()};
}

}  // namespace

void save_basis(const std::filesystem::path& path, const BiharmonicBasis& basis) {
  const auto N = static_cast<std::size_t>(basis.num_functions());
  require(basis.control_vertices.size() == N && basis.iterations.size() == N && basis.used_fallback.size() == N,
          "save_basis {}: inconsistent basis ({} columns, {} control vertices)", path.string(), N,
          basis.control_vertices.size());
  npz::write(path, {{"phi", npz::make_f64(basis.phi)},
                    {"control_vertices", npz::make_i64({N}, as_int64(basis.control_vertices))},
                    {"iterations", npz::make_i64({N}, as_int64(basis.iterations))},
                    {"used_fallback", npz::make_i64({N}, as_int64(basis.used_fallback))},
                    {"options", npz::make_i64({3}, {basis.bounded ? 1 : 0, basis.normalized ? 1 : 0,
                                                    basis.lumping == MassLumping::kVoronoi ? 0 : 1})},
                    {"surface_fingerprint", npz::make_string(fmt::format("{:016x}", basis.surface_fingerprint))}});
}

BiharmonicBasis load_basis(const std::filesystem::path& path) {
  const npz::Reader in(path);
  const npz::Array phi = in.read("phi");
  require(phi.shape.size() == 2 && phi.shape[0] > 0 && phi.shape[1] > 0 && phi.is_numeric(),
          "{}: key 'phi' has shape {} and dtype {}, expected a (#V, N) float array", path.string(), phi.shape_string(),
          phi.dtype());
  const std::size_t n = phi.shape[0], N = phi.shape[1];
  BiharmonicBasis basis;
  const std::vector<double> values = phi.to_doubles();
  basis.phi = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      values.data(), static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(N));
  require(basis.phi.allFinite(), "{}: key 'phi' holds non-finite values", path.string());
  for (const std::int64_t v : read_ints(in, "control_vertices", N)) {
    require(v >= 0 && v < static_cast<std::int64_t>(n), "{}: key 'control_vertices' holds {} outside [0, {})",
            path.string(), v, n);
    basis.control_vertices.push_back(static_cast<int>(v));
  }
  for (const std::int64_t k : read_ints(in, "iterations", N)) basis.iterations.push_back(static_cast<int>(k));
  for (const std::int64_t k : read_ints(in, "used_fallback", N)) basis.used_fallback.push_back(k != 0 ? 1 : 0);
  const std::vector<std::int64_t> flags = read_ints(in, "options", 3);
  require(flags[2] == 0 || flags[2] == 1, "{}: key 'options' has lumping {} (expected 0 or 1)", path.string(),
          flags[2]);
  basis.bounded = flags[0] != 0;
  basis.normalized = flags[1] != 0;
  basis.lumping = flags[2] == 0 ? MassLumping::kVoronoi : MassLumping::kBarycentric;
  const std::string hex = in.read("surface_fingerprint").to_string();
  char* end = nullptr;
  basis.surface_fingerprint = std::strtoull(hex.c_str(), &end, 16);
  require(hex.size() == 16 && end == hex.c_str() + hex.size(),
          "{}: key 'surface_fingerprint' is '{}', expected 16 hex digits", path.string(), hex);
  return basis;
}

}  // namespace sflsh::material
