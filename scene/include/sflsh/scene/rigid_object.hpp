#pragma once
// A free rigid object with six degrees of freedom stepped implicitly: each step minimizes
//   Φ(x, R) = Φ_inertia+gravity + u_obstacles + u_surfaces + D_friction        (rigid_terms.hpp)
// by Newton (rigid_solver.hpp). Obstacles (ground, fixed and prescribed objects) are posed at the step's
// end; other surfaces (bodies' skins) are points at their start and end positions in the step, frozen in the
// solve. Penetration deeper than the tolerance stiffens the offending contacts ×4 and solves again (as the
// bodies' ContactPotential does); a failed Newton solve halves the step, and after `max_halvings` the step
// throws sflsh::Error naming the object. docs/contact.md, "Free rigid objects".
#include <sflsh/scene/rigid_solver.hpp>
#include <sflsh/scene/rigid_terms.hpp>

#include <memory>
#include <string>
#include <vector>

namespace sflsh::scene {

struct RigidObjectParameters {
  double friction = 0.5;           ///< Coulomb coefficient μ (0: frictionless)
  double slip_velocity = 1e-3;     ///< ε_v [m/s]: slower sliding is smoothed into sticking (ε = ε_v h)
  double stiffness = 1e7;          ///< [N/m³]: a sample's k = stiffness · (area / samples) [N/m]
  double margin = 1e-3;            ///< δ [m]
  double tolerance = 1e-3;         ///< largest accepted penetration [m]
  double refinement_factor = 4.0;  ///< stiffness factor per rejected solve
  int max_refinements = 6;         ///< re-solves per step before it is accepted anyway (counted)
  int friction_updates = 2;        ///< re-solves with the normal forces and tangents of the last solve
  int max_halvings = 4;            ///< step reductions after a failed solve before it throws
  void validate() const;
};

/// Points of another surface near the object during one step: positions at the step's start and end
/// (world) [m] and stiffness [N/m] per point.
struct SurfacePoints {
  std::vector<Eigen::Vector3d> start, end;
  std::vector<double> stiffness;
  /// Per point (empty: none): 1 when the point does not answer the contact itself (a body's skin outside its
  /// soft region, carried by the skeleton); its force is reported apart in RigidStepReport::rigid_surface_force.
  std::vector<char> rigid;
};

/// What one step did.
struct RigidStepReport {
  int newton_iterations = 0;
  int refinements = 0;
  int halvings = 0;
  bool unresolved = false;                                   ///< accepted deeper than the tolerance
  double max_penetration = 0.0;                              ///< [m] at the step's end, over obstacles and surfaces
  Eigen::Vector3d obstacle_force = Eigen::Vector3d::Zero();  ///< on the object from obstacles [N] (world)
  Eigen::Vector3d surface_force = Eigen::Vector3d::Zero();   ///< on the object from the surfaces [N]
  Eigen::Vector3d rigid_surface_force = Eigen::Vector3d::Zero();  ///< the part of it from rigid points [N]
  /// Friction on the object from the surfaces [N] (world), in total and per input surface and point (empty
  /// without friction); the surfaces feel the opposite.
  Eigen::Vector3d surface_friction_force = Eigen::Vector3d::Zero();
  std::vector<std::vector<Eigen::Vector3d>> surface_friction;
  double contact_energy = 0.0;  ///< penalty energy stored at the step's end [J]
  double friction_work = 0.0;   ///< D at the solution [J] (an estimate of the friction loss)
};

class RigidObject {
 public:
  /// shape: its local frame's origin is the centre of mass. Throws sflsh::Error on bad parameters.
  RigidObject(std::string name, std::shared_ptr<Obstacle> shape, const RigidProperties& properties,
              const RigidState& initial, const Eigen::Vector3d& gravity, const RigidObjectParameters& parameters);

  /// Advances by h [s] against `obstacles` (posed at the step's end) and `surfaces`.
  RigidStepReport step(double h, const std::vector<const Obstacle*>& obstacles,
                       const std::vector<SurfacePoints>& surfaces);

  const RigidState& state() const { return state_; }
  /// Sets the state when another solver stepped the object (a body's solve, docs/contact.md); throws when it is
  /// not finite.
  void set_state(const RigidState& state);
  const RigidProperties& properties() const { return properties_; }
  const Obstacle& shape() const { return *shape_; }
  const std::string& name() const { return name_; }
  /// ½ m |v|² + ½ ωᵀ I_world ω [J].
  double kinetic() const { return kinetic_energy(properties_, state_); }
  /// −m g·x [J] (zero at the world origin's height).
  double potential() const { return -properties_.mass * gravity_.dot(state_.placement.x); }
  /// The radius of the smallest ball about the centre of mass holding the shape [m].
  double bounding_radius() const { return bounding_radius_; }

 private:
  RigidStepReport solve(double h, const std::vector<const Obstacle*>& obstacles,
                        const std::vector<SurfacePoints>& surfaces);

  std::string name_;
  std::shared_ptr<Obstacle> shape_;
  RigidProperties properties_;
  RigidState state_;
  Eigen::Vector3d gravity_;
  RigidObjectParameters parameters_;
  std::vector<RigidSample> samples_;  ///< the shape's contact samples (k with factor 1)
  double bounding_radius_ = 0.0;
  double gyration_radius_ = 0.1;
};

/// The contact samples of a shape: a sphere its centre with its radius; a capsule points along its axis
/// with its radius; a box its corners, edge midpoints and face centres; each with k = stiffness · area / n.
std::vector<RigidSample> contact_samples(const Obstacle& shape, double area, double stiffness);

}  // namespace sflsh::scene
