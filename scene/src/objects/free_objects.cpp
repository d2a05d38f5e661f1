// The scene's free rigid objects (free_objects.hpp).
#include "objects/free_objects.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/scoped_seconds.hpp>

#include <algorithm>
#include <chrono>

namespace sflsh::scene::detail {

namespace {
nlohmann::json vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
Pose to_pose(const RigidPlacement& p) {
  Pose pose;
  pose.rotation = p.R;
  pose.translation = p.x;
  return pose;
}
}  // namespace

RigidProperties free_object_properties(const ObjectSpec& spec) {
  const double density = spec.density > 0.0 ? spec.density : 1000.0;
  RigidProperties p;
  switch (spec.shape) {
    case ShapeKind::sphere:
      p = sphere_properties(spec.radius, density);
      break;
    case ShapeKind::box:
      p = box_properties(spec.half_extents, density);
      break;
    case ShapeKind::capsule:
      p = capsule_properties(spec.radius, 0.5 * spec.length, density);
      break;
    case ShapeKind::mesh: {
      const std::shared_ptr<Obstacle> shape = make_shape(spec);  // centred on its centre of mass
      const auto& mesh = dynamic_cast<const TriangleMesh&>(*shape);
      Eigen::Vector3d centre;
      p = mesh_properties(mesh.vertices(), mesh.triangles(), density, centre);
      break;
    }
    case ShapeKind::plane:
      throw_error("a free object must be a sphere, box, capsule or closed mesh (got a {})", shape_name(spec.shape));
  }
  return spec.density > 0.0 ? p : p.with_mass(spec.mass);
}

std::vector<BodySurfaceStep> body_surfaces(const std::vector<std::unique_ptr<SceneBody>>& bodies,
                                           const std::vector<BodyContact>& contact, const ContactSpec& spec, double t1,
                                           BodySurfaceCache& cache) {
  std::vector<BodySurfaceStep> out(bodies.size());
  if (cache.stiffness.size() != bodies.size()) {
    const double k = contact_parameters(spec).stiffness;  // [N/m³]
    cache = {};
    for (const auto& body : bodies) {
      std::vector<double> area = lumped_vertex_areas(body->world_surface(), body->model().faces);
      for (double& a : area) a *= k;  // k_i = stiffness · area_i [N/m]
      cache.stiffness.push_back(std::move(area));
    }
  }
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    out[b].start = bodies[b]->world_surface();
    out[b].end = bodies[b]->predicted_world_surface(t1);
    out[b].stiffness = cache.stiffness[b];
    out[b].rigid.assign(out[b].stiffness.size(), 1);
    const BodyContact& c = contact[b];
    if (!c.objects) continue;
    for (std::size_t v = 0; v < out[b].stiffness.size() && v < c.entry_of_vertex.size(); ++v)
      if (const int entry = c.entry_of_vertex[v]; entry >= 0) {
        out[b].rigid[v] = 0;
        out[b].stiffness[v] *= c.objects->stiffness_factor(entry);
      }
  }
  return out;
}

FreeObjects::FreeObjects(std::vector<SceneObject>& objects, const ContactSpec& contact, const Eigen::Vector3d& gravity)
    : objects_(objects), tolerance_(contact.tolerance) {
  RigidObjectParameters parameters;
  parameters.margin = contact.margin;
  parameters.tolerance = contact.tolerance;
  for (std::size_t j = 0; j < objects.size(); ++j) {
    SceneObject& o = objects[j];
    if (o.spec.motion != ObjectMotionKind::free) {
      obstacles_.emplace_back(j, make_shape(o.spec));
      continue;
    }
    parameters.friction = o.spec.friction;
    RigidState initial;
    const Pose start = free_start_pose(o.spec);
    initial.placement = {start.translation, start.rotation};
    initial.velocity = o.spec.velocity;
    initial.angular_velocity = o.spec.angular_velocity;
    Free f;
    f.object = j;
    f.rigid = std::make_unique<RigidObject>(o.spec.name, make_shape(o.spec), free_object_properties(o.spec), initial,
                                            gravity, parameters);
    f.motion = std::make_shared<SolvedMotion>(start);
    f.initial_energy = f.rigid->kinetic() + f.rigid->potential();
    o.motion = f.motion;
    o.world_shape->set_pose(start);
    free_.push_back(std::move(f));
  }
}

