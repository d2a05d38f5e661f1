// What a scene writes (scene_output.hpp).
#include "runner/scene_output.hpp"

#include "bodies/body_skeleton.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/scoped_seconds.hpp>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>

namespace sflsh::scene::detail {

namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

SceneOutput::SceneOutput(const Scene& scene, const std::vector<std::unique_ptr<SceneBody>>& bodies,
                         const std::vector<SceneObject>& objects, const std::vector<BodyContact>& contact,
                         RunFolder* folder, BackgroundJobs* jobs)
    : scene_(scene), bodies_(bodies), objects_(objects), contact_(contact), folder_(folder), jobs_(jobs) {
  model::check_output_format(scene_.output.format, "[output] format");
  writers_.resize(bodies_.size());
  skinned_series_.resize(bodies_.size());
  skinned_xdmf_.resize(bodies_.size());
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    SceneBody& body = *bodies_[b];
    if (body.soft()) {
      model::SimulationWriterOptions o;
      o.prefix = body.name();
      o.write_layer = scene_.output.layer;
      o.rotation = body.placement().R;
      o.translation = body.placement().t;
      o.fields = scene_.output.fields;
      o.compression = scene_.output.compression;
      o.layer_compression = scene_.output.layer_compression;
      o.series_compression = scene_.output.series_compression;
      o.precision = scene_.output.precision;
      o.format = scene_.output.format;
      o.jobs = jobs_;
      writers_[b] = std::make_unique<model::SimulationWriter>(body.layer(), folder_, o);
    } else if (folder_ && xdmf()) {
      folder_->stage(body.name() + ".h5");
      skinned_xdmf_[b] = std::make_unique<xdmf::Series>(folder_->stage(body.name() + ".xmf"), body.model().faces,
                                                        scene_.output.precision, scene_.output.series_compression);
    } else if (folder_) {
      skinned_series_[b] = std::make_unique<vtk::PvdSeries>(folder_->stage(body.name() + ".pvd"));
    }
  }
  if (!folder_) return;
  if (!objects_.empty() && xdmf()) {
    Eigen::MatrixXd ids;
    const Surface surface = merged_object_surfaces(objects_, ids);  // the objects' triangles do not change
    folder_->stage("objects.h5");
    objects_xdmf_ = std::make_unique<xdmf::Series>(folder_->stage("objects.xmf"), surface.triangles,
                                                   scene_.output.precision, scene_.output.series_compression);
    vtk::Fields fixed;
    fixed.cell_data.push_back({"object_id", ids, true});
    objects_xdmf_->set_static(fixed);
  } else if (!objects_.empty()) {
    objects_series_ = std::make_unique<vtk::PvdSeries>(folder_->stage("objects.pvd"));
  }
  if (!xdmf()) scene_series_ = std::make_unique<vtk::PvdSeries>(folder_->stage("scene.pvd"));
}

void SceneOutput::frame(int f, double t, bool write) {
  write = write && folder_;
  if (!write) {
    // Only σ: each soft body's skin displacement, independent of the others (in parallel, like the steps).
    tbb::parallel_for(std::size_t{0}, bodies_.size(), [&](std::size_t b) {
      if (bodies_[b]->soft() && bodies_[b]->solver() != SolverKind::full)
        writers_[b]->add_positions(f, t, bodies_[b]->positions(), false);
    });
    for (std::size_t b = 0; b < bodies_.size(); ++b)
      if (bodies_[b]->solver() == SolverKind::full) writers_[b]->add_frame(f, t, bodies_[b]->state(), false);
    return;
  }
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    SceneBody& body = *bodies_[b];
    if (body.soft()) {
      const std::vector<vtk::Field> extra = contact_fields(contact_[b], body);
      if (body.tracking())  // the frame moves with the skeleton: its deviation per vertex, then the placement
        writers_[b]->set_frame_deviation(
            body.surface_deviation(), scene_.output.layer ? body.node_deviation() : std::vector<reduced::Matrix34d>{});
      if (scene_.output.layer)
        writers_[b]->add_frame(f, t, body.state(), true, extra);  // layer frames need the full state
      else
        writers_[b]->add_positions(f, t, body.positions(), true, extra);
    } else {
      write_skinned(b, f, t);
    }
    // Soft and skinned bodies' frames are both <name>_NNNNNN.vtp, in the world.
    if (scene_series_)
      scene_series_->add(t, fmt::format("{}_{:06d}.vtp", body.name(), f), static_cast<int>(b), body.name());
  }
  if (!objects_.empty()) write_objects(f, t);
}

