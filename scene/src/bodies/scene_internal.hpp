#pragma once
// Internal to the scene runner: one body's simulation (its motion, skinning only or a soft layer with the
// full-space or reduced solver), rigid placements, and the crowd's expansion into bodies.
#include <sflsh/body/body_model.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/body/skinning.hpp>
#include <sflsh/fullspace/fullspace_solver.hpp>
#include <sflsh/material/material_file.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/reduced/reduced_model.hpp>
#include <sflsh/reduced/reduced_solver.hpp>
#include <sflsh/run/body_solver_factory.hpp>
#include <sflsh/scene/scene_file.hpp>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace sflsh::scene::detail {

using meshing::RowMatrixX3d;

/// p_world = R p + t.
struct Rigid {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  RowMatrixX3d apply(const RowMatrixX3d& p) const { return (p * R.transpose()).rowwise() + t.transpose(); }
  RowMatrixX3d apply_inverse(const RowMatrixX3d& p) const { return (p.rowwise() - t.transpose()) * R; }
  Rigid inverse() const { return {R.transpose(), -R.transpose() * t}; }
  Rigid operator*(const Rigid& o) const { return {R * o.R, R * o.t + t}; }
};
Rigid placement_transform(const Placement& placement);

/// The motion of a scene body (scene_motion.cpp): `frames` frames at `fps`, started `offset` s in ("rest":
/// the rest pose held still), with the approach keyframes added to the root translation.
body::Motion scene_motion(const std::string& name, double offset, const std::vector<SceneKeyframe>& approach,
                          double fps, int frames);

/// Seconds spent per effect (summary.json "effects").
struct EffectSeconds {
  double skinning = 0.0;    ///< posing skinned bodies and the skinned part of soft ones
  double elasticity = 0.0;  ///< the solves without their mass and contact terms
  double inertia = 0.0;     ///< the mass terms (inertia, and gravity when inertia is off)
  double object_contact = 0.0;
  double body_contact = 0.0;
};

struct BodySetup {
  const Scene* scene = nullptr;
  std::filesystem::path cache_dir;
  const material::MaterialFile* material = nullptr;  ///< overrides the spec's file (crowds); may be null
};

/// One body: its spec, motion and placement, and either only its skinning (no layer is built) or its soft
/// layer with a solver. Potentials (contact) are added before start().
class SceneBody {
 public:
  SceneBody(BodySpec spec, const body::BodyModel& model, const BodySetup& setup);

  const BodySpec& spec() const { return spec_; }
  const std::string& name() const { return spec_.name; }
  SolverKind solver() const { return solver_; }  ///< what runs: skinned when no elastic effect reaches it
  bool soft() const { return solver_ != SolverKind::skinned; }
  const Rigid& placement() const { return placement_; }
  const body::BodyModel& model() const { return model_; }
  const body::Betas& beta() const { return beta_; }
  const std::string& subject_label() const { return subject_label_; }
  const body::Motion& motion() const { return motion_; }
  model::BodyLayer& layer() { return *layer_; }
  const model::BodyLayer& layer() const { return *layer_; }
  /// The layer's skin nodes a contact may act on (outer nodes without prescribed components and, reduced, with
  /// basis functions), ascending.
  std::vector<int> contact_nodes() const;
  /// Per body vertex: the layer node its skin vertex sits on (−1 outside the region or when embedded).
  const std::vector<int>& vertex_node() const { return vertex_node_; }

