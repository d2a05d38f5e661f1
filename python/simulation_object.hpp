#pragma once
// The object behind sflsh.Simulation: a run::BodySimulation stepped from Python, and the state of every frame
// solved so far (for Simulation.write, which writes the run folder `sflsh simulate` writes from them).
#include <sflsh/model/problem.hpp>
#include <sflsh/run/body_simulation.hpp>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace sflsh::python {

struct PythonSimulation {
  std::unique_ptr<run::BodySimulation> simulation;
  bool record = true;                ///< keep every frame's state for write()
  std::vector<model::State> states;  ///< frames 0 … frame() when recording

  /// Solves the next frame and records its state.
  void step();
  run::BodySimulation& operator*() { return *simulation; }
  const run::BodySimulation& operator*() const { return *simulation; }
};

/// How Simulation.write writes: `sflsh simulate`'s output options.
struct WriteOptions {
  std::string format = "xdmf";  ///< xdmf | vtk
  bool write_layer = false;
  int every = 1;
  std::string precision = "float32";  ///< float32 | float64 (xdmf)
  std::string compression;            ///< "" (zlib xdmf; LZ4 body, zlib layer vtk frames) | lz4 | zlib | none
  /// The frames' arrays ("all" alone: every one); nullopt: the format's (default_frame_fields() for xdmf, all for vtk)
  std::optional<std::vector<std::string>> fields;
};

/// Writes the run folder `sflsh simulate` writes for the frames solved so far (frame 0 … frame()): the body series,
/// the layer series on request, dynamics.vtp and summary.json, all at once into `dir`. Throws sflsh::Error when the
/// simulation was made with record=False or the options are bad.
void write_run_folder(const PythonSimulation& sim, const std::filesystem::path& dir, const WriteOptions& options);

}  // namespace sflsh::python
