#pragma once
// Shared test inputs for the meshing tests: the open body and its coarse template layer meshes,
// taken from a cache folder in the build tree so that the many test processes mesh only once.
#include <sflsh/body/body_io.hpp>
#include <sflsh/meshing/layer_cache.hpp>

#include <filesystem>
#include <map>

namespace sflsh::testing {

inline const body::BodyModel& open_body() {
  static const body::BodyModel model = body::load_body(std::filesystem::path(SFLSH_DATA_DIR) / "open_body.npz");
  return model;
}

inline meshing::LayerMeshOptions coarse_options(meshing::Mesher mesher) {
  meshing::LayerMeshOptions options;
  options.mesher = mesher;
  options.size = meshing::SizePreset::coarse;
  return options;
}

/// The coarse template layer of the open body for one backend (cached in the build tree).
inline const meshing::LayerMesh& coarse_layer(meshing::Mesher mesher) {
  static std::map<meshing::Mesher, meshing::LayerMesh> meshes;
  auto it = meshes.find(mesher);
  if (it == meshes.end())
    it =
        meshes.emplace(mesher, meshing::cached_layer_mesh(open_body(), coarse_options(mesher), SFLSH_TEST_CACHE)).first;
  return it->second;
}

}  // namespace sflsh::testing
