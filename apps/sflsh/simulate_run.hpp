#pragma once
// One body along a motion with the full-space solver or the reduced model: what `sflsh simulate --solver
// full|reduced` does, shared with `sflsh sweep` (which runs many such cases in-process, `--no-output` style).
#include <CLI/CLI.hpp>
#include <functional>
#include <nlohmann/json.hpp>
#include <sflsh/core/run_folder.hpp>
#include <string>

#include "commands.hpp"
#include "layer_setup.hpp"

namespace sflsh::app {

/// The settings of one body run (the options of `sflsh simulate` without --scene, --out, --no-output).
struct BodyRunSettings {
  std::string solver = "full";  ///< full | reduced
  SubjectOptions subject;
  std::string motion;
  int frames = 0;  ///< 0: the motion's length
  double fps = 60.0;
  int substeps = 1;
  std::string mesh = "default";               ///< coarse | default | fine
  LayerSettings layer;                        ///< mesher, material, cache, density, gravity, stiffness, mass
  std::string integrator = "backward_euler";  ///< backward_euler | bdf2 | newmark (time_integrator.hpp)
  bool write_layer = false;                   ///< also write layer.pvd (when frames are written)
  int every = 1;                              ///< write every N-th frame (frame 0 and the last always)
  std::string format = "vtk";                 ///< vtk (.pvd of .vtp/.vtu) | xdmf (.xmf + .h5), docs/output.md
  std::string precision = "float64";          ///< float64 | float32 (xdmf datasets)
  // Reduced model.
  int handles = 86;
  int cubature = -1;                      ///< −1 auto, 0 every tet, else a tet count
  std::string cubature_weights = "nnls";  ///< nnls | voronoi
  bool affine = false;
  double newton_tolerance = 1e-5;         ///< [m] reduced::ReducedOptions::step_tolerance
  bool allow_long = false;                ///< run even when the work estimate exceeds WorkLimits (--allow-long)
};

/// How a run reports while it runs.
struct BodyRunReporting {
  bool progress = true;                     ///< the frame progress line
  bool log_details = true;                  ///< the layer/solver line at info level (else debug)
  std::function<void(int frame)> on_frame;  ///< called after every converged output frame (may be empty)
  /// Called once the solver is set up, before the first step (may be empty): {"tets", "coordinates", "cubature"}
  /// (the last two 0 in full space), so that a run that fails later can still say what it ran.
  std::function<void(const nlohmann::json& setup)> on_setup;
};

/// --handles, --cubature, --cubature-weights, --affine with simulate's help texts.
void add_reduced_run_options(CLI::App& cmd, BodyRunSettings& settings);
/// --integrator with simulate's help text.
void add_integrator_option(CLI::App& cmd, std::string& integrator);

/// Runs one body: builds the layer (and the reduced model), steps every frame and returns summary.json of
/// `sflsh simulate` without its header and "output" entries (solver, integrator, mass, subject, beta, motion, mesh,
/// material, reduced, dynamics, frames, timings). Frames go to `frames_to` when it is not null (rank 0 only).
/// Throws sflsh::Error with a one-line message on bad settings or when a step fails.
nlohmann::json run_body_simulation(const BodyRunSettings& settings, RunFolder* frames_to, int rank, int size,
                                   const BodyRunReporting& reporting = {});

}  // namespace sflsh::app
