#pragma once
// How a rigid obstacle moves: fixed, prescribed by keyframes, or free (translation under gravity and the
// contact reaction). ContactPotential asks a motion for the pose at the end of each substep and, after an
// accepted substep, commits it with the contact force the body exerted on the object in that substep.
#include <sflsh/scene/obstacle.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <vector>

namespace sflsh::scene {

class RigidMotion {
 public:
  virtual ~RigidMotion() = default;
  /// The pose at time t [s]. For a free motion: the pose it would reach at t from its committed state.
  virtual Pose pose(double t) const = 0;
  /// After an accepted substep ending at t: `force` [N] (world) is the total contact force the bodies
  /// exerted on the object during it. Kinematic motions ignore it.
  virtual void commit(double /*t*/, const Eigen::Vector3d& /*force*/) {}
  /// True when the motion depends on the contact force (the object is free).
  virtual bool reacts() const { return false; }
};

/// An object that never moves.
class FixedMotion final : public RigidMotion {
 public:
  explicit FixedMotion(const Pose& pose = {}) : pose_(pose) {}
  Pose pose(double /*t*/) const override { return pose_; }

 private:
  Pose pose_;
};

/// One key of a prescribed motion: at time t [s] the object is at `position` [m] with `rotation`.
struct Keyframe {
  double t = 0.0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
};

enum class KeyframeInterpolation {
  linear,       ///< piecewise linear positions (C⁰)
  catmull_rom,  ///< C¹ cubic Hermite with Catmull–Rom tangents, zero tangents at the first and last key
};

/// A prescribed motion through keyframes (ascending times). Before the first key and after the last one
/// the object holds that key's pose. Positions follow `interpolation`; rotations are slerped between
/// neighbouring keys in both modes (C⁰ angular velocity at keys). With Catmull–Rom the tangent at an
/// inner key is m_i = (x_{i+1} − x_{i−1}) / (t_{i+1} − t_{i−1}) and 0 at the end keys, so the position is
/// C¹ everywhere including the transitions to the holds.
class KeyframeMotion final : public RigidMotion {
 public:
  /// Throws sflsh::Error when `keys` is empty or the times are not strictly increasing / finite.
  KeyframeMotion(std::vector<Keyframe> keys, KeyframeInterpolation interpolation = KeyframeInterpolation::catmull_rom);
  Pose pose(double t) const override;
  /// d position / dt [m/s] at t (0 in the holds).
  Eigen::Vector3d velocity(double t) const;
  const std::vector<Keyframe>& keys() const { return keys_; }

 private:
  std::vector<Keyframe> keys_;
  KeyframeInterpolation interpolation_;
};

/// A free object, translation only (its rotation stays the initial one): mass m, gravity g and the
/// contact reaction F. Semi-implicit Euler with the contact force lagged by one substep (and linearized by
/// set_contact_stiffness, below):
///   v_{n+1} = v_n + dt (g + F_n / m),   x_{n+1} = x_n + dt v_{n+1},
/// where F_n is the force committed at the end of the previous substep (the penalty on the body is
/// implicit in the body's solve, the reaction on the object is explicit). Stable while dt·√(k_c/m) ≲ 2
/// with k_c the summed contact stiffness of the touching nodes (docs/contact.md).
class FreeMotion final : public RigidMotion {
 public:
  /// mass [kg] > 0, gravity [m/s²], initial pose and velocity [m/s] at time t0 [s].
  FreeMotion(double mass, const Eigen::Vector3d& gravity, const Pose& initial, const Eigen::Vector3d& velocity,
             double t0 = 0.0);
  Pose pose(double t) const override;
  void commit(double t, const Eigen::Vector3d& force) override;
  bool reacts() const override { return true; }

  /// k [N/m] ≥ 0: the summed stiffness of the touching nodes. With k > 0 the lagged reaction is linearized,
  ///   (m + dt² k) v_{n+1} = m v_n + dt (m g + F_n),
  /// which is unconditionally stable (backward Euler on the object; isotropic k also damps the tangential
  /// motion while touching). 0 (the default): the explicit update above.
  void set_contact_stiffness(double k);
  double time() const { return t_; }
  const Eigen::Vector3d& position() const { return pose_.translation; }
  const Eigen::Vector3d& velocity() const { return velocity_; }
  double mass() const { return mass_; }

 private:
  /// The velocity after a step of dt from the committed state with the lagged force.
  Eigen::Vector3d predicted_velocity(double dt) const;

  double mass_;
  Eigen::Vector3d gravity_;
  Pose pose_;
  Eigen::Vector3d velocity_;
  Eigen::Vector3d force_ = Eigen::Vector3d::Zero();  ///< F_n: contact force of the last committed substep
  double contact_stiffness_ = 0.0;                   ///< k of set_contact_stiffness [N/m]
  double t_;
};

}  // namespace sflsh::scene
