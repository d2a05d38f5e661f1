#pragma once
// Frame output of a body simulation: the posed body surface per frame as `sflsh motion export` writes it
// (same points, same order, body.pvd), optionally the tet layer (layer.pvd), and the per-vertex dynamics
// amplitude σ of docs/physics.md §4 accumulated on the fly (the elastic displacement u of the skin is what
// inverse skinning returns for a simulation driven by the same poses).
#include <sflsh/core/background_jobs.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/vtk_io.hpp>
#include <sflsh/core/xdmf_series.hpp>
#include <sflsh/model/body_layer.hpp>

#include <nlohmann/json.hpp>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace sflsh::model {

/// Per-vertex σ, σ_n, σ_t (docs/physics.md §4 steps 4–6) from a stream of displacement fields.
class DynamicsAmplitude {
 public:
  /// `normals`: unit normals per vertex (n×3) for the normal/tangential split.
  explicit DynamicsAmplitude(RowMatrixX3d normals);
  /// Adds one frame's displacement (n×3) [m].
  void add(const RowMatrixX3d& displacement);
  int frames() const { return frames_; }
  /// σ_i = sqrt(mean_t ‖u_i − ū_i‖²) [m] per vertex.
  Eigen::VectorXd sigma() const;
  Eigen::VectorXd sigma_normal() const;
  Eigen::VectorXd sigma_tangent() const;

 private:
  RowMatrixX3d normals_;
  RowMatrixX3d sum_;
  Eigen::VectorXd sum_sq_, sum_n_, sum_sq_n_;
  int frames_ = 0;
};

/// Area-weighted unit vertex normals of a triangle surface.
RowMatrixX3d vertex_normals(const RowMatrixX3d& vertices,
                            const Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>& faces);

/// Strain-energy density ψ = E_e / V_e per tet [J/m³] at elastic state x.
Eigen::VectorXd strain_energy_density(const Problem& problem, const Eigen::VectorXd& x);
/// ψ [J/m³] of the listed tets only (one value per entry of `tets`).
Eigen::VectorXd strain_energy_density(const Problem& problem, const Eigen::VectorXd& x, const std::vector<int>& tets);

/// The point/cell arrays a body frame (and a layer frame) can carry: displacement, velocity,
/// skin_weights_argmax, soft_tissue_displacement, elastic_displacement, strain_energy_density,
/// thickness_fraction (and its older name thickness), young_tangent, young_normal, soft_region, Normals, and
/// in scenes with contact contact_force, penetration. Their units: core/array_units.hpp, docs/output.md.
const std::vector<std::string>& frame_field_names();
/// The arrays written when none are asked for (`simulate --fields`, Python's Simulation.write, a scene's [output]
/// fields when given as "default"): what a viewer colours and shades by, each once per frame (docs/output.md,
/// "Size"); the others (velocity, elastic_displacement, …) with `--fields all` or by name.
const std::vector<std::string>& default_frame_fields();
/// A field list as users write it: "all" alone is every array (nullopt), "default" alone default_frame_fields(),
/// otherwise names of frame_field_names() (checked as check_frame_field_names does).
std::optional<std::vector<std::string>> resolve_frame_fields(const std::vector<std::string>& names,
                                                             const std::string& where, const std::string& context = "");
/// The frame output formats: "vtk", "xdmf"; throws sflsh::Error "<where>: …" for another name.
void check_output_format(const std::string& format, const std::string& where);
/// Throws sflsh::Error "<where>: unknown field '<name>'<context> (expected …)" for a name not in frame_field_names().
void check_frame_field_names(const std::vector<std::string>& names, const std::string& where,
                             const std::string& context = "");

/// Whether frame `frame` of `frames` (0 … frames − 1) is written with `every` ≥ 1: every N-th frame, plus
/// always the first and the last one (a series starts at rest and ends where the run ends).
bool is_written_frame(int frame, int frames, int every);

