#pragma once
// Penalty contact between mesh nodes (the layer's skin nodes) and rigid or externally moved obstacles,
// as an extra per-node energy both integrators add to Φ (fullspace/node_potential.hpp). Per node i and
// obstacle j with signed distance φ_j (obstacle.hpp):
//   u_ij(p) = ½ k_i (δ − φ_j(p))²  if φ_j(p) < δ,  0 otherwise,   k_i = stiffness · area_i · factor_i
// C¹ in p (value and gradient vanish at φ = δ). Model, units and defaults: docs/contact.md.
#include <sflsh/model/node_potential.hpp>
#include <sflsh/scene/obstacle.hpp>
#include <sflsh/scene/rigid_motion.hpp>

#include <Eigen/Core>

#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace sflsh::scene {

struct ContactParameters {
  /// Pressure per unit penetration [N/m³ = Pa/m]; a node's stiffness is k_i = stiffness · area_i [N/m].
  /// Default 1e7: 10 kPa (the order of the tissue's Young moduli, 2–30 kPa) at 1 mm; with a 1.5 cm
  /// node spacing (area 2.25e-4 m²) k_i = 2250 N/m, ~10× the tissue's own per-node stiffness E·h.
  double stiffness = 1e7;
  /// Area [m²] of a node when the potential is built without per-node weights.
  double default_node_area = 2.25e-4;
  /// δ [m]: the penalty starts at distance δ outside the obstacle (a skin of thickness δ around it).
  double margin = 1e-3;
  /// Largest accepted penetration max(0, −φ) [m] at the end of a substep.
  double tolerance = 1e-3;
  /// A node deeper than `tolerance` gets factor_i *= refinement_factor and the substep is solved again.
  double refinement_factor = 4.0;
  /// Re-solves of one substep before it is accepted anyway (counted in ContactStats::unresolved).
  int max_refinements = 4;
  /// [m] added to a node's reach in the broad phase for the elastic motion the skinned end misses.
  double broad_phase_safety = 0.01;
  /// true: clamp the Hessian's negative eigenvalues (PSD, what Newton needs); false: the exact Hessian
  /// (finite-difference tests).
  bool project_hessian = true;

  /// Throws sflsh::Error naming the first out-of-range field.
  void validate() const;
};

/// Work counters, cumulative since construction (or reset_stats()).
struct ContactStats {
  std::int64_t broad_phase_passes = 0;        ///< begin_substep() calls
  std::int64_t broad_phase_queries = 0;       ///< exact φ evaluations of the broad phase
  std::int64_t candidates = 0;                ///< candidate entries, summed over passes
  std::int64_t narrow_phase_evaluations = 0;  ///< φ evaluations (with derivatives) in evaluate()
  std::int64_t refinements = 0;               ///< rejected substeps (stiffness raised)
  std::int64_t unresolved = 0;                ///< substeps accepted deeper than the tolerance
  std::int64_t accepted = 0;                  ///< accepted substeps
  double max_penetration = 0.0;               ///< [m] over accepted substeps
  double max_force = 0.0;       ///< [N] the largest |Σ of the nodes' contact forces| of an accepted substep
  double max_force_time = 0.0;  ///< [s] its substep's end
  double seconds = 0.0;         ///< wall time inside the potential
};

/// An obstacle the potential acts against, with how it moves. `motion` null: the caller sets the pose
/// (and, for a TriangleMesh, the vertices) before each substep; otherwise begin_substep() sets the pose
/// at the substep's end and accept_substep() commits the reaction force to it.
struct ContactObstacle {
  ContactObstacle() = default;
  ContactObstacle(std::shared_ptr<Obstacle> shape_, std::shared_ptr<RigidMotion> motion_, std::string name_ = {})
      : shape(std::move(shape_)), motion(std::move(motion_)), name(std::move(name_)) {}
  std::shared_ptr<Obstacle> shape;
  std::shared_ptr<RigidMotion> motion;
  std::string name;  ///< how messages name it, e.g. "object 'ball'" (empty: "obstacle <index>")
};

/// Lumped (one third of the incident triangles') area per vertex [m²] of a triangle surface, e.g. the
/// layer's skin: the per-node weights of ContactPotential.
std::vector<double> lumped_vertex_areas(const RowMatrixX3d& vertices, const RowMatrixX3i& triangles);

class ContactPotential final : public model::NodePotential {
 public:
  /// nodes: ascending mesh node ids (unconstrained); areas: empty, or one lumped skin area [m²] per node
  /// (the weight of its stiffness); at most 64 obstacles. Throws sflsh::Error on bad input.
  ContactPotential(std::vector<int> nodes, std::vector<double> areas, std::vector<ContactObstacle> obstacles,
                   const ContactParameters& parameters = {});

