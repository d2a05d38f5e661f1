#pragma once
// Internal to the scene runner: what a scene writes. Each soft body's frames and σ map (model::SimulationWriter,
// placed where the body stands), each skinned body's posed surface, the objects' surfaces, and the collections
// that open the whole scene at once: scene.pvd (every body and the objects, in the world, per written frame)
// and scene_dynamics.pvd (every soft body's σ map where it stands). With [output] format = "xdmf" the series
// are <name>.xmf + <name>.h5 and there are no collections (ParaView's .pvd reader opens VTK XML files only).
#include "bodies/scene_internal.hpp"
#include "contact/scene_contact.hpp"
#include "objects/scene_objects.hpp"

#include <sflsh/core/background_jobs.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/core/xdmf_series.hpp>

#include <nlohmann/json.hpp>

#include <functional>
#include <memory>
#include <vector>

namespace sflsh::scene::detail {

class SceneOutput {
 public:
  /// `folder` null: nothing is written (σ is still accumulated); `jobs` null: files are written at once. The
  /// bodies, objects and contacts must outlive the output.
  SceneOutput(const Scene& scene, const std::vector<std::unique_ptr<SceneBody>>& bodies,
              const std::vector<SceneObject>& objects, const std::vector<BodyContact>& contact, RunFolder* folder,
              BackgroundJobs* jobs);
  /// Frame f at time t [s]: σ of every soft body; with `write` (and a folder) also the files of every body and
  /// of the objects (posed here, written by the jobs).
  void frame(int f, double t, bool write);
  /// Writes the series' indexes, the σ maps and the collections (after the jobs are done).
  void finish();
  /// σ statistics of soft body b (model::SimulationWriter::dynamics_summary).
  nlohmann::json dynamics_summary(std::size_t b) const;
  /// Seconds spent posing the written frames' surfaces (soft bodies' writers and skinned bodies).
  double posing_seconds() const;
  /// Seconds spent posing the skinned bodies.
  double skinning_seconds() const { return skinning_seconds_; }
  /// The summary's "output" entries of the collections (file names), empty without any.
  nlohmann::json collections() const;

 private:
  void write_skinned(std::size_t b, int f, double t);
  void write_objects(int f, double t);
  void submit(std::function<void()> job);
  bool xdmf() const { return scene_.output.format == "xdmf"; }

  const Scene& scene_;
  const std::vector<std::unique_ptr<SceneBody>>& bodies_;
  const std::vector<SceneObject>& objects_;
  const std::vector<BodyContact>& contact_;
  RunFolder* folder_;
  BackgroundJobs* jobs_;
  std::vector<std::unique_ptr<model::SimulationWriter>> writers_;  ///< per body; null for skinned bodies
  std::vector<std::unique_ptr<vtk::PvdSeries>> skinned_series_;    ///< per body; vtk format, skinned bodies
  std::vector<std::unique_ptr<xdmf::Series>> skinned_xdmf_;        ///< per body; xdmf format, skinned bodies
  std::unique_ptr<vtk::PvdSeries> objects_series_;
  std::unique_ptr<xdmf::Series> objects_xdmf_;
  std::unique_ptr<vtk::PvdSeries> scene_series_;  ///< scene.pvd (vtk format)
  double skinning_seconds_ = 0.0;
};

}  // namespace sflsh::scene::detail