/// Where and how a SimulationWriter writes (scenes write several bodies, each placed in the world).
struct SimulationWriterOptions {
  std::string prefix = "body";  ///< <prefix>.pvd, <prefix>_NNNNNN.vtp, <prefix>_layer.pvd, <prefix>_dynamics.vtp
  bool write_layer = false;
  /// A rigid placement applied to every written point (p_world = rotation p + translation) and the
  /// rotation to every written vector field; σ is unaffected.
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  /// The arrays written into the frames (names of frame_field_names()); nullopt: all of them. Only the
  /// requested ones are computed.
  std::optional<std::vector<std::string>> fields;
  /// Compression of the body's .vtp frames (dynamics.vtp stays zlib): LZ4 writes them about 8× faster.
  vtk::Compression compression = vtk::Compression::lz4;
  /// Compression of the layer's .vtu frames: zlib, which meshio reads (it reads no LZ4).
  vtk::Compression layer_compression = vtk::Compression::zlib;
  /// The time series: "vtk" (.pvd of one .vtp/.vtu per frame) or "xdmf" (<prefix>.xmf + <prefix>.h5: the
  /// triangles and the fields that do not change stored once, one dataset per field and frame).
  std::string format = "vtk";
  /// Precision of the xdmf series' floating-point datasets (the vtk frames stay Float64).
  xdmf::Precision precision = xdmf::Precision::float64;
  /// Compression of the xdmf series' datasets: zlib (HDF5 shuffle + deflate) or none.
  vtk::Compression series_compression = vtk::Compression::zlib;
  /// Non-null: the frame files are written by these jobs (a background thread); the caller waits for them
  /// before committing the run folder. Null: written at once.
  BackgroundJobs* jobs = nullptr;
};

/// Writes a body simulation frame by frame into a run folder and accumulates σ.
/// body.pvd / body_NNNNNN.vtp: the posed body surface (all vertices, model order) with point data
///   displacement (posed − shaped template, as `sflsh motion export`), velocity (finite difference of
///   posed positions between written frames, as the export), skin_weights_argmax, Normals (of the posed
///   surface), soft_region (1 on the soft layer's skin, 0 elsewhere), and in the region
///   soft_tissue_displacement (posed − skinned, world frame), elastic_displacement (unposed frame),
///   strain_energy_density (of the tet under the vertex) [J/m³] and the κ fields thickness_fraction (also
///   as thickness), young_tangent, young_normal (zero outside the region).
/// layer.pvd / layer_NNNNNN.vtu (on request): the posed tet layer with displacement (posed − rest),
///   elastic_displacement, velocity (ṗ of the state), κ per node and per tet, strain_energy_density per tet.
/// dynamics.vtp (at finish): the shaped neutral surface, placed like the frames, with sigma, sigma_normal,
///   sigma_tangent [mm], the κ fields, soft_region and Normals.
class SimulationWriter {
 public:
  /// `run` null: nothing is written (σ is still accumulated). The layer must outlive the writer.
  SimulationWriter(const BodyLayer& layer, RunFolder* run, bool write_layer);
  /// With a prefix and a placement; prefix "body" gives the file names above.
  SimulationWriter(const BodyLayer& layer, RunFolder* run, const SimulationWriterOptions& options);
  /// Records (and writes) the frame at time t, numbered by the frames added so far; `extra` point fields
  /// (one row per body vertex, world frame) are written beside the others.
  void add_frame(double t, const State& state, const std::vector<vtk::Field>& extra = {});
  /// Records frame `index` at time t into σ; with `write` (and a run folder) also poses the surface and
  /// writes <prefix>_<index>.vtp. Frames that are not written cost only the skin's displacement.
  void add_frame(int index, double t, const State& state, bool write, const std::vector<vtk::Field>& extra = {});
  /// The same from the node positions x [m] alone (what σ and the written fields need; no velocities).
  void add_positions(int index, double t, const Eigen::VectorXd& x, bool write,
                     const std::vector<vtk::Field>& extra = {});
  /// The placement of the frames added from now on (p_world = rotation p + translation), instead of the options':
  /// a scene body whose skeleton tracks its motion moves frame by frame. dynamics.vtp keeps the options' placement.
  void set_frame_placement(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation);
  /// Per body vertex and per layer node an affine map [L | t] applied to the posed positions before the placement,
  /// and L to the frame's vector arrays: a tracking skeleton's deviation from its motion (empty: none).
  void set_frame_deviation(std::vector<Eigen::Matrix<double, 3, 4>> vertex,
                           std::vector<Eigen::Matrix<double, 3, 4>> node);
  /// Whether a frame array is requested (SimulationWriterOptions::fields).
  bool wants(const std::string& field) const;
  /// Writes the .pvd collections and dynamics.vtp.
  void finish();
  /// σ statistics over the region's vertices in mm: sigma_mean_mm, sigma_median_mm, sigma_max_mm,
  /// sigma_normal_mean_mm, sigma_tangent_mean_mm, frames.
  nlohmann::json dynamics_summary() const;
  /// Per body vertex σ in metres (zero outside the region).
  Eigen::VectorXd sigma_per_vertex() const;
  /// Per body vertex σ_n and σ_t in metres (zero outside the region), as dynamics.vtp holds them in mm.
  Eigen::VectorXd sigma_normal_per_vertex() const;
  Eigen::VectorXd sigma_tangent_per_vertex() const;
  /// The posed surface of the last frame written (n×3; empty before the first one or without a run folder).
  const RowMatrixX3d& last_posed() const { return previous_posed_; }
  /// Seconds spent posing the written frames' surfaces (caller's thread).
  double posing_seconds() const { return posing_seconds_; }
  /// The σ map's file name: dynamics.vtp for prefix "body", <prefix>_dynamics.vtp otherwise.
  std::string dynamics_file() const;

