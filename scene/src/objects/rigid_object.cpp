// A free rigid object stepped implicitly (rigid_object.hpp).
#include <sflsh/core/error.hpp>
#include <sflsh/scene/rigid_object.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace sflsh::scene {

void RigidObjectParameters::validate() const {
  auto positive = [](double v, const char* name) {
    require(std::isfinite(v) && v > 0.0, "free object: {} must be positive (got {})", name, v);
  };
  require(std::isfinite(friction) && friction >= 0.0, "free object: friction must be ≥ 0 (got {})", friction);
  positive(slip_velocity, "slip_velocity [m/s]");
  positive(stiffness, "contact stiffness [N/m³]");
  require(std::isfinite(margin) && margin >= 0.0, "free object: margin must be ≥ 0 (got {} m)", margin);
  positive(tolerance, "contact tolerance [m]");
  require(std::isfinite(refinement_factor) && refinement_factor > 1.0,
          "free object: refinement_factor must be > 1 (got {})", refinement_factor);
  require(max_refinements >= 0 && friction_updates >= 0 && max_halvings >= 0,
          "free object: refinement, friction-update and halving counts must be ≥ 0");
}

std::vector<RigidSample> contact_samples(const Obstacle& shape, double area, double stiffness) {
  std::vector<RigidSample> samples;
  if (const auto* sphere = dynamic_cast<const Sphere*>(&shape)) {
    samples.push_back({Eigen::Vector3d::Zero(), sphere->radius(), 0.0});
  } else if (const auto* capsule = dynamic_cast<const Capsule*>(&shape)) {
    const int n = 5;  // the segment's ends and three inner points (a flat contact along the side)
    for (int i = 0; i < n; ++i)
      samples.push_back(
          {Eigen::Vector3d(0, 0, capsule->half_length() * (2.0 * i / (n - 1) - 1.0)), capsule->radius(), 0.0});
  } else if (const auto* box = dynamic_cast<const Box*>(&shape)) {
    // Corners, edge midpoints and face centres: every point of the 3×3×3 lattice on the surface.
    for (int i = -1; i <= 1; ++i)
      for (int j = -1; j <= 1; ++j)
        for (int k = -1; k <= 1; ++k)
          if (i != 0 || j != 0 || k != 0)
            samples.push_back({box->half_extent().cwiseProduct(Eigen::Vector3d(i, j, k)), 0.0, 0.0});
  } else if (const auto* mesh = dynamic_cast<const TriangleMesh*>(&shape)) {
    // Its vertices, at most 256 of them evenly by index (a flat face between them rests on its corners).
    const Eigen::Index n = mesh->vertices().rows();
    const Eigen::Index stride = std::max<Eigen::Index>(1, (n + 255) / 256);
    for (Eigen::Index v = 0; v < n; v += stride) samples.push_back({mesh->vertices().row(v).transpose(), 0.0, 0.0});
  } else {
    throw_error("free object: only spheres, boxes, capsules and meshes can be free");
  }
  for (RigidSample& s : samples) s.stiffness = stiffness * area / static_cast<double>(samples.size());
  return samples;
}

RigidObject::RigidObject(std::string name, std::shared_ptr<Obstacle> shape, const RigidProperties& properties,
                         const RigidState& initial, const Eigen::Vector3d& gravity,
                         const RigidObjectParameters& parameters)
    : name_(std::move(name)),
      shape_(std::move(shape)),
      properties_(properties),
      state_(initial),
      gravity_(gravity),
      parameters_(parameters) {
  parameters_.validate();
  require(std::isfinite(properties.mass) && properties.mass > 0.0,
          "free object '{}': mass must be positive (got {} kg)", name_, properties.mass);
  require(properties.second_moment.allFinite() && properties.second_moment.diagonal().minCoeff() > 0.0,
          "free object '{}': the second moment of mass must be positive definite", name_);
  require(initial.placement.x.allFinite() && initial.velocity.allFinite() && initial.angular_velocity.allFinite(),
          "free object '{}': position and velocities must be finite", name_);
  samples_ = contact_samples(*shape_, properties.area, parameters.stiffness);
  const Aabb box = shape_->local_bounds();
  bounding_radius_ = box.lower.cwiseAbs().cwiseMax(box.upper.cwiseAbs()).norm();
  gyration_radius_ = std::sqrt(properties.second_moment.trace() / properties.mass);
}

