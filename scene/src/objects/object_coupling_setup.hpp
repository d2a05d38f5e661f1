#pragma once
// Internal to the scene runner: whether the scene's free objects can be solved in the body's Newton solve
// (coupled_objects.hpp), and building them for it.
#include "bodies/scene_internal.hpp"
#include "contact/scene_contact.hpp"
#include "objects/coupled_objects.hpp"
#include "objects/free_objects.hpp"
#include "objects/scene_objects.hpp"

#include <memory>
#include <string>
#include <vector>

namespace sflsh::scene::detail {

/// Empty when the free objects of the scene can share the body's solve ([contact] object_coupling =
/// "monolithic", one body, soft and reduced, with inertia, object contact on); else why not.
std::string monolithic_blocker(const Scene& scene, const std::vector<std::unique_ptr<SceneBody>>& bodies);

/// The coupled objects of `free` for `body`, whose object-contact potential (`contact.objects`) leaves the free
/// objects out; the other objects become their obstacles. Call after the body's BodyContact is built.
std::unique_ptr<CoupledObjects> make_coupled_objects(const Scene& scene, const SceneBody& body,
                                                     const BodyContact& contact, FreeObjects& free,
                                                     const std::vector<SceneObject>& objects,
                                                     const Eigen::Vector3d& gravity);

}  // namespace sflsh::scene::detail