  // model::NodePotential
  const std::vector<int>& nodes() const override { return nodes_; }
  bool begin_substep(double t0, double dt, const meshing::RowMatrixX3d& p_start,
                     const meshing::RowMatrixX3d& p_skinned_end) override;
  const std::vector<int>& candidates() const override { return candidates_; }
  /// u of candidate c (index into candidates(); the node is nodes()[candidates()[c]]) at posed p.
  double evaluate(int c, const Eigen::Vector3d& p, Eigen::Vector3d* gradient, Eigen::Matrix3d* hessian) const override;
  bool accept_substep(const meshing::RowMatrixX3d& p_end) override;
  int max_refinements() const override { return parameters_.max_refinements; }
  std::string unresolved() const override { return unresolved_; }

  const ContactParameters& parameters() const { return parameters_; }
  const std::vector<ContactObstacle>& obstacles() const { return obstacles_; }
  /// k_i of entry k [N/m], with its current refinement factor.
  double node_stiffness(int k) const;
  double stiffness_factor(int k) const { return factor_[static_cast<std::size_t>(k)]; }

  // Results of the last accepted substep (zero elsewhere), one row per entry of nodes().
  /// Contact force on each node −∇u [N], world frame.
  const meshing::RowMatrixX3d& contact_force() const { return force_; }
  /// max(0, −φ) over the obstacles [m].
  const Eigen::VectorXd& penetration() const { return penetration_; }
  /// Total force [N] and torque about its pose origin [N·m] the nodes exert on obstacle j (world).
  const Eigen::Vector3d& obstacle_force(int j) const { return obstacle_force_[static_cast<std::size_t>(j)]; }
  const Eigen::Vector3d& obstacle_torque(int j) const { return obstacle_torque_[static_cast<std::size_t>(j)]; }

  ContactStats stats() const;
  void reset_stats();

  /// The obstacles entry k is near in the current substep (bit j for obstacle j); 0 when not a candidate.
  std::uint64_t obstacle_mask(int k) const { return mask_[static_cast<std::size_t>(k)]; }
  /// The state a step changes besides the results: the refinement factors and the deepest accepted
  /// penetration. Saved at a step's start and put back when the step is solved again (a scene's body-contact
  /// exchanges), so that every exchange starts from the same stiffness.
  /// The maxima are put back too, so that they count accepted steps only (not an exchange's intermediate solves).
  struct Checkpoint {
    std::vector<double> factor;
    double max_penetration = 0.0, max_force = 0.0, max_force_time = 0.0;
  };
  Checkpoint checkpoint() const { return {factor_, stats_.max_penetration, stats_.max_force, stats_.max_force_time}; }
  void restore(const Checkpoint& c) {
    factor_ = c.factor;
    stats_.max_penetration = c.max_penetration;
    stats_.max_force = c.max_force;
    stats_.max_force_time = c.max_force_time;
  }

 private:
  /// u of entry k summed over the obstacles in `mask`, with derivatives; counts evaluations.
  double evaluate_masked(int k, std::uint64_t mask, const Eigen::Vector3d& p, Eigen::Vector3d* gradient,
                         Eigen::Matrix3d* hessian) const;

  std::vector<int> nodes_;
  std::vector<double> area_;
  std::vector<ContactObstacle> obstacles_;
  ContactParameters parameters_;

  std::vector<double> factor_;       ///< per entry: refinement factor on k (1 until raised)
  std::string unresolved_;           ///< unresolved(): why the last accept_substep refused for good
  std::vector<int> candidates_;      ///< entries of nodes() near an obstacle in this substep
  std::vector<std::uint64_t> mask_;  ///< per entry: the obstacles it is near (bit j)
  double t_end_ = 0.0;               ///< end time of the current substep
  double substep_t0_ = -std::numeric_limits<double>::infinity();
  double substep_dt_ = -1.0;
  int substep_refinements_ = 0;  ///< rejections of the current substep so far
  bool last_accepted_ = true;

  meshing::RowMatrixX3d force_;
  Eigen::VectorXd penetration_;
  std::vector<Eigen::Vector3d> obstacle_force_;
  std::vector<Eigen::Vector3d> obstacle_torque_;

  // Counters (evaluate() is const and may run on several threads).
  ContactStats stats_;
  mutable std::atomic<std::int64_t> narrow_evaluations_{0};
  mutable std::atomic<std::int64_t> evaluate_nanoseconds_{0};
};

}  // namespace sflsh::scene