RigidStepReport RigidObject::step(double h, const std::vector<const Obstacle*>& obstacles,
                                  const std::vector<SurfacePoints>& surfaces) {
  require(std::isfinite(h) && h > 0.0, "free object '{}': step must be positive (got {} s)", name_, h);
  const RigidState saved = state_;
  std::string failure;
  for (int halving = 0; halving <= parameters_.max_halvings; ++halving) {
    const int n = 1 << halving;
    state_ = saved;
    RigidStepReport total;
    total.halvings = halving;
    bool ok = true;
    for (int k = 0; k < n && ok; ++k) {
      // The surfaces' points move linearly over the step.
      std::vector<SurfacePoints> part = surfaces;
      for (std::size_t s = 0; s < surfaces.size(); ++s)
        for (std::size_t i = 0; i < surfaces[s].start.size(); ++i) {
          const Eigen::Vector3d d = surfaces[s].end[i] - surfaces[s].start[i];
          part[s].start[i] = surfaces[s].start[i] + d * (static_cast<double>(k) / n);
          part[s].end[i] = surfaces[s].start[i] + d * (static_cast<double>(k + 1) / n);
        }
      try {
        const RigidStepReport r = solve(h / n, obstacles, part);
        total.newton_iterations += r.newton_iterations;
        total.refinements += r.refinements;
        total.unresolved = total.unresolved || r.unresolved;
        total.max_penetration = std::max(total.max_penetration, r.max_penetration);
        total.obstacle_force = r.obstacle_force;
        total.surface_force = r.surface_force;
        total.rigid_surface_force = r.rigid_surface_force;
        total.surface_friction_force = r.surface_friction_force;
        total.surface_friction = r.surface_friction;
        total.contact_energy = r.contact_energy;
        total.friction_work += r.friction_work;
      } catch (const Error& e) {
        failure = e.what();
        ok = false;
      }
    }
    if (ok) return total;
  }
  state_ = saved;
  throw_error("free object '{}': the step of {} s failed after {} halvings: {}", name_, h, parameters_.max_halvings,
              failure);
}

