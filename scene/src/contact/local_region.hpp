#pragma once
// Where a reduced body gets local bumps for contact (reduced/local_basis.hpp, docs/contact.md "Local resolution of
// contact"): the contact nodes an object reaches during the scene, found before the run from the body's skinned
// motion (its rest shape posed at sampled times) and each object's motion — a fixed or prescribed object at its pose
// of each sample, a free object along its ballistic path from its start until it first meets the skin.
#include "bodies/scene_internal.hpp"
#include "objects/scene_objects.hpp"

#include <vector>

namespace sflsh::scene::detail {

struct LocalRegionOptions {
  double reach = 0.005;  ///< a node is reached when the object's φ at its skinned position is below this [m]
  int samples = 120;     ///< times sampled over the scene (at most; every frame when fewer)
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();  ///< the free objects' [m/s²], world
  bool free_objects = false;  ///< also where free objects land (off: fixed and prescribed objects only)
};

/// Entries of `nodes` (ascending mesh nodes) an object reaches, for a body placed by `body_from_world`.
std::vector<int> reached_nodes(const SceneBody& body, const std::vector<int>& nodes, const Rigid& body_from_world,
                               const std::vector<SceneObject>& objects, double duration,
                               const LocalRegionOptions& options);

/// Gives a reduced body its local patch ([contact] local_*: reached_nodes, then SceneBody::set_local_region), before
/// the body starts; `gravity` [m/s²] is the free objects'.
void add_local_patch(SceneBody& body, const std::vector<int>& nodes, const Rigid& body_from_world,
                     const std::vector<SceneObject>& objects, const ContactSpec& contact, double duration,
                     const Eigen::Vector3d& gravity);

}  // namespace sflsh::scene::detail
