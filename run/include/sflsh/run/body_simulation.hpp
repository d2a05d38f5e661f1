#pragma once
// One body along a motion with the full-space solver or the reduced model, frame by frame: what `sflsh simulate
// --solver full|reduced` runs, what `sflsh sweep` runs many times in-process, and what the Python module's
// Simulation steps from Python. The object builds the subject's layer (and the reduced model) once, advances one
// output frame per step() through the shared frame loop (model/frame_loop.hpp), accumulates σ and the per-frame
// records, optionally writes the frames into a run folder, and gives summary.json's body entries at any time.
#include <sflsh/body/body_model.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/body/subject_selection.hpp>
#include <sflsh/core/background_jobs.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/material/material_file.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/model/frame_loop.hpp>
#include <sflsh/model/layer_settings.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/model/step_stats.hpp>
#include <sflsh/model/time_integrator.hpp>
#include <sflsh/run/body_solver_factory.hpp>
#include <sflsh/run/solver_choice.hpp>

#include <nlohmann/json.hpp>

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace sflsh::reduced {
struct ReducedModel;
class ReducedSolver;
}  // namespace sflsh::reduced
namespace sflsh::fullspace {
class FullSpaceSolver;
}

namespace sflsh::run {

/// The settings of one body run (the options of `sflsh simulate` without --scene, --out, --no-output, the keywords
/// of Python's Simulation) as text, with the project's run defaults (solver_choice.hpp). The messages of refused
/// settings name the command-line options.
struct BodyRunSettings {
  std::string solver = "full";  ///< full | reduced
  body::SubjectSelection subject;
  std::string motion;  ///< a procedural name or an AMASS .npz path
  int frames = 0;      ///< 0: the motion's length
  double fps = 60.0;
  int substeps = 1;
  std::string mesh{kDefaultMesh};  ///< coarse | default | fine
  model::LayerSettings layer;      ///< mesher, material, cache, density, gravity, stiffness, mass
  /// A material held in memory (the Python module's Material), used instead of layer.material when set.
  std::shared_ptr<const material::MaterialFile> material_data;
  /// backward_euler | bdf2 | newmark; bdf2 unless told (model::kDefaultIntegrator; the paper's: backward_euler)
  std::string integrator = std::string(model::to_string(model::kDefaultIntegrator));
  /// Per-frame kinetic, elastic and gravitational energies over every tet in summary.json's frames (--energies).
  /// Off by default: over every tet they cost the reduced model about as much as its step (docs/output.md).
  bool energies = false;
  bool write_layer = false;  ///< also write layer.pvd (when frames are written)
  int every = 1;             ///< write every N-th frame (frame 0 and the last always)
  /// xdmf (.xmf + .h5: topology and fixed fields once, the default) | vtk (.pvd of .vtp/.vtu), docs/output.md
  std::string format = "xdmf";
  std::string precision = "float32";  ///< float32 | float64 (xdmf datasets; vtk frames are Float64)
  /// lz4 | zlib | none: of every vtk frame file, or zlib | none of the xdmf datasets; empty: zlib for xdmf, LZ4 for
  /// the body's .vtp and zlib for the layer's .vtu
  std::string compression;
  /// The arrays of the body and layer frames (names of model::frame_field_names(), as a scene's [output] fields);
  /// nullopt: the format's default — model::default_frame_fields() for xdmf, every array for vtk (the .pvd layout
  /// of `motion export` with all its arrays, as before xdmf became the default).
  std::optional<std::vector<std::string>> fields;
  // Reduced model.
  int handles = kDefaultHandles;
  int cubature = kDefaultCubature;        ///< −1 auto, 0 every tet, else a tet count
  std::string cubature_weights = "nnls";  ///< nnls | voronoi
  bool affine = false;
  double newton_tolerance = kDefaultNewtonTolerance;  ///< [m] reduced::ReducedOptions::step_tolerance
  bool allow_long = false;  ///< run even when the work estimate exceeds WorkLimits (--allow-long)
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

/// A body simulation that advances one output frame at a time. Not copyable or movable (the solvers refer to
/// the layer it owns). The full-space solver needs PETSc initialized (fullspace::PetscSession) for its lifetime.
class BodySimulation {
 public:
  /// Checks the settings, loads the body, the subject and the motion, builds the layer and the solver and
  /// records frame 0 (the rest state). Frames go to `frames_to` when it is not null (rank 0 only); `rank` and
  /// `size` are the MPI rank and process count (full space runs on MPI_COMM_WORLD). Throws sflsh::Error with a
  /// one-line message on bad settings.
  explicit BodySimulation(const BodyRunSettings& settings, RunFolder* frames_to = nullptr, int rank = 0, int size = 1,
                          const BodyRunReporting& reporting = {});
  ~BodySimulation();
  BodySimulation(const BodySimulation&) = delete;
  BodySimulation& operator=(const BodySimulation&) = delete;

