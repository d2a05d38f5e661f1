// Free objects in the body's solve: when, and how they are set up (object_coupling_setup.hpp).
#include "objects/object_coupling_setup.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/scene/contact_potential.hpp>

namespace sflsh::scene::detail {

std::string monolithic_blocker(const Scene& scene, const std::vector<std::unique_ptr<SceneBody>>& bodies) {
  if (scene.contact.object_coupling != "monolithic") return "[contact] object_coupling = \"staggered\"";
  if (!scene.effects.object_contact) return "object contact is off";
  if (bodies.size() != 1)
    return fmt::format("the scene has {} bodies (one Newton solve holds one body)", bodies.size());
  const SceneBody& body = *bodies.front();
  if (body.solver() != SolverKind::reduced)
    return fmt::format("body '{}' is solved {} (only the reduced solver takes objects in)", body.name(),
                       solver_name(body.solver()));
  if (!scene.effects.inertia) return "inertia is off";
  return {};
}

std::unique_ptr<CoupledObjects> make_coupled_objects(const Scene& scene, const SceneBody& body,
                                                     const BodyContact& contact, FreeObjects& free,
                                                     const std::vector<SceneObject>& objects,
                                                     const Eigen::Vector3d& gravity) {
  require(contact.objects != nullptr, "coupled objects: body '{}' has no object contact", body.name());
  CoupledSetup setup;
  for (const FreeObjects::Member& m : free.members()) {
    setup.objects.push_back(m.rigid);
    setup.friction.push_back(m.friction);
  }
  const ContactParameters parameters = contact_parameters(scene.contact);
  setup.nodes = contact.objects->nodes();
  const std::vector<double> areas = node_areas(body, setup.nodes);
  for (double a : areas) setup.node_stiffness.push_back(parameters.stiffness * a);  // k_i = stiffness · area_i [N/m]
  // The skin outside the soft layer: carried by the skeleton (the body's potential has no node there).
  const RowMatrixX3d world = body.world_surface();
  const std::vector<double> vertex_area = lumped_vertex_areas(world, body.model().faces);
  std::vector<int> rigid;
  for (std::size_t v = 0; v < contact.entry_of_vertex.size(); ++v)
    if (contact.entry_of_vertex[v] < 0) {
      rigid.push_back(static_cast<int>(v));
      setup.rigid_stiffness.push_back(parameters.stiffness * vertex_area[v]);
    }
  setup.rigid_positions = [&body, rigid](double t) {
    const RowMatrixX3d all = body.predicted_world_surface(t);
    RowMatrixX3d out(static_cast<Eigen::Index>(rigid.size()), 3);
    for (std::size_t k = 0; k < rigid.size(); ++k) out.row(static_cast<Eigen::Index>(k)) = all.row(rigid[k]);
    return out;
  };
  for (const SceneObject& o : objects)
    if (o.spec.motion != ObjectMotionKind::free) setup.obstacles.emplace_back(make_shape(o.spec), o.motion);
  setup.world_from_body = body.placement();
  setup.gravity = gravity;
  setup.parameters.margin = scene.contact.margin;
  setup.parameters.tolerance = scene.contact.tolerance;
  return std::make_unique<CoupledObjects>(std::move(setup));
}

}  // namespace sflsh::scene::detail
