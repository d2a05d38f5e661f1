#pragma once
// Internal to the scene runner: the scene's free objects (motion = "free"), rigid with six degrees of
// freedom (rigid_object.hpp). Each step, before the bodies, every free object is solved implicitly against
// the ground and the other objects posed at the step's end and against every body's skin (its surface now
// and predicted at the step's end). The bodies then solve against the object's new pose in their own
// ContactPotential, so both sides of the contact are implicit; the exchange is staggered once per step.
// The energy balance, contact forces and penetration go into summary.json → free_objects.
#include "bodies/scene_internal.hpp"
#include "contact/scene_contact.hpp"
#include "objects/scene_objects.hpp"

#include <sflsh/core/summary.hpp>
#include <sflsh/scene/rigid_object.hpp>

#include <memory>
#include <utility>
#include <vector>

namespace sflsh::scene::detail {

/// The pose of a free object as its last solve left it (the runner's objects and the bodies' potentials
/// read it; the object is not moved by commit()).
class SolvedMotion final : public RigidMotion {
 public:
  explicit SolvedMotion(const Pose& pose) : pose_(pose) {}
  Pose pose(double /*t*/) const override { return pose_; }
  void set(const Pose& pose) { pose_ = pose; }

 private:
  Pose pose_;
};

/// The mass properties of a free object's spec: from `density`, or scaled to `mass`. Throws sflsh::Error
/// for shapes that cannot be free.
RigidProperties free_object_properties(const ObjectSpec& spec);

/// A body's surface over a step: world vertices now and predicted at the step's end, stiffness per vertex.
struct BodySurfaceStep {
  RowMatrixX3d start, end;
  std::vector<double> stiffness;  ///< [N/m]
  std::vector<char> rigid;        ///< 1: the vertex is not a contact node of the body's soft layer
};

/// What body_surfaces() computes once per body: k = stiffness · lumped area [N/m] per vertex.
struct BodySurfaceCache {
  std::vector<std::vector<double>> stiffness;
};

/// Every body's surface over [now, t1] for the free objects (the cache is filled on the first call). A vertex
/// is rigid when it sits on no entry of the body's object-contact potential (BodyContact::entry_of_vertex:
/// outside the soft region, an embedded skin, or a skinned body): the skeleton, which follows its motion, takes
/// its force. A soft vertex's stiffness carries the refinement factor its node has now in that potential, so
/// that the object pushes with the stiffness the body feels.
std::vector<BodySurfaceStep> body_surfaces(const std::vector<std::unique_ptr<SceneBody>>& bodies,
                                           const std::vector<BodyContact>& contact, const ContactSpec& spec, double t1,
                                           BodySurfaceCache& cache);

class FreeObjects {
 public:
  /// Builds a RigidObject for every free object of `objects` (their motions become SolvedMotion).
  FreeObjects(std::vector<SceneObject>& objects, const ContactSpec& contact, const Eigen::Vector3d& gravity);
  bool empty() const { return free_.empty(); }

  /// Steps every free object over [t0, t0 + h] (see above); errors name the object.
  void step(double t0, double h, const std::vector<BodySurfaceStep>& bodies);
  /// The free objects (scene object index, rigid body, friction coefficient), in order.
  struct Member {
    std::size_t object = 0;
    RigidObject* rigid = nullptr;
    double friction = 0.0;
  };
  std::vector<Member> members();
  /// The objects are stepped in a body's solve (coupled_objects.hpp): step() is not called; after each step the
  /// runner passes what the solve did per member (in members() order) with the step's end time.
  void set_coupled() { coupled_ = true; }
  bool coupled() const { return coupled_; }
  void account_coupled(const std::vector<RigidStepReport>& reports, double t1, double seconds);
  /// Per body: (vertex, friction force [N], world) the objects exerted on the body's skin vertices in the last
  /// step (the opposite of what they felt), for the bodies' own solves of the step; rigid vertices omitted.
  const std::vector<std::vector<std::pair<int, Eigen::Vector3d>>>& friction_on_bodies() const {
    return friction_on_bodies_;
  }
  /// The force the bodies' potentials exerted on object j in the last step [N] (world), for the summary.
  void add_body_reaction(std::size_t object, const Eigen::Vector3d& force);
  /// Energies [J] per object and step are sampled at every call (the runner calls it once per frame).
  void record(double t);
  nlohmann::json summary() const;
  double seconds() const { return seconds_; }  ///< in the objects' solves [s]

 private:
  struct Free {
    std::size_t object = 0;  ///< index in the runner's objects
    std::unique_ptr<RigidObject> rigid;
    std::shared_ptr<SolvedMotion> motion;
    double initial_energy = 0.0;       ///< T + V at t = 0 [J]
    double last_contact_energy = 0.0;  ///< penalty energy at the last step's end [J]
    double max_energy_gain = 0.0;      ///< max over steps of E − E(0), E = T + V + penalty [J]
    double friction_work = 0.0;        ///< Σ D at the solutions [J]
    double max_obstacle_force = 0.0, max_surface_force = 0.0, max_body_reaction = 0.0;  ///< [N]
    double max_skeleton_force = 0.0;  ///< the part of the surface force from rigid vertices [N]
    Eigen::Vector3d last_surface_force = Eigen::Vector3d::Zero(), last_skeleton_force = Eigen::Vector3d::Zero();
    Eigen::Vector3d last_body_reaction = Eigen::Vector3d::Zero();  ///< [N] of the last step
    Eigen::Vector3d last_friction = Eigen::Vector3d::Zero();       ///< on the object from the skins [N]
    Eigen::Vector3d last_soft_friction = Eigen::Vector3d::Zero();  ///< its part from soft vertices [N]
    double max_friction = 0.0;                                     ///< [N]
    double max_penetration = 0.0;                                  ///< over the steps [m]
    double last_penetration = 0.0;                                 ///< at the last step [m]
    double resting_max_penetration = 0.0;                          ///< over the last second [m]
    double last_time = 0.0;
    std::vector<std::pair<double, double>> penetration_history;  ///< (t, depth) of the last second
    long steps = 0, newton_iterations = 0, refinements = 0, halvings = 0, unresolved = 0;
    nlohmann::json frames = nlohmann::json::array();  ///< per written frame: t, energies
  };

  /// The step's bookkeeping of one object (energies, forces, penetration), its pose to the scene's object.
  void account(Free& f, const RigidStepReport& r, double t1);

  std::vector<SceneObject>& objects_;
  bool coupled_ = false;
  std::vector<Free> free_;
  std::vector<std::pair<std::size_t, std::shared_ptr<Obstacle>>> obstacles_;  ///< the other objects' shapes
  std::vector<std::vector<std::pair<int, Eigen::Vector3d>>> friction_on_bodies_;
  double tolerance_ = 1e-3;
  double seconds_ = 0.0;
};

}  // namespace sflsh::scene::detail
