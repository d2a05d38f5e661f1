#pragma once
// Internal to the scene runner: a soft body's contact (its potentials against the objects and the other
// bodies), the per-node skin areas that weight them, and the contact fields of its frames.
#include "bodies/scene_internal.hpp"
#include "objects/scene_objects.hpp"

#include <sflsh/core/vtk_io.hpp>
#include <sflsh/scene/contact_potential.hpp>
#include <sflsh/scene/node_loads.hpp>
#include <sflsh/scene/obstacle.hpp>

#include <nlohmann/json.hpp>

#include <memory>
#include <vector>

namespace sflsh::scene::detail {

/// A soft body's contact: its potentials against the objects and against the other bodies.
class CoupledObjects;

/// The dent the objects make at the step of the largest object contact force (docs/contact.md "Reduced against full
/// space"): the mean soft-tissue displacement |p − p_skinned| of the body's surface vertices within 10 cm of an
/// object's surface, and 10–20 cm away (the spread) [m], at that step's end.
struct Dent {
  double force = 0.0;  ///< the largest total contact force so far [N]
  double time = 0.0;   ///< [s]
  double dent = 0.0, spread = 0.0;
  int near_vertices = 0, far_vertices = 0;
};

struct BodyContact {
  std::shared_ptr<ContactPotential> objects;                  ///< null without object contact
  std::vector<std::shared_ptr<detail::PlacedMotion>> placed;  ///< per scene object (object potential)
  std::shared_ptr<ContactPotential> bodies;                   ///< null without body contact
  std::shared_ptr<NodeLoads> friction;  ///< the free objects' friction on the skin (null without free objects)
  std::vector<int> other;               ///< per body obstacle: the other body's index
  std::vector<std::shared_ptr<TriangleMesh>> surfaces;  ///< per body obstacle, in this body's frame
  std::vector<int> entry_of_node;                       ///< per layer node: its entry in the potentials, or −1
  std::vector<int> entry_of_vertex;  ///< per body vertex: the entry of the node it sits on, or −1 (not soft)
  double surface_seconds = 0.0;      ///< updating the other bodies' surfaces
  double max_penetration = 0.0;      ///< measured at the written frames on the skin [m]
  ContactPotential::Checkpoint objects_start, bodies_start;  ///< the potentials at the start of the step
  const CoupledObjects* coupled = nullptr;  ///< free objects in this body's solve (their push on the nodes), or null
  Dent dent;                                ///< of the object potential's obstacles
};

/// Sums over the bodies' potentials for the scene summary.
struct ContactTally {
  double object_seconds = 0.0, body_seconds = 0.0;  ///< object and body contact, the latter with the surface updates
  long potentials = 0;
  ContactStats total;  ///< broad-phase passes, narrow-phase evaluations, deepest penetration
};

/// summary.json "contact" of one soft body (empty without potentials): per potential its counters, largest
/// penetration and force, and for the objects the dent (Dent); adds to `tally`.
nlohmann::json contact_summary(const BodyContact& contact, ContactTally& tally);

/// Updates `contact.dent` when the object potential's largest force grew in the step that ended at t.
void record_dent(const SceneBody& body, BodyContact& contact, double t);

/// Lumped skin area per contact node: the region vertex's (lumped_vertex_areas) on the node it sits on;
/// nodes without a region vertex (embedded skins) get the mean.
std::vector<double> node_areas(const SceneBody& body, const std::vector<int>& nodes);
/// The potentials' parameters from the scene's [contact] (validated).
ContactParameters contact_parameters(const ContactSpec& spec);
/// Deepest penetration [m] of the listed world points into the shapes.
double deepest(const RowMatrixX3d& points, const std::vector<const Obstacle*>& shapes);
/// contact_force [N] and penetration [m] per body vertex from the body's potentials (world frame); none
/// without contact.
std::vector<vtk::Field> contact_fields(const BodyContact& contact, const SceneBody& body);

}  // namespace sflsh::scene::detail
