// summary.json's body entries of a BodySimulation, its end (drain the frame writes, close the series) and the
// whole run of `sflsh simulate --solver full|reduced` and `sflsh sweep` (run_body_simulation).
#include <sflsh/core/error.hpp>
#include <sflsh/core/progress.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/model/time_integrator.hpp>
#include <sflsh/reduced/reduced_model.hpp>
#include <sflsh/reduced/reduced_solver.hpp>
#include <sflsh/run/body_simulation.hpp>

namespace sflsh::run {

namespace {}  // namespace

double BodySimulation::seconds() const { return seconds_since(t_start_); }

nlohmann::json BodySimulation::summary() const {
  const model::Integrator integrator = choice_.integrator;
  const double h = 1.0 / (motion_.fps * settings_.substeps);
  nlohmann::json summary = nlohmann::json::object();
  summary["compression"] = vtk::to_string(writer_options_.compression);
  summary["layer_compression"] = vtk::to_string(writer_options_.layer_compression);
  summary["integrator"] = model::to_string(integrator);
  summary["mass"] = model::to_string(layer_->problem.mass_kind);
  summary["solver"] = {{"name", settings_.solver},
                       {"integrator", model::to_string(integrator)},
                       {"startup_steps", total_.startup_steps},
                       {"processes", size_},
                       {"step", h},
                       {"substeps", settings_.substeps},
                       {"newton_iterations", total_.newton_iterations},
                       {"linear_iterations", total_.linear_iterations},
                       {"preconditioner_builds", total_.preconditioner_builds},
                       {"failed_attempts", total_.failed_attempts},
                       {"projected_retries", total_.projected_retries},
                       {"truncated_solves", total_.truncated_solves}};
  // The full-space CG's preconditioner as PETSc names it (automatic depends on the size and the process count).
  if (solver_.full) summary["solver"]["preconditioner"] = solver_.full->preconditioner_type();
  summary["body"] = body::body_label(settings_.subject);
  summary["subject"] = subject_label_;
  summary["beta"] = std::vector<double>(beta_.data(), beta_.data() + beta_.size());
  summary["motion"] = {
      {"name", motion_.name}, {"source", motion_.source}, {"fps", motion_.fps}, {"frames", motion_.num_frames()}};
  summary["mesh"] = {{"mesher", settings_.layer.mesher},
                     {"size", settings_.mesh},
                     {"nodes", layer_->problem.num_nodes()},
                     {"tets", layer_->problem.num_tets()},
                     {"constrained_dofs", layer_->problem.dirichlet.dof.size()},
                     // the template inverted tets at this shape and thickness: which layer replaced it
                     {"remeshed", layer_->remeshed},
                     {"fallback", layer_->fallback},
                     {"layer_mesher", meshing::mesher_name(layer_->mesh->mesher)}};
  summary["material"] = model::material_summary(settings_.layer, material_file_);
  if (reduced_model_) {
    summary["reduced"] = {
        {"point_handles", reduced_model_->handles.point_nodes.size()},
        {"bone_handles", reduced_model_->handles.bone_joints().size()},
        {"affine", settings_.affine},
        {"coordinates", reduced_model_->subspace.num_dofs()},
        {"basis_nonzeros", reduced_model_->subspace.basis.nonZeros()},
        {"cubature", solver_.reduced->cubature().size()},
        {"cubature_model", reduced_model_->cubature.size()},
        {"cubature_added", solver_.reduced->cubature_added()},
        {"cubature_method", reduced_model_->cubature.method},
        {"stiffness_ratio_max", reduced_model_->cubature.stiffness_ratio_max},
        {"stiffness_ratio_min", reduced_model_->cubature.stiffness_ratio_min},
        {"guard", solver_.reduced->guard()
                      ? nlohmann::json{{"exponent_limit", solver_.reduced->guard()->exponent_limit()},
                                       {"energy_limit_j", solver_.reduced->guard()->energy_limit()},
                                       {"smallest_tet_exponent_limit", solver_.reduced->guard()->smallest_tet_limit()},
                                       {"guarded_tets", solver_.reduced->guard()->num_guarded()},
                                       {"checks", solver_.reduced->guard()->checks()},
                                       {"per_tet_passes", solver_.reduced->guard()->tet_passes()},
                                       {"renewals", solver_.reduced->guard()->full_checks()},
                                       {"clusters", solver_.reduced->guard()->num_clusters()},
                                       {"cluster_renewals", solver_.reduced->guard()->cluster_renewals()},
                                       {"exact_evaluations", solver_.reduced->guard()->exact_evaluations()},
                                       {"pass_seconds", solver_.reduced->guard()->pass_seconds()},
                                       {"renew_seconds", solver_.reduced->guard()->renew_seconds()}}
                      : nlohmann::json(nullptr)},
        {"newton_tolerance_m", settings_.newton_tolerance},
        {"cache", reduced_model_->cache_outcome},
        {"factorizations", total_.factorizations},
        {"model_seconds", reduced_model_->build_seconds}};
  }
  summary["dynamics"] = writer_->dynamics_summary();
  summary["frames"] = frames_;
  const double steps = static_cast<double>(frame_);  // the frames solved (all of them after a whole run)
  summary["timings"] = {{"build_seconds", build_seconds_},
                        {"solve_seconds", total_.seconds},
                        {"function_seconds", total_.function_seconds},
                        {"jacobian_seconds", total_.jacobian_seconds},
                        {"model_seconds", model_seconds_},
                        {"elastic_seconds", total_.elastic_seconds},
                        {"inertia_seconds", total_.inertia_seconds},
                        {"potential_seconds", total_.potential_seconds},
                        {"dense_solve_seconds", total_.solve_seconds},
                        {"output_seconds", output_seconds_},
                        {"posing_seconds", writer_->posing_seconds()},
                        {"writer_seconds", jobs_ ? jobs_->busy_seconds() : 0.0},
                        {"writer_wait_seconds", jobs_ ? jobs_->waited_seconds() : 0.0},
                        {"frames_per_second", total_.seconds > 0 ? steps / total_.seconds : 0.0},
                        {"seconds_per_frame", steps > 0 ? total_.seconds / steps : 0.0}};
  set_total_seconds(summary, seconds());
  return summary;
}

nlohmann::json BodySimulation::finish() {
  require(!finished_output_, "simulate: finish() was called already");
  const auto t_drain = Clock::now();
  if (jobs_) jobs_->wait();
  output_seconds_ += seconds_since(t_drain);
  writer_->finish();
  finished_output_ = true;
  return summary();
}

nlohmann::json run_body_simulation(const BodyRunSettings& settings, RunFolder* frames_to, int rank, int size,
                                   const BodyRunReporting& reporting) {
  BodySimulation simulation(settings, frames_to, rank, size, reporting);
  const int frames = simulation.num_frames();
  Progress progress("frames", frames > 0 ? static_cast<std::size_t>(frames - 1) : 0, rank == 0 && reporting.progress);
  while (!simulation.finished()) {
    simulation.step();
    progress.advance();
    if (reporting.on_frame) reporting.on_frame(simulation.frame());
  }
  progress.finish();
  if (rank != 0) return {};
  return simulation.finish();
}

model::SimulationWriterOptions frame_writer_options(const BodyRunSettings& settings) {
  model::check_output_format(settings.format, "--format");
  model::SimulationWriterOptions options;
  options.write_layer = settings.write_layer;
  options.format = settings.format;
  options.precision = xdmf::parse_precision(settings.precision, "--precision");
  if (settings.fields) model::check_frame_field_names(*settings.fields, "--fields");
  options.fields = settings.fields;
  if (!settings.fields && settings.format == "xdmf") options.fields = model::default_frame_fields();
  if (!settings.compression.empty()) {
    const vtk::Compression asked = vtk::parse_compression(settings.compression, "--compression");
    require(settings.format != "xdmf" || asked != vtk::Compression::lz4,
            "--compression lz4: HDF5 has no LZ4 filter here (expected zlib or none for --format xdmf)");
    options.compression = options.layer_compression = options.series_compression = asked;
  }
  return options;
}

nlohmann::json simulate_output_summary(const BodyRunSettings& settings, const nlohmann::json& body_summary) {
  const bool xdmf = settings.format == "xdmf";
  const model::SimulationWriterOptions writer = frame_writer_options(settings);
  nlohmann::json output = {{"format", settings.format},
                           {"series", xdmf ? "body.xmf" : "body.pvd"},
                           {"layer", settings.write_layer ? (xdmf ? "layer.xmf" : "layer.pvd") : ""},
                           {"every", settings.every},
                           {"compression", xdmf ? vtk::to_string(writer.series_compression)
                                                : body_summary.value("compression", std::string("lz4"))},
                           {"precision", xdmf ? settings.precision : "float64"}};
  if (!xdmf && settings.write_layer)
    output["layer_compression"] = body_summary.value("layer_compression", std::string("zlib"));
  output["fields"] = writer.fields ? nlohmann::json(*writer.fields) : nlohmann::json("all");
  return output;
}

}  // namespace sflsh::run
