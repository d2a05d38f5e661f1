#pragma once
// Internal to the scene runner: the scene's free rigid objects inside one reduced body's Newton solve
// (reduced/coupled_system.hpp, docs/contact.md "One solve for objects and body"). Each object adds its six
// coordinates y = (Δx, θ) to the body's unknowns, and Φ gains, in the body's frame (object_coupling_terms.hpp):
// the object's inertia and gravity, its samples against the fixed and prescribed objects (the ground), the soft
// skin's contact nodes against the object's exact φ with the body's penalty (k_i = stiffness · area_i, the same
// nodes and areas as the body's ContactPotential), the skin outside the soft layer (carried by the skeleton,
// frozen in the solve) likewise, and smoothed Coulomb friction on all of them with the normal force, normal and
// contact point lagged by one substep. The contact impulse is then one force with two sides.
#include "bodies/scene_internal.hpp"

#include <sflsh/reduced/coupled_system.hpp>
#include <sflsh/scene/object_coupling_terms.hpp>
#include <sflsh/scene/rigid_motion.hpp>
#include <sflsh/scene/rigid_object.hpp>

#include <functional>
#include <memory>
#include <unordered_map>
#include <vector>

namespace sflsh::scene::detail {

/// What the coupled objects need from the scene.
struct CoupledSetup {
  std::vector<RigidObject*> objects;   ///< not owned; their world states are read at start and set by finish_step
  std::vector<double> friction;        ///< μ per object
  std::vector<int> nodes;              ///< the body's contact nodes (ascending)
  std::vector<double> node_stiffness;  ///< k_i [N/m] per node
  /// The skin vertices outside the soft layer: stiffness [N/m] per vertex, and their world positions at t.
  std::vector<double> rigid_stiffness;
  std::function<RowMatrixX3d(double t)> rigid_positions;
  /// The other objects (fixed or prescribed): own shape copies and their world motions.
  std::vector<std::pair<std::shared_ptr<Obstacle>, std::shared_ptr<RigidMotion>>> obstacles;
  Rigid world_from_body;
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();  ///< world [m/s²]
  RigidObjectParameters parameters;                   ///< margin, tolerance, stiffness, refinement, ε_v
};

class CoupledObjects final : public reduced::CoupledSystem {
 public:
  explicit CoupledObjects(CoupledSetup setup);

  Eigen::Index size() const override { return 6 * static_cast<Eigen::Index>(objects_.size()); }
  const std::vector<int>& nodes() const override { return setup_.nodes; }
  void begin_substep(double t0, double dt, const RowMatrixX3d& p_start, const RowMatrixX3d& p_skinned_end) override;
  const std::vector<int>& candidates() const override { return candidates_; }
  double evaluate(const RowMatrixX3d& P, const Eigen::VectorXd& y, reduced::CoupledDerivatives* derivatives,
                  bool with_hessian) const override;
  bool accept_substep(const RowMatrixX3d& P_end, const Eigen::VectorXd& y) override;
  int max_refinements() const override { return setup_.parameters.max_refinements; }
  void commit_substep(const RowMatrixX3d& P_end, const Eigen::VectorXd& y) override;
  void save() override;
  void restore() override;

  /// After the body's step: sets every object's world state and returns what its step did (forces on the
  /// object [N] and penetration [m] at the step's end, refinements, energies).
  std::vector<RigidStepReport> finish_step();
  /// What the objects did to the body's contact node `entry` (an index into nodes()) at the last committed
  /// substep: the force on the node [N] (body frame: penalty and friction) and its depth inside an object [m].
  const Eigen::Vector3d& node_force(int entry) const { return node_force_[static_cast<std::size_t>(entry)]; }
  double node_penetration(int entry) const { return node_depth_[static_cast<std::size_t>(entry)]; }
  /// Time spent in the objects' part of the body's solve since the last call [s] (the chain rule to the
  /// body's coordinates excluded).
  double take_seconds();

 private:
  /// A lagged friction contact: on node entry `id` (kind node), rigid vertex `id` (kind rigid) or an obstacle.
  enum class Kind { node, rigid, obstacle };
  struct Lagged {
    Kind kind = Kind::node;
    int id = -1;
    FrictionContact contact;
  };
  /// Per object: the state (body frame), stiffness factors, lagged friction and the step's report.
  struct Object {
    RigidState state;
    std::vector<RigidSample> samples;  ///< factor 1
    std::vector<double> sample_factor;
    std::unordered_map<int, double> node_factor, rigid_factor;
    std::vector<Lagged> lagged;
    RigidStepReport report;
  };
  /// The substep's view of one object: its candidates and the fixed points near it.
  struct Near {
    std::vector<int> candidates;          ///< indices into candidates_
    std::vector<int> rigid;               ///< indices into the rigid vertices
    std::vector<int> friction;            ///< indices into the object's lagged contacts
    std::vector<int> friction_candidate;  ///< per friction entry: its candidate (node kind) or −1
  };
  /// The energy of object o at its frame, with its derivatives added into d (its block of y at 6o).
  double object_energy(std::size_t o, const ObjectFrame& frame, const RowMatrixX3d& P, reduced::CoupledDerivatives* d,
                       bool with_hessian) const;
  double node_stiffness(const Object& object, int entry) const;
  double rigid_stiffness(const Object& object, int vertex) const;

  CoupledSetup setup_;
  std::vector<Object> objects_, saved_;
  double t0_ = 0.0, dt_ = 0.0, epsilon_ = 0.0;
  std::vector<int> candidates_;              ///< entries of nodes() near an object in this substep
  std::vector<int> candidate_of_entry_;      ///< per entry of nodes(): its candidate, or −1
  RowMatrixX3d p_start_;                     ///< per candidate: its posed position at t0 [m]
  RowMatrixX3d rigid_start_, rigid_end_;     ///< the rigid skin vertices at t0 and t0 + dt (body frame) [m]
  std::vector<Near> near_;                   ///< per object
  std::vector<Eigen::Vector3d> node_force_;  ///< per entry of nodes(), at the last commit [N]
  std::vector<double> node_depth_;           ///< per entry of nodes(), at the last commit [m]
  std::vector<const Obstacle*> posed_;       ///< the obstacles at t0 + dt in the body's frame
  mutable double seconds_ = 0.0;             ///< in this system's part of the solve [s]
};

}  // namespace sflsh::scene::detail