  /// The frame the state is at: 0 after construction, frame() + 1 after each step().
  int frame() const { return frame_; }
  /// The motion's frames, frame 0 included.
  int num_frames() const { return static_cast<int>(motion_.num_frames()); }
  bool finished() const { return frame_ + 1 >= num_frames(); }
  /// Solves frame() + 1 (settings.substeps solver steps), records it into σ, the summary and the output, and
  /// returns the frame's step statistics. Throws sflsh::Error when finished() or when a step fails.
  const model::StepStats& step();

  /// summary.json's body entries (solver, integrator, mass, subject, beta, motion, mesh, material, reduced,
  /// dynamics, frames, timings) over the frames solved so far, with "compression" and "layer_compression" (which the
  /// caller moves).
  nlohmann::json summary() const;
  /// Waits for the frame files, writes the .pvd collections and dynamics.vtp (when writing) and returns
  /// summary(). Call once, after the last step.
  nlohmann::json finish();

  const BodyRunSettings& settings() const { return settings_; }
  const body::BodyModel& body() const { return *body_; }
  const body::Betas& beta() const { return beta_; }
  const std::string& subject_label() const { return subject_label_; }
  const body::Motion& motion() const { return motion_; }
  const model::BodyLayer& layer() const { return *layer_; }
  const model::SimulationWriter& writer() const { return *writer_; }
  /// The current full-space state (x, w at every node).
  model::State state() const;
  /// Time of the current frame [s].
  double time() const { return motion_.time(static_cast<std::size_t>(frame_)); }
  /// The posed body surface (n×3, body frame as the frames are written) at the current frame, with the region's
  /// skin displaced by the soft tissue, and the purely skinned surface (u = 0): their difference is the
  /// soft_tissue_displacement field of body.pvd.
  model::RowMatrixX3d posed_surface() const;
  model::RowMatrixX3d skinned_surface() const;
  /// The reduced model (null in full space).
  const reduced::ReducedModel* reduced_model() const { return reduced_model_.get(); }
  /// Wall time of the last step() call [s]: the solver's steps and the frame's recording (σ, energies, output).
  double last_step_seconds() const { return last_step_seconds_; }
  /// Wall time since the simulation was made [s] (summary()'s timings.total_seconds).
  double seconds() const;
  /// The statistics summed over every frame so far.
  const model::StepStats& total() const { return total_; }

 private:
  using Clock = std::chrono::steady_clock;
  BodyRunSettings settings_;
  SolverChoice choice_;  ///< settings_'s solver, parsed once (solver_choice)
  BodyRunReporting reporting_;
  int rank_ = 0;
  int size_ = 1;
  Clock::time_point t_start_;
  std::unique_ptr<body::BodyModel> body_;  ///< heap: the layer keeps a pointer to it
  std::string subject_label_;
  body::Betas beta_ = body::Betas::Zero();
  body::Motion motion_;
  std::optional<material::MaterialFile> material_file_;
  std::unique_ptr<model::BodyLayer> layer_;
  std::unique_ptr<reduced::ReducedModel> reduced_model_;
  BuiltSolver solver_;
  model::SimulationWriterOptions writer_options_;
  std::unique_ptr<model::SimulationWriter> writer_;
  /// Declared after the writer its jobs refer to: destroyed first (pending writes dropped, a running one awaited).
  std::optional<BackgroundJobs> jobs_;
  nlohmann::json frames_ = nlohmann::json::array();
  model::StepStats total_;
  model::StepStats last_;
  int frame_ = 0;
  double build_seconds_ = 0.0;
  double model_seconds_ = 0.0;
  double output_seconds_ = 0.0;
  double last_step_seconds_ = 0.0;
  bool finished_output_ = false;
};

/// The solver of these settings (solver, integrator, handles, cubature, cubature weights, affine, Newton tolerance),
/// checked; the messages name the command-line options.
SolverChoice solver_choice(const BodyRunSettings& settings);

/// Runs one body to the end of its motion: a BodySimulation stepped through every frame with a progress line,
/// returning summary.json of `sflsh simulate` without its header and "output" entries (empty on ranks other
/// than 0). Throws sflsh::Error with a one-line message on bad settings or when a step fails.
nlohmann::json run_body_simulation(const BodyRunSettings& settings, RunFolder* frames_to, int rank, int size,
                                   const BodyRunReporting& reporting = {});

/// summary.json's "output" entry of `sflsh simulate` (and of the Python Simulation.write): format, series, layer,
/// every, the compressions and precision, the fields when chosen, from the settings and the body's summary() (its
/// "compression" and "layer_compression").
nlohmann::json simulate_output_summary(const BodyRunSettings& settings, const nlohmann::json& body_summary);
/// How the frames of a run with these settings are written: format, precision, compressions, fields and layer (the
/// command line's and Python's names checked, errors naming --format, --precision, --compression, --fields).
model::SimulationWriterOptions frame_writer_options(const BodyRunSettings& settings);

}  // namespace sflsh::run
