#pragma once
// One (subject, motion) pair of the fit (SFLSH §5): the subject's layer built once for the motion, and the
// reduced simulation of it for any control-point material κ, measured as the paper's per-vertex dynamics
// of the region skin in the neutral pose (docs/physics.md §4; for a simulation driven by the motion's own poses
// inverse skinning returns the elastic displacement exactly, so d̃ = u − mean_t u).
#include <sflsh/model/body_layer.hpp>
#include <sflsh/reduced/layer_parameterization.hpp>
#include <sflsh/reduced/reduced_model.hpp>
#include <sflsh/reduced/reduced_solver.hpp>

#include <memory>
#include <mutex>
#include <string>

namespace sflsh::reduced {

class SkinDisplacementMap;

/// Per-vertex dynamics of one simulation over the region's skin vertices, in mm.
struct CaseDynamics {
  Eigen::VectorXd sigma_normal;   ///< σ_n (R)
  Eigen::VectorXd sigma_tangent;  ///< σ_t (R)
  Eigen::VectorXd sigma() const;  ///< √(σ_n² + σ_t²)
  double mean_sigma() const;      ///< mean over the region vertices [mm] (the Table 2 entry of one motion)
  double seconds = 0.0;           ///< wall time of the whole simulation [s]
  double setup_seconds = 0.0;     ///< of which the set-up: problem for κ, integrator, initial state [s]
  int frames = 0;
  int cubature_added = 0;  ///< tets the cubature guard added during the run (reduced_solver.hpp)
};

class DynamicsCase {
 public:
  /// Builds the layer of subject `beta` for `motion` (the first `frames` frames; 0 = all).
  DynamicsCase(const body::BodyModel& model, std::string subject, const body::Betas& beta, const body::Motion& motion,
               const model::BodyLayerOptions& options);
  ~DynamicsCase();

  const std::string& subject() const { return subject_; }
  const std::string& motion() const { return motion_; }
  const body::Betas& beta() const { return layer_->beta; }
  const model::BodyLayer& layer() const { return *layer_; }
  const model::BodyLayerOptions& layer_options() const { return options_; }
  int num_region_vertices() const { return static_cast<int>(normals_.rows()); }
  /// Unit normals of the shaped template at the region vertices (the σ_n / σ_t split).
  const meshing::RowMatrixX3d& normals() const { return normals_; }

  /// Simulates the clip with the reduced model for control values κ (N × 3, physical). Thread-safe.
  /// Throws sflsh::Error (naming subject, motion and the cause) when the simulation fails.
  CaseDynamics simulate(const LayerParameterization& parameterization, const material::KappaMatrix& kappa,
                        const ReducedModel& model, const ReducedOptions& options = {}) const;

  /// The same with forward sensitivities (reduced_sensitivity.hpp) of σ_n, σ_t with respect to the Young
  /// moduli of the N control points: `dsigma` receives (2R × 2N) [mm/Pa], rows [σ_n; σ_t], columns Y_t of
  /// controls 0..N−1 then Y_n. `young_map` is W of young_map.hpp for the model's cubature tets. Newton runs to
  /// the sensitivity tolerance (sensitivity_solver_options), so σ agrees with simulate() to that tolerance.
  /// With `thickness`, N more columns: dσ/dh of the control points' thickness [mm per unit h], exact through the
  /// retarget (meshing::Retargeter::node_derivative) and the rest geometry (rest_geometry_derivative.hpp).
  CaseDynamics simulate_with_sensitivity(const LayerParameterization& parameterization,
                                         const material::KappaMatrix& kappa, const ReducedModel& model,
                                         const Eigen::MatrixXd& young_map, Eigen::MatrixXd& dsigma,
                                         const ReducedOptions& options = {}, bool thickness = false) const;

 private:
  /// K B of the skin (built on first use; every simulation of this case shares the one subspace).
  const SkinDisplacementMap& skin_map(const ReducedModel& model) const;
  /// The β part of the retarget (meshing::Retargeter::shape), made on first use: every parameterization is on
  /// the one template mesh, so any of their retargeters gives the same.
  const meshing::ShapedLayer& shaped_layer(const LayerParameterization& parameterization) const;

  std::string subject_, motion_;
  model::BodyLayerOptions options_;
  std::unique_ptr<model::BodyLayer> layer_;
  meshing::RowMatrixX3d normals_;
  int frames_ = 0;
  double fps_ = 60.0;
  mutable std::once_flag skin_map_once_;
  mutable std::unique_ptr<SkinDisplacementMap> skin_map_;  ///< K B, built on first use
  mutable std::once_flag shaped_once_;
  mutable std::unique_ptr<meshing::ShapedLayer> shaped_;  ///< built on first use
};

}  // namespace sflsh::reduced