void FreeObjects::step(double t0, double h, const std::vector<BodySurfaceStep>& bodies) {
  const auto clock = std::chrono::steady_clock::now();
  const double t1 = t0 + h;
  // The other objects at the step's end (free objects do not touch each other).
  std::vector<const Obstacle*> obstacles;
  for (const auto& [j, shape] : obstacles_) {
    shape->set_pose(objects_[j].motion->pose(t1));
    obstacles.push_back(shape.get());
  }
  friction_on_bodies_.assign(bodies.size(), {});
  for (Free& f : free_) {
    std::vector<SurfacePoints> surfaces;
    std::vector<std::size_t> surface_body;         // per surface: its body
    std::vector<std::vector<int>> surface_vertex;  // per surface and point: the body vertex
    const Eigen::Vector3d centre = f.rigid->state().placement.x;
    // Only the vertices within reach of the object's ball over the step (the object refines this).
    const double reach = f.rigid->bounding_radius() + h * f.rigid->state().velocity.norm() + 0.05;
    for (std::size_t bi = 0; bi < bodies.size(); ++bi) {
      const BodySurfaceStep& b = bodies[bi];
      SurfacePoints s;
      std::vector<int> vertex;
      for (Eigen::Index v = 0; v < b.end.rows(); ++v) {
        const Eigen::Vector3d e = b.end.row(v).transpose(), a = b.start.row(v).transpose();
        if ((e - centre).norm() > reach + (e - a).norm()) continue;
        s.start.push_back(a);
        s.end.push_back(e);
        s.stiffness.push_back(b.stiffness[static_cast<std::size_t>(v)]);
        s.rigid.push_back(b.rigid[static_cast<std::size_t>(v)]);
        vertex.push_back(static_cast<int>(v));
      }
      if (s.end.empty()) continue;
      surfaces.push_back(std::move(s));
      surface_body.push_back(bi);
      surface_vertex.push_back(std::move(vertex));
    }
    const RigidStepReport r = f.rigid->step(h, obstacles, surfaces);
    account(f, r, t1);
    // Friction: the bodies' soft skins take the opposite of what each of their vertices exerted.
    f.last_soft_friction.setZero();
    for (std::size_t s = 0; s < r.surface_friction.size(); ++s)
      for (std::size_t i = 0; i < r.surface_friction[s].size(); ++i) {
        const Eigen::Vector3d& force = r.surface_friction[s][i];
        if (force.isZero(0.0) || surfaces[s].rigid[i]) continue;
        f.last_soft_friction += force;
        friction_on_bodies_[surface_body[s]].emplace_back(surface_vertex[s][i], -force);
      }
  }
  seconds_ += seconds_since(clock);
}

void FreeObjects::account(Free& f, const RigidStepReport& r, double t1) {
  f.motion->set(to_pose(f.rigid->state().placement));
  objects_[f.object].world_shape->set_pose(f.motion->pose(t1));
  ++f.steps;
  f.newton_iterations += r.newton_iterations;
  f.refinements += r.refinements;
  f.halvings += r.halvings;
  f.unresolved += r.unresolved ? 1 : 0;
  f.last_contact_energy = r.contact_energy;
  f.friction_work += r.friction_work;
  f.max_obstacle_force = std::max(f.max_obstacle_force, r.obstacle_force.norm());
  f.max_surface_force = std::max(f.max_surface_force, r.surface_force.norm());
  f.max_skeleton_force = std::max(f.max_skeleton_force, r.rigid_surface_force.norm());
  f.last_surface_force = r.surface_force;
  f.last_skeleton_force = r.rigid_surface_force;
  f.last_friction = r.surface_friction_force;
  f.max_friction = std::max(f.max_friction, r.surface_friction_force.norm());
  f.max_penetration = std::max(f.max_penetration, r.max_penetration);
  f.last_penetration = r.max_penetration;
  f.last_time = t1;
  f.penetration_history.emplace_back(t1, r.max_penetration);
  while (!f.penetration_history.empty() && f.penetration_history.front().first < t1 - 1.0)
    f.penetration_history.erase(f.penetration_history.begin());
  const double energy = f.rigid->kinetic() + f.rigid->potential() + r.contact_energy;
  f.max_energy_gain = std::max(f.max_energy_gain, energy - f.initial_energy);
}

std::vector<FreeObjects::Member> FreeObjects::members() {
  std::vector<Member> out;
  for (Free& f : free_) out.push_back({f.object, f.rigid.get(), objects_[f.object].spec.friction});
  return out;
}

