#pragma once
// Runs a scene (scene_file.hpp): builds only what its effects ask for and steps every body together.
//   - no elastic effect (inertia, gravity, contact) → every body is only skinned: no layer, no solve;
//   - no inertia → quasi-static solves; a quasi-static body without gravity whose contact finds no candidate in
//     a step is at rest and is not solved;
//   - no contact effect → no contact potential and no proximity structure is ever built;
//   - object contact: each soft body gets a penalty potential against the scene's objects (placed in the body's
//     frame); body contact: against the other bodies' posed surfaces, one Gauss–Seidel sweep per step (bodies
//     solved earlier are seen at the step's end, later ones predicted), or with [contact] body_exchange = true
//     exchanged within the step until the touching bodies agree (group_step.cpp, exchange_accelerator.hpp; the
//     order of the bodies plays no part).
//     Skeletons follow their motions: contact moves soft tissue only.
// Output in the run folder: <body>.pvd / <body>_NNNNNN.vtp per body in world coordinates (with contact_force
// and penetration fields when contact is on), objects.pvd, summary.json with "effects" (the effects that ran
// and their time).
#include <sflsh/core/work_limit.hpp>
#include <sflsh/scene/scene_file.hpp>

#include <nlohmann/json.hpp>

#include <filesystem>

namespace sflsh::scene {

struct SceneRunOptions {
  int frames = 0;                   ///< > 0 overrides the scene's frame count
  std::filesystem::path out;        ///< run folder; empty: nothing is written
  std::filesystem::path cache_dir;  ///< template meshes and reduced models; empty: the default
  std::filesystem::path data_dir;   ///< the project's data folder (default shape model of crowds)
  int threads = 0;                  ///< bodies solved in parallel when they do not interact (0: all cores)
  bool write_frames = true;         ///< false: summary.json only
  int every = 0;                    ///< > 0 overrides the scene's [output] every (write every N-th frame)
  bool background_writing = true;   ///< false: frame files are written on the stepping thread
  /// true: bodies that cannot touch each other in a step form separate groups stepped in parallel; false: one
  /// group of all bodies (the reference the groups must reproduce exactly).
  bool group_bodies = true;
  bool allow_long = false;  ///< run even when the work estimate exceeds WorkLimits (--allow-long)
  int rank = 0;             ///< MPI rank: only rank 0 writes
  nlohmann::json header;    ///< summary header (command line, versions)
};

/// The size of the run before anything is built: bodies (the crowd's count included), their solver steps
/// (elastic bodies only: frames × substeps each) and body-frames, and the per-frame data held for the run.
WorkEstimate estimate_scene_work(const Scene& scene, const SceneRunOptions& options);

/// Runs the scene; returns the summary (also written as summary.json). Throws sflsh::Error naming the body,
/// object or file on failure; nothing is left in the output folder then.
nlohmann::json run_scene(const Scene& scene, const SceneRunOptions& options);

}  // namespace sflsh::scene