  /// Unknowns to solve with the body's own (free objects, coupled_objects.hpp); reduced bodies with a prescribed
  /// skeleton only, set before start(). Not owned.
  void set_coupled(reduced::CoupledSystem* coupled) { coupled_ = coupled; }
  /// Reduced bodies: local bumps around these layer nodes (the skin objects reach, local_region.hpp), set before
  /// start(); the solver's subspace becomes [B  Φ] (reduced/local_basis.hpp).
  void set_local_region(std::vector<int> nodes, const reduced::LocalBasisOptions& options, int max_nodes);
  /// The local bumps in use (null without).
  const reduced::LocalBasis* local_basis() const { return local_ ? &*local_ : nullptr; }
  /// Builds the solver (after the potentials are in layer().problem.potentials).
  void start(bool inertia);
  /// Advances from t0 by h. A quasi-static body without gravity whose potentials have no candidates is at
  /// rest and is not solved (counted in idle_steps). Solver failures throw naming the body.
  void step(double t0, double h, EffectSeconds& seconds);
  double time() const { return t_; }
  /// Remembers the state at the start of a step, and puts it back (with the step counters): the step is then
  /// solved again from the same start, e.g. against other bodies' newer surfaces (body-contact exchanges).
  void save_step_start();
  void restore_step_start();

  /// The posed body surface (n×3) in the world at the current time.
  RowMatrixX3d world_surface() const;
  /// The surface at time t with the current elastic displacement carried by the pose at t (a prediction of
  /// the body at the end of a step, for the other bodies' contact).
  RowMatrixX3d predicted_world_surface(double t) const;
  model::State state() const;
  /// The node positions alone [m] (reduced bodies: without building the full state).
  Eigen::VectorXd positions() const;
  /// The largest elastic displacement of the skin now [m] (0 for a skinned body).
  double max_elastic_displacement() const;
  /// Whether the skeleton tracks its motion (skeleton = "tracking"), and its deviation from the motion now as affine
  /// maps in the body's own (posed) frame, per body vertex and per layer node (empty otherwise).
  bool tracking() const { return built_.reduced && built_.reduced->tracking(); }
  const reduced::SkeletonDeviation& skeleton() const { return built_.reduced->skeleton(); }  ///< tracking() only
  std::vector<reduced::Matrix34d> surface_deviation() const;
  std::vector<reduced::Matrix34d> node_deviation() const;
  /// summary.json "skeleton" of a tracking body: the largest root displacement and rotation and when.
  nlohmann::json skeleton_summary() const;
  /// A tracking body's deviation r = (θ, τ, φ_1 … φ_J) at the end of every step, with its time [s].
  const std::vector<std::pair<double, Eigen::VectorXd>>& deviation_history() const { return deviation_history_; }

  // Counters for summary.json.
  long steps = 0, idle_steps = 0, newton_iterations = 0, refinements = 0, failed_attempts = 0;
  double solve_seconds = 0.0, setup_seconds = 0.0;
  std::string model_info;  ///< one line: nodes, tets, handles, cubature

 private:
  bool at_rest_this_step(double t0, double h) const;
  RowMatrixX3d skinned_world_surface(double t) const;

  BodySpec spec_;
  const body::BodyModel& model_;
  SolverKind solver_ = SolverKind::skinned;
  Rigid placement_;
  body::Betas beta_ = body::Betas::Zero();
  std::string subject_label_;
  body::Motion motion_;
  std::unique_ptr<body::Poser> poser_;       ///< skinned bodies
  std::unique_ptr<model::BodyLayer> layer_;  ///< soft bodies
  std::optional<reduced::ReducedModel> reduced_model_;
  run::BuiltSolver built_;  ///< the solver (run/body_solver_factory.hpp), from start()
  std::vector<int> vertex_node_;
  bool quasi_static_ = false;
  reduced::CoupledSystem* coupled_ = nullptr;
  std::optional<reduced::LocalBasis> local_;  ///< local bumps for contact (reduced bodies), or none
  reduced::Cubature local_cubature_;          ///< with local_: the model's cubature fitted without the patch
  double t_ = 0.0;
  // The tracking root's largest deviation so far: |τ| [m], |θ| [rad] and their times [s].
  std::vector<std::pair<double, Eigen::VectorXd>> deviation_history_;
  struct StepStart;                         ///< save_step_start()'s state (scene_body.cpp)
  std::shared_ptr<const StepStart> start_;  ///< null until saved
};

}  // namespace sflsh::scene::detail
