#pragma once
// The on-disk cache of template layer meshes (one common discretization per body model, region,
// size and backend). A cache entry carries its key; an entry whose key no longer matches (the body
// model or the meshing code changed) is stale and is rebuilt; an unreadable entry is an error.
#include <sflsh/meshing/layer_mesh.hpp>

#include <filesystem>
#include <string>

namespace sflsh::meshing {

/// Bump when the meshing code changes what a cached mesh would contain.
inline constexpr int kLayerMeshFormat = 1;

/// A content hash (16 hex digits) of the arrays of a body model that the layer depends on.
std::string body_fingerprint(const body::BodyModel& model);

/// The key a mesh built from (model, options) carries: fingerprint, format, region, mesher, size, h.
std::string layer_cache_key(const body::BodyModel& model, const LayerMeshOptions& options);

/// $SFLSH_CACHE, else $XDG_CACHE_HOME/sflsh, else $HOME/.cache/sflsh, else <temp>/sflsh-cache.
std::filesystem::path default_cache_dir();

/// File of the cache entry for (model, options) inside `dir`.
std::filesystem::path layer_cache_path(const std::filesystem::path& dir, const body::BodyModel& model,
                                       const LayerMeshOptions& options);

/// .npz of a layer mesh, with its key. Writing is atomic.
void save_layer_mesh(const std::filesystem::path& path, const LayerMesh& mesh, const std::string& key);
/// Reads a layer mesh; throws "<path>: …" naming the key/array when the file is corrupt. `key` gets
/// the stored key.
LayerMesh load_layer_mesh(const std::filesystem::path& path, std::string* key = nullptr);

enum class CacheOutcome { hit, built, rebuilt_stale, rebuilt_forced };
const char* cache_outcome_name(CacheOutcome outcome);

/// The template layer for (model, options) from the cache in `dir`, built and stored when absent,
/// stale, or when `rebuild` is set. A corrupt entry throws (naming the file and suggesting
/// --rebuild-cache) unless `rebuild` is set.
LayerMesh cached_layer_mesh(const body::BodyModel& model, const LayerMeshOptions& options,
                            const std::filesystem::path& dir, bool rebuild = false, CacheOutcome* outcome = nullptr);

}  // namespace sflsh::meshing