namespace {

/// The surface points a rigid object's step can reach, with what its contacts need of each.
struct RigidStepNearbyPoints {
  std::vector<Eigen::Vector3d> points, moved;
  std::vector<double> stiffness;
  std::vector<char> rigid;
  std::vector<std::pair<std::size_t, std::size_t>> origin;  // (surface, point) of each point
};

/// Broad phase: the surface points within `reach` of the object's position `x`, plus their own motion.
RigidStepNearbyPoints rigid_step_nearby_points(const std::vector<SurfacePoints>& surfaces, const Eigen::Vector3d& x,
                                               double reach) {
  RigidStepNearbyPoints nearby;
  for (std::size_t si = 0; si < surfaces.size(); ++si)
    for (std::size_t i = 0; i < surfaces[si].end.size(); ++i) {
      const SurfacePoints& s = surfaces[si];
      const Eigen::Vector3d d = s.end[i] - s.start[i];
      if ((s.end[i] - x).norm() < reach + d.norm()) {
        nearby.points.push_back(s.end[i]);
        nearby.moved.push_back(d);
        nearby.stiffness.push_back(s.stiffness[i]);
        nearby.rigid.push_back(s.rigid.empty() ? 0 : s.rigid[i]);
        nearby.origin.emplace_back(si, i);
      }
    }
  return nearby;
}

/// Friction contacts (point, other side's motion, normal, normal force) lagged from a placement.
std::vector<FrictionContact> rigid_step_friction_contacts(const RigidPlacement& P,
                                                          const RigidObstacleContactTerm& on_obstacles,
                                                          const std::vector<const Obstacle*>& obstacles,
                                                          const ObjectSurfaceContactTerm& on_surfaces,
                                                          const RigidStepNearbyPoints& nearby, double delta) {
  std::vector<FrictionContact> contacts;
  for (std::size_t s = 0; s < on_obstacles.samples().size(); ++s)
    for (std::size_t j = 0; j < obstacles.size(); ++j) {
      Eigen::Vector3d n;
      const double phi = on_obstacles.gap(P, s, j, &n);
      if (!(phi < delta)) continue;
      const RigidSample& sample = on_obstacles.samples()[s];
      contacts.push_back({sample.point - sample.radius * P.R.transpose() * n, Eigen::Vector3d::Zero(), n,
                          sample.stiffness * (delta - phi)});
    }
  for (std::size_t i = 0; i < nearby.points.size(); ++i) {
    Eigen::Vector3d n;
    const double phi = on_surfaces.gap(P, i, &n);
    if (!(phi < delta)) continue;
    const Eigen::Vector3d closest = P.R.transpose() * (nearby.points[i] - phi * n - P.x);  // on the object's surface
    contacts.push_back({closest, nearby.moved[i], n, on_surfaces.stiffness(i) * (delta - phi), static_cast<int>(i)});
  }
  return contacts;
}

/// The friction each surface point exerts at the solution, for the other side's reaction.
void rigid_step_surface_friction(const RigidFrictionTerm& friction, const RigidPlacement& placement,
                                 const std::vector<SurfacePoints>& surfaces, const RigidStepNearbyPoints& nearby,
                                 RigidStepReport& report) {
  report.surface_friction.assign(surfaces.size(), {});
  for (std::size_t si = 0; si < surfaces.size(); ++si)
    report.surface_friction[si].assign(surfaces[si].end.size(), Eigen::Vector3d::Zero());
  report.surface_friction_force.setZero();
  const std::vector<Eigen::Vector3d> forces = friction.forces(placement);
  for (std::size_t k = 0; k < forces.size(); ++k) {
    const int source = friction.contacts()[k].source;
    if (source < 0) continue;
    const auto [si, i] = nearby.origin[static_cast<std::size_t>(source)];
    report.surface_friction[si][i] += forces[k];
    report.surface_friction_force += forces[k];
  }
}

/// Penetration at the end: records the deepest in `report` and, when `stiffen`, stiffens every contact deeper
/// than the tolerance; returns whether any was.
bool rigid_step_stiffen_deep_contacts(RigidObstacleContactTerm& on_obstacles,
                                      const std::vector<const Obstacle*>& obstacles,
                                      ObjectSurfaceContactTerm& on_surfaces, std::size_t num_points,
                                      const RigidPlacement& placement, const RigidObjectParameters& parameters,
                                      bool stiffen, RigidStepReport& report) {
  bool too_deep = false;
  report.max_penetration = 0.0;
  for (std::size_t s = 0; s < on_obstacles.samples().size(); ++s)
    for (std::size_t j = 0; j < obstacles.size(); ++j) {
      const double depth = -on_obstacles.gap(placement, s, j);
      report.max_penetration = std::max(report.max_penetration, depth);
      if (depth > parameters.tolerance) {
        too_deep = true;
        if (stiffen) on_obstacles.samples()[s].stiffness *= parameters.refinement_factor;
      }
    }
  for (std::size_t i = 0; i < num_points; ++i) {
    const double depth = -on_surfaces.gap(placement, i);
    report.max_penetration = std::max(report.max_penetration, depth);
    if (depth > parameters.tolerance) {
      too_deep = true;
      if (stiffen) on_surfaces.scale_stiffness(i, parameters.refinement_factor);
    }
  }
  return too_deep;
}

/// The contact energy at the solution and the contact forces on the object: from the obstacles, from the
/// surfaces, and the rigid surface points' share of the latter.
void rigid_step_contact_forces(const RigidObstacleContactTerm& on_obstacles,
                               const ObjectSurfaceContactTerm& on_surfaces, const RigidStepNearbyPoints& nearby,
                               const RigidPlacement& placement, double delta, RigidStepReport& report) {
  Vector6d g_obstacles = Vector6d::Zero(), g_surfaces = Vector6d::Zero();
  report.contact_energy =
      on_obstacles.evaluate(placement, &g_obstacles, nullptr) + on_surfaces.evaluate(placement, &g_surfaces, nullptr);
  report.obstacle_force = -g_obstacles.head<3>();  // F = −∂u/∂x
  report.surface_force = -g_surfaces.head<3>();
  // The rigid points' share: u_i = ½ k_i (δ − φ_i)² pushes the object by −k_i (δ − φ_i) n_i (n_i: from the
  // object's surface to the point).
  for (std::size_t i = 0; i < nearby.points.size(); ++i) {
    if (!nearby.rigid[i]) continue;
    Eigen::Vector3d n;
    const double phi = on_surfaces.gap(placement, i, &n);
    if (phi < delta) report.rigid_surface_force -= on_surfaces.stiffness(i) * (delta - phi) * n;
  }
}

}  // namespace

