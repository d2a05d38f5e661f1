// Simulation.write: the run folder of `sflsh simulate` from the states a Python simulation recorded. The frames go
// through the same SimulationWriter the command line runs, with the same placement of the written frames
// (model::is_written_frame), so a folder written from Python opens and compares exactly like the command's.
#include "simulation_object.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/core/xdmf_series.hpp>
#include <sflsh/model/simulation_output.hpp>

namespace sflsh::python {

void PythonSimulation::step() {
  simulation->step();
  if (record) states.push_back(simulation->state());
}

void write_run_folder(const PythonSimulation& python, const std::filesystem::path& dir, const WriteOptions& options) {
  const run::BodySimulation& sim = *python;
  require(python.record, "write: the simulation was made with record=False and kept no frames to write");
  require(static_cast<int>(python.states.size()) == sim.frame() + 1, "write: {} recorded states for frames 0 … {}",
          python.states.size(), sim.frame());
  require(options.every >= 1, "--every must be at least 1, got {}", options.every);
  run::BodyRunSettings settings = sim.settings();
  settings.format = options.format;
  settings.write_layer = options.write_layer;
  settings.every = options.every;
  settings.precision = options.precision;
  settings.compression = options.compression;
  settings.fields =
      options.fields
          ? std::optional(model::resolve_frame_fields(*options.fields, "fields").value_or(model::frame_field_names()))
          : std::nullopt;  // the format's default
  const model::SimulationWriterOptions writer_options = run::frame_writer_options(settings);
  RunFolder run(dir);
  model::SimulationWriter writer(sim.layer(), &run, writer_options);
  const int frames = static_cast<int>(python.states.size());
  for (int f = 0; f < frames; ++f)
    writer.add_frame(f, sim.motion().time(static_cast<std::size_t>(f)), python.states[static_cast<std::size_t>(f)],
                     model::is_written_frame(f, frames, options.every));
  writer.finish();

  const std::vector<std::string> argv = {"python", "sflsh.Simulation.write", dir.string(), "--format", options.format};
  std::vector<const char*> args;
  for (const std::string& a : argv) args.push_back(a.c_str());
  nlohmann::json summary = summary_header("simulate", static_cast<int>(args.size()), args.data());
  nlohmann::json body = sim.summary();
  body["compression"] = vtk::to_string(writer_options.compression);
  body["layer_compression"] = vtk::to_string(writer_options.layer_compression);
  summary.update(body);
  summary["output"] = run::simulate_output_summary(settings, body);
  summary.erase("compression");
  summary.erase("layer_compression");
  write_summary(run, summary, sim.seconds());
  run.commit();
}

}  // namespace sflsh::python