void FreeObjects::account_coupled(const std::vector<RigidStepReport>& reports, double t1, double seconds) {
  seconds_ += seconds;
  require(reports.size() == free_.size(), "free objects: {} reports for {} objects", reports.size(), free_.size());
  for (std::size_t k = 0; k < free_.size(); ++k) {
    Free& f = free_[k];
    const RigidStepReport& r = reports[k];
    account(f, r, t1);
    // One solve: the soft layer felt exactly the opposite of its penalty and friction on the object.
    f.last_soft_friction = r.surface_friction_force;
    add_body_reaction(f.object, r.surface_force - r.rigid_surface_force);
  }
}

void FreeObjects::add_body_reaction(std::size_t object, const Eigen::Vector3d& force) {
  for (Free& f : free_)
    if (f.object == object) {
      // The soft layers' penalty and the friction they took (applied to them as loads).
      const Eigen::Vector3d total = force + f.last_soft_friction;
      f.max_body_reaction = std::max(f.max_body_reaction, total.norm());
      f.last_body_reaction = total;
    }
}

void FreeObjects::record(double t) {
  for (Free& f : free_) {
    const RigidState& s = f.rigid->state();
    f.frames.push_back({{"t", t},
                        {"kinetic_J", f.rigid->kinetic()},
                        {"potential_J", f.rigid->potential()},
                        {"contact_J", f.last_contact_energy},
                        {"position_m", vec(s.placement.x)},
                        {"penetration_m", f.last_penetration}});
  }
}

nlohmann::json FreeObjects::summary() const {
  nlohmann::json out = nlohmann::json::array();
  for (const Free& f : free_) {
    const RigidObject& r = *f.rigid;
    const RigidState& s = r.state();
    const double kinetic = r.kinetic(), potential = r.potential();
    const double total = kinetic + potential + f.last_contact_energy;
    double resting = 0.0;
    for (const auto& [t, d] : f.penetration_history) resting = std::max(resting, d);
    const Eigen::Vector3d inertia = r.properties().inertia().diagonal();
    const SceneObject& o = objects_[f.object];
    out.push_back({{"name", o.spec.name},
                   {"shape", shape_name(o.spec.shape)},
                   {"coupling", coupled_ ? "monolithic" : "staggered"},
                   {"mass_kg", r.properties().mass},
                   {"inertia_kg_m2", vec(inertia)},
                   {"friction", o.spec.friction},
                   {"final_position_m", vec(s.placement.x)},
                   {"final_velocity_m_per_s", vec(s.velocity)},
                   {"final_angular_velocity_rad_per_s", vec(s.angular_velocity)},
                   {"energy",
                    {{"initial_J", f.initial_energy},
                     {"kinetic_J", kinetic},
                     {"potential_J", potential},
                     {"contact_J", f.last_contact_energy},
                     {"total_J", total},
                     {"drift_J", total - f.initial_energy},
                     {"dissipated_J", f.initial_energy - total},
                     {"friction_estimate_J", f.friction_work},
                     {"max_gain_J", f.max_energy_gain},
                     {"note",
                      "E = kinetic + gravity potential (−m g·x) + penalty; dissipated = initial − E, which includes "
                      "the work done on bodies"}}},
                   {"contact",
                    {{"tolerance_m", tolerance_},
                     {"max_obstacle_force_N", f.max_obstacle_force},
                     {"max_body_force_N", f.max_surface_force},
                     {"max_body_reaction_N", f.max_body_reaction},
                     {"max_skeleton_force_N", f.max_skeleton_force},
                     {"max_friction_force_N", f.max_friction},
                     {"final_friction_force_N", vec(f.last_friction)},
                     {"final_body_force_N", vec(f.last_surface_force)},
                     {"final_skeleton_force_N", vec(f.last_skeleton_force)},
                     {"final_body_reaction_N", vec(f.last_body_reaction)},
                     {"note",
                      "body_force: penalty on the object from the bodies' skins (object side); skeleton_force: its "
                      "part from skin outside the soft layers, carried by the skeletons; friction_force: friction on "
                      "the object from the skins; body_reaction: penalty of the soft layers' contact potentials "
                      "(body side) plus the friction the soft layers took as loads, on the object"},
                     {"max_penetration_m", f.max_penetration},
                     {"final_penetration_m", f.last_penetration},
                     {"last_second_max_penetration_m", resting}}},
                   {"solver",
                    {{"steps", f.steps},
                     {"newton_iterations", f.newton_iterations},
                     {"refinements", f.refinements},
                     {"halved_steps", f.halvings},
                     {"unresolved_steps", f.unresolved}}},
                   {"frames", f.frames}});
  }
  return out;
}

}  // namespace sflsh::scene::detail