RigidStepReport RigidObject::solve(double h, const std::vector<const Obstacle*>& obstacles,
                                   const std::vector<SurfacePoints>& surfaces) {
  const RigidPlacement start = state_.placement;
  const double delta = parameters_.margin;
  const RigidInertiaTerm inertia(properties_, state_, h, gravity_);
  RigidObstacleContactTerm on_obstacles(samples_, obstacles, delta);

  // Broad phase: surface points that can come within δ of the object in this step.
  const double reach = bounding_radius_ + delta + h * state_.velocity.norm() +
                       h * state_.angular_velocity.norm() * bounding_radius_ + 0.02;
  const RigidStepNearbyPoints nearby = rigid_step_nearby_points(surfaces, start.x, reach);
  ObjectSurfaceContactTerm on_surfaces(*shape_, nearby.points, nearby.stiffness, delta);
  auto friction_at = [&](const RigidPlacement& P) {
    return rigid_step_friction_contacts(P, on_obstacles, obstacles, on_surfaces, nearby, delta);
  };

  RigidNewtonSettings settings;
  settings.length = gyration_radius_;
  settings.tolerance = 1e-10 + 1e-6 * parameters_.tolerance;
  RigidStepReport report;
  RigidPlacement placement = start;
  std::vector<FrictionContact> contacts = friction_at(start);
  const double epsilon = parameters_.slip_velocity * h;
  for (int refinement = 0;; ++refinement) {
    for (int update = 0; update <= parameters_.friction_updates; ++update) {
      const RigidFrictionTerm friction(contacts, start, parameters_.friction, epsilon);
      const std::vector<const RigidTerm*> terms = {&inertia, &on_obstacles, &on_surfaces, &friction};
      const RigidNewtonResult result = minimize_rigid(terms, placement, settings);
      report.newton_iterations += result.iterations;
      if (!result.converged) throw_error("{}", result.failure);
      if (parameters_.friction == 0.0) break;
      contacts = friction_at(placement);
      if (update == parameters_.friction_updates) {
        report.friction_work = friction.evaluate(placement, nullptr, nullptr);
        rigid_step_surface_friction(friction, placement, surfaces, nearby, report);
      }
    }
    // Penetration at the end: stiffen what is deeper than the tolerance and solve again.
    const bool too_deep =
        rigid_step_stiffen_deep_contacts(on_obstacles, obstacles, on_surfaces, nearby.points.size(), placement,
                                         parameters_, refinement < parameters_.max_refinements, report);
    if (!too_deep) break;
    if (refinement == parameters_.max_refinements) {
      report.unresolved = true;
      break;
    }
    ++report.refinements;
    placement = start;
    contacts = friction_at(start);
  }
  if (!placement.x.allFinite() || !placement.R.allFinite()) throw_error("NaN/Inf in the placement after the solve");

  rigid_step_contact_forces(on_obstacles, on_surfaces, nearby, placement, delta, report);
  // v_{n+1} = (x_{n+1} − x_n)/h,  ω_{n+1} = log(R_{n+1} R_nᵀ)/h (world).
  state_.velocity = (placement.x - start.x) / h;
  state_.angular_velocity = rotation_log(placement.R * start.R.transpose()) / h;
  placement.R = Eigen::Quaterniond(placement.R).normalized().toRotationMatrix();  // round-off back onto SO(3)
  state_.placement = placement;
  return report;
}

void RigidObject::set_state(const RigidState& state) {
  require(state.placement.x.allFinite() && state.placement.R.allFinite() && state.velocity.allFinite() &&
              state.angular_velocity.allFinite(),
          "free object '{}': its new state is not finite", name_);
  state_ = state;
}

}  // namespace sflsh::scene
