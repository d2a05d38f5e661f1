#pragma once
// Reading and writing body models as .npz in SMPL's key layout:
//   v_template (n, 3) f8 · f (m, 3) integer · shapedirs (n, 3, ≥10) f8 · posedirs (n, 3, 207) f8, optional ·
//   J_regressor (24, n) f8 (dense) · weights (n, 24) f8 · kintree_table (2, 24) integer, root parent
//   -1 or 4294967295 · joint_names (24,) optional, informational.
// Real SMPL .pkl files must be converted to .npz once (they are Python pickles); any float or
// integer dtype of the right shape is accepted.
#include <sflsh/body/body_model.hpp>

#include <filesystem>

namespace sflsh::body {

/// Loads a body model; every missing key, wrong shape or dtype is a one-line sflsh::Error naming the
/// file, the key and the expected shape. The result is validated.
BodyModel load_body(const std::filesystem::path& path);

/// Saves a body model (atomic write).
void save_body(const std::filesystem::path& path, const BodyModel& model);

/// The path of the open body shipped in data/ (SFLSH_DATA_DIR or the SFLSH_DATA environment variable).
std::filesystem::path default_body_path();

/// The project's data directory: $SFLSH_DATA when set, else the source tree's data/ folder.
std::filesystem::path data_dir();

}  // namespace sflsh::body
