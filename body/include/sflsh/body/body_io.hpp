#pragma once
// Reading and writing body models as .npz in SMPL's key layout:
//   v_template (n, 3) f8 · f (m, 3) integer · shapedirs (n, 3, ≥10) f8 · posedirs (n, 3, 207) f8, optional ·
//   J_regressor (24, n) f8 (dense) · weights (n, 24) f8 · kintree_table (2, 24) integer, root parent
//   -1 or 4294967295 · joint_names (24,) optional, informational.
// Real SMPL .pkl files must be converted to .npz once (they are Python pickles); any float or
// integer dtype of the right shape is accepted.
#include <sflsh/body/body_model.hpp>

#include <cstddef>
#include <filesystem>

namespace sflsh::body {

/// Bounds on a body file, checked from the shapes before any array is converted: 4..1,000,000
/// vertices, 4..4,000,000 faces, 10..10,000 shape components; positions and displacements within
/// ±100 m (a body in metres; millimetre files are refused).
inline constexpr std::size_t kMaxBodyVertices = 1000000;
inline constexpr std::size_t kMaxBodyFaces = 4000000;
inline constexpr std::size_t kMaxShapeComponents = 10000;
inline constexpr double kMaxBodyMetres = 100.0;

/// Loads a body model; every missing key, wrong shape, dtype, index or value is a one-line
/// sflsh::Error "<file>: <key>: found, expected". The result is validated.
BodyModel load_body(const std::filesystem::path& path);

/// Saves a body model (atomic write).
void save_body(const std::filesystem::path& path, const BodyModel& model);

/// The path of the open body shipped in data/ (SFLSH_DATA_DIR or the SFLSH_DATA environment variable).
std::filesystem::path default_body_path();

/// The project's data directory: $SFLSH_DATA when set, else the source tree's data/ folder.
std::filesystem::path data_dir();

}  // namespace sflsh::body