void SceneOutput::write_skinned(std::size_t b, int f, double t) {
  const SceneBody& body = *bodies_[b];
  const auto clock = Clock::now();
  RowMatrixX3d posed = body.world_surface();
  skinning_seconds_ += seconds_since(clock);
  vtk::Fields fields;
  fields.field_data.push_back({"TimeValue", Eigen::MatrixXd::Constant(1, 1, t), false});
  if (xdmf::Series* series = skinned_xdmf_[b].get()) {
    submit([series, t, posed = std::move(posed), &faces = body.model().faces, fields = std::move(fields)]() mutable {
      fields.point_data.push_back({"Normals", vtk::vertex_normals(posed, faces), false});
      series->write(t, posed, fields);
    });
    return;
  }
  const std::string name = fmt::format("{}_{:06d}.vtp", body.name(), f);
  skinned_series_[b]->add(t, name);
  submit([path = folder_->stage(name), posed = std::move(posed), &faces = body.model().faces,
          fields = std::move(fields),
          this] { vtk::write_surface(path, posed, faces, fields, scene_.output.compression); });
}

void SceneOutput::write_objects(int f, double t) {
  Eigen::MatrixXd ids;
  Surface surface = merged_object_surfaces(objects_, ids);
  vtk::Fields fields;
  if (objects_xdmf_) {
    submit([series = objects_xdmf_.get(), t, surface = std::move(surface), fields = std::move(fields)]() mutable {
      fields.point_data.push_back({"Normals", vtk::vertex_normals(surface.vertices, surface.triangles), false});
      series->write(t, surface.vertices, fields);
    });
    return;
  }
  fields.cell_data.push_back({"object_id", ids, true});
  fields.field_data.push_back({"TimeValue", Eigen::MatrixXd::Constant(1, 1, t), false});
  const std::string name = fmt::format("objects_{:06d}.vtp", f);
  objects_series_->add(t, name);
  if (scene_series_) scene_series_->add(t, name, static_cast<int>(bodies_.size()), "objects");
  submit([path = folder_->stage(name), surface = std::move(surface), fields = std::move(fields), this] {
    vtk::write_surface(path, surface.vertices, surface.triangles, fields, scene_.output.compression);
  });
}

void SceneOutput::submit(std::function<void()> job) {
  if (jobs_)
    jobs_->submit(std::move(job));
  else
    job();
}

void SceneOutput::finish() {
  if (!folder_) return;
  vtk::PvdSeries maps(folder_->stage("scene_dynamics.pvd"));
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    if (writers_[b]) {
      writers_[b]->finish();
      maps.add_untimed(writers_[b]->dynamics_file(), static_cast<int>(maps.size()), bodies_[b]->name());
    }
    if (bodies_[b]->tracking())
      write_deviation_csv(folder_->stage(bodies_[b]->name() + "_skeleton.csv"), bodies_[b]->skeleton(),
                          bodies_[b]->deviation_history());
    if (skinned_series_[b]) skinned_series_[b]->write();
    if (skinned_xdmf_[b]) skinned_xdmf_[b]->close();
  }
  if (objects_series_) objects_series_->write();
  if (objects_xdmf_) objects_xdmf_->close();
  if (scene_series_) scene_series_->write();
  if (!xdmf() && maps.size() > 0) maps.write();
}

nlohmann::json SceneOutput::dynamics_summary(std::size_t b) const { return writers_[b]->dynamics_summary(); }

double SceneOutput::posing_seconds() const {
  double seconds = skinning_seconds_;
  for (const auto& w : writers_)
    if (w) seconds += w->posing_seconds();
  return seconds;
}

nlohmann::json SceneOutput::collections() const {
  nlohmann::json j = nlohmann::json::array();
  if (!folder_ || xdmf()) return j;
  j.push_back("scene.pvd");
  if (std::any_of(writers_.begin(), writers_.end(), [](const auto& w) { return w != nullptr; }))
    j.push_back("scene_dynamics.pvd");
  return j;
}

}  // namespace sflsh::scene::detail
