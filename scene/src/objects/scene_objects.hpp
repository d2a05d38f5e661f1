#pragma once
// Internal to the scene runner: the scene's rigid objects (shape + world motion) and their copies placed in a
// body's frame for its contact potential.
#include "bodies/scene_internal.hpp"

#include <sflsh/scene/contact_potential.hpp>
#include <sflsh/scene/obstacle.hpp>
#include <sflsh/scene/rigid_motion.hpp>

#include <memory>
#include <vector>

namespace sflsh::scene::detail {

/// A scene object: its spec, its world motion and a shape posed in the world (for output and checks).
struct SceneObject {
  ObjectSpec spec;
  std::shared_ptr<RigidMotion> motion;  ///< world frame
  std::shared_ptr<Obstacle> world_shape;
};

/// The shape of an object spec in its local frame (a new instance each call); a free mesh is moved so that its
/// local origin is its centre of mass.

std::shared_ptr<Obstacle> make_shape(const ObjectSpec& spec);
/// The object with its world motion (a free object is held at its start until FreeObjects takes it over).
SceneObject make_object(const ObjectSpec& spec);
/// Every object's surface in the world at its current pose, merged (`object_id` per triangle in `ids`).
Surface merged_object_surfaces(const std::vector<SceneObject>& objects, Eigen::MatrixXd& ids);
/// The world pose of a spec's position and axis-angle rotation [degrees].
Pose spec_pose(const Eigen::Vector3d& position, const Eigen::Vector3d& rotation_degrees);
/// The start of a free object: its centre of mass and rotation (a mesh's `position` places the file's origin).
Pose free_start_pose(const ObjectSpec& spec);

/// An object's world motion seen from a body's frame (body_from_world ∘ world pose). The reaction force a
/// body commits is kept (rotated to the world) for the runner, which commits the sum over bodies once per
/// step to the world motion: several bodies may touch one free object.
class PlacedMotion final : public RigidMotion {
 public:
  PlacedMotion(std::shared_ptr<RigidMotion> world, const Rigid& body_from_world)
      : world_(std::move(world)), body_from_world_(body_from_world) {}
  Pose pose(double t) const override {
    const Pose w = world_->pose(t);
    return {body_from_world_.R * w.rotation, body_from_world_.R * w.translation + body_from_world_.t};
  }
  void commit(double t, const Eigen::Vector3d& force) override {
    committed_t_ = t;
    force_world_ = body_from_world_.R.transpose() * force;
  }
  bool reacts() const override { return world_->reacts(); }
  /// The force of the last commit (world) and clears it.
  Eigen::Vector3d take_force() {
    const Eigen::Vector3d f = force_world_;
    force_world_.setZero();
    return f;
  }

 private:
  std::shared_ptr<RigidMotion> world_;
  Rigid body_from_world_;
  double committed_t_ = 0.0;
  Eigen::Vector3d force_world_ = Eigen::Vector3d::Zero();
};

}  // namespace sflsh::scene::detail