 private:
  void add(int index, double t, const Eigen::VectorXd& x, const State* state, bool write,
           const std::vector<vtk::Field>& extra);
  const BodyLayer& layer_;
  RunFolder* run_;
  SimulationWriterOptions options_;
  bool write_layer_;
  std::unique_ptr<vtk::PvdSeries> body_series_, layer_series_;
  std::unique_ptr<xdmf::Series> body_xdmf_, layer_xdmf_;  ///< format "xdmf" instead of the .pvd series
  Eigen::MatrixXd dominant_joint_;                        ///< per body vertex: argmax of the skinning weights
  Eigen::MatrixXd vertex_kappa_;                          ///< per body vertex (h, Y_t, Y_n), zero outside the region
  Eigen::MatrixXd soft_region_;                           ///< per body vertex 1 in the region, 0 elsewhere
  std::vector<int> skin_tets_;      ///< the tets that hold skin vertices, each once (strain_energy_density)
  std::vector<int> skin_tet_slot_;  ///< per region vertex: its tet's index in skin_tets_
  DynamicsAmplitude amplitude_;
  RowMatrixX3d previous_posed_;
  double previous_t_ = 0.0;
  int frame_ = 0;
  double posing_seconds_ = 0.0;
  Eigen::Matrix3d frame_rotation_;  ///< the placement of the next frames (options' unless set_frame_placement)
  Eigen::Vector3d frame_translation_;
  std::shared_ptr<const std::vector<Eigen::Matrix<double, 3, 4>>> vertex_deviation_, node_deviation_;

  void write_layer_frame(int index, double t, const State& state);
  /// Whether the options place the body (a rotation or translation other than the identity).
  bool placed() const;
  /// The points placed in the world: rotation p + translation per row.
  RowMatrixX3d place(const RowMatrixX3d& points) const;
  /// Runs the job on the background jobs, or at once without them.
  void run_job(std::function<void()> job);
};

}  // namespace sflsh::model
