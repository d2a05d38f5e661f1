// sflsh simulate --solver full|reduced: the full-space reference solver or the reduced model on a subject's
// soft-tissue layer driven by a motion. Both write the posed body surface per frame exactly as `sflsh motion export`
// does (same points, same order, same .pvd layout), so that subtracting the two gives the soft-tissue motion.
#include "commands.hpp"
#include "layer_setup.hpp"
#include "simulate_run.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/scene/scene_file.hpp>
#include <sflsh/scene/scene_runner.hpp>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <memory>
#include <optional>

namespace sflsh::app {

namespace {

struct SimulateOptions {
  BodyRunSettings body;  ///< solver, subject, motion, frames, mesh, layer, integrator, reduced model
  bool no_output = false;
  int every = 1;  ///< write every N-th frame (the first and the last always)
  std::string out;
  // Scene files.
  std::string scene;
  int threads = 0;
  bool every_given = false;         ///< --every overrides the scene's [output] every
  bool format_given = false;        ///< --format overrides the scene's [output] format
  std::vector<std::string> fields;  ///< --fields: the arrays of the frames (when given)
  bool fields_given = false;
};

// sflsh simulate --scene FILE: bodies, objects and the effects the scene calls for (scene_runner.hpp).
void run_scene_file(const SimulateOptions& opt, const Invocation& invocation, int rank) {
  scene::Scene scene = scene::load_scene(opt.scene);
  if (opt.format_given) scene.output.format = opt.body.format;
  require(scene.output.format != "xdmf" || scene.output.series_compression != vtk::Compression::lz4,
          "--format xdmf: {}: [output] compression lz4 is not available for HDF5 datasets (expected zlib or none)",
          opt.scene);
  scene::SceneRunOptions options;
  options.frames = opt.body.frames;
  options.out = opt.out;
  options.cache_dir = opt.body.layer.cache;
  options.threads = opt.threads;
  options.write_frames = !opt.no_output;
  options.every = opt.every_given ? opt.every : 0;
  options.rank = rank;
  options.allow_long = opt.body.allow_long;
  options.header = summary_header("simulate", invocation.argc, invocation.argv);
  const nlohmann::json summary = scene::run_scene(scene, options);
  if (rank != 0) return;
  std::string effects;
  for (const auto& e : summary["effects"])
    effects += fmt::format("{}{} {:.2f} s", effects.empty() ? "" : ", ", e["name"].get<std::string>(),
                           e["seconds"].get<double>());
  logger()->info("scene '{}': {} frames in {:.1f} s ({}); wrote {}", scene.name, summary["scene"]["frames"].get<int>(),
                 summary["timings"]["loop_seconds"].get<double>(), effects, opt.out);
}

void run_simulate(const SimulateOptions& opt, const Invocation& invocation, int rank, int size) {
  const auto t_start = std::chrono::steady_clock::now();
  require(opt.every >= 1, "--every must be at least 1, got {}", opt.every);
  if (!opt.scene.empty()) return run_scene_file(opt, invocation, rank);
  require(!opt.body.motion.empty(), "simulate: --motion is required (or give a scene with --scene FILE)");
  std::optional<RunFolder> run;
  if (rank == 0) run.emplace(opt.out);
  const bool write = rank == 0 && !opt.no_output;
  nlohmann::json summary = summary_header("simulate", invocation.argc, invocation.argv);
  BodyRunSettings settings = opt.body;
  settings.every = opt.every;
  if (opt.fields_given)  // "all" is every array, whatever the format's default
    settings.fields = model::resolve_frame_fields(opt.fields, "--fields").value_or(model::frame_field_names());
  const nlohmann::json body = run_body_simulation(settings, write ? &*run : nullptr, rank, size);
  if (rank != 0) return;
  summary.update(body);
  summary["output"] =
      opt.no_output ? nlohmann::json("summary.json only") : run::simulate_output_summary(settings, body);
  summary.erase("compression");
  summary.erase("layer_compression");
  write_summary(*run, summary, seconds_since(t_start));
  run->commit();
  logger()->info("simulated {} frames in {:.1f} s ({:.3f} s per frame); mean σ = {:.2f} mm",
                 summary["motion"]["frames"].get<long>(), summary["timings"]["solve_seconds"].get<double>(),
                 summary["timings"]["seconds_per_frame"].get<double>(),
                 summary["dynamics"].value("sigma_mean_mm", 0.0));
}

}  // namespace

void register_simulate_commands(CLI::App& app, const Invocation& invocation) {
  auto opt = std::make_shared<SimulateOptions>();
  auto* cmd = app.add_subcommand(
      "simulate",
      "Simulate a subject's soft tissue along a motion and write the posed body surface per frame (as "
      "`sflsh motion export` does). PETSc options (-snes_*, -ksp_*, -pc_*) may follow; parallel with mpirun -n P.");
  cmd->add_option("--solver", opt->body.solver,
                  "Solver: full (the full-space reference) | reduced (handles + cubature)")
      ->check(CLI::IsMember({"full", "reduced"}));
  add_reduced_run_options(*cmd, opt->body);
  add_body_option(*cmd, opt->body.subject);
  add_subject_options(*cmd, opt->body.subject);
  cmd->add_option(
      "--scene", opt->scene,
      "Scene file (TOML, docs/scenes.md, data/scenes/): bodies, objects and effects; then only --frames, --every, "
      "--format, --out, --cache, --threads, --no-output and --allow-long apply");
  cmd->add_option("--threads", opt->threads, "Scenes: threads for bodies that do not interact (0: all cores)");
  cmd->add_option("--motion", opt->body.motion,
                  "Motion: a procedural name (sflsh motion list) or an AMASS .npz path (required without --scene)");
  add_frame_options(*cmd, opt->body.frames, opt->body.fps, opt->body.substeps);
  add_integrator_option(*cmd, opt->body.integrator);
  add_mesh_option(*cmd, opt->body.mesh);
  add_layer_options(*cmd, opt->body.layer);
  add_mass_option(*cmd, opt->body.layer);
  cmd->add_flag("--energies", opt->body.energies,
                "Record each frame's kinetic, elastic and gravitational energy over every tet in summary.json "
                "(frames[].energy, J); off by default: for the reduced model they cost about as much as its step");
  cmd->add_flag("--write-layer", opt->body.write_layer, "Also write the tet layer per frame (layer.xmf or layer.pvd)");
  cmd->add_option(
         "--format", opt->body.format,
         "Time series: xdmf (body.xmf + body.h5: triangles and fixed fields once, one compressed HDF5 dataset per "
         "field and frame; ParaView, meshio) | vtk (body.pvd of one .vtp per frame, layer.pvd of .vtu; "
         "docs/output.md); "
         "with --scene it overrides [output] format")
      ->check(CLI::IsMember({"vtk", "xdmf"}))
      ->capture_default_str()
      ->each([opt](const std::string&) { opt->format_given = true; });
  cmd->add_option("--precision", opt->body.precision,
                  "Floating-point precision of an xdmf series: float32 (display) | float64 (vtk frames are Float64)")
      ->check(CLI::IsMember({"float64", "float32"}))
      ->capture_default_str();
  cmd->add_option("--fields", opt->fields,
                  "The arrays of the body and layer frames, comma-separated: default (soft_tissue_displacement, "
                  "strain_energy_density, Normals and the fixed fields; the default for xdmf), all (the default "
                  "for vtk), or names of docs/output.md; as a scene's [output] fields")
      ->delimiter(',')
      ->each([opt](const std::string&) { opt->fields_given = true; });
  cmd->add_option(
         "--compression", opt->body.compression,
         "Compression: zlib | none for xdmf (default zlib: HDF5 shuffle + deflate); lz4 | zlib | none of every "
         "vtk frame file (default: LZ4 for the body's .vtp frames, zlib for the layer's .vtu frames, which "
         "meshio reads)")
      ->check(CLI::IsMember({"lz4", "zlib", "none"}));
  cmd->add_flag("--no-output", opt->no_output, "Write only summary.json");
  cmd->add_option(
         "--every", opt->every,
         "Write every N-th frame (frame 0 and the last frame always; σ and the summary still use every frame); "
         "with --scene it overrides [output] every")
      ->each([opt](const std::string&) { opt->every_given = true; });
  cmd->add_flag("--allow-long", opt->body.allow_long,
                "Run even when the work estimate (solver steps, bodies, body-frames, memory) exceeds the limits of "
                "docs/scenes.md (\"Input limits\")");
  cmd->add_option("--out", opt->out, "Output folder")->required();
  cmd->callback([opt, invocation] {
    with_petsc(invocation, [&](int rank, int size) { run_simulate(*opt, invocation, rank, size); });
  });
}

}  // namespace sflsh::app
