// The work estimate of a scene run, checked before anything is built (scene_runner.hpp, docs/scenes.md).
#include <sflsh/scene/scene_runner.hpp>

#include <algorithm>

namespace sflsh::scene {

namespace {

/// Bytes held per body and output frame for the whole run: the body's motion sample (72 pose values and a
/// root translation) and its per-frame records (curve, σ, summary), rounded up.
constexpr double kBytesPerBodyFrame = 1024.0;

}  // namespace

WorkEstimate estimate_scene_work(const Scene& scene, const SceneRunOptions& options) {
  const double frames =
      options.frames > 0 ? static_cast<double>(options.frames) : static_cast<double>(scene.num_frames());
  double bodies = static_cast<double>(scene.bodies.size());
  double elastic = 0.0;  // bodies that are solved, not only skinned
  if (scene.effects.elastic())
    for (const BodySpec& b : scene.bodies) elastic += b.solver != SolverKind::skinned ? 1.0 : 0.0;
  if (scene.crowd) {
    bodies += static_cast<double>(scene.crowd->count);
    if (scene.effects.elastic() && scene.crowd->solver != SolverKind::skinned)
      elastic += static_cast<double>(scene.crowd->count);
  }
  WorkEstimate e;
  e.bodies = bodies;
  e.steps = elastic * std::max(0.0, frames - 1.0) * static_cast<double>(scene.substeps);
  e.body_frames = bodies * frames;
  e.bytes = e.body_frames * kBytesPerBodyFrame;
  return e;
}

}  // namespace sflsh::scene
