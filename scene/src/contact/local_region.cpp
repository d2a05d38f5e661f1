#include "contact/local_region.hpp"

#include <sflsh/core/error.hpp>

#include <algorithm>
#include <cmath>

namespace sflsh::scene::detail {

namespace {

/// The contact nodes' skinned positions at t: the rest shape posed by the body's motion (no elastic displacement).
RowMatrixX3d skinned_nodes(const model::Problem& problem, const std::vector<int>& nodes, double t) {
  RowMatrixX3d p(static_cast<Eigen::Index>(nodes.size()), 3);
  model::NodeFrame frame;
  if (problem.trajectory) problem.trajectory->evaluate_nodes(t, nodes, frame);
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const auto row = static_cast<Eigen::Index>(k);
    const Eigen::Vector3d x = problem.rest.row(nodes[k]).transpose();
    const Eigen::Vector3d posed =
        problem.trajectory ? Eigen::Vector3d(frame.A[k] * x + frame.d.row(row).transpose()) : x;
    p.row(row) = posed.transpose();
  }
  return p;
}

/// Marks the nodes within `reach` of the shape at `pose` (body frame); returns whether any is inside it.
bool mark_reached(Obstacle& shape, const Pose& pose, const RowMatrixX3d& p, double reach, std::vector<char>& reached) {
  shape.set_pose(pose);
  Aabb box = shape.bounds();
  box.lower.array() -= reach;
  box.upper.array() += reach;
  bool inside = false;
  for (Eigen::Index k = 0; k < p.rows(); ++k) {
    const Eigen::Vector3d x = p.row(k).transpose();
    if ((x.array() < box.lower.array()).any() || (x.array() > box.upper.array()).any()) continue;
    const double phi = shape.distance(x);
    if (phi < reach) reached[static_cast<std::size_t>(k)] = 1;
    inside = inside || phi < 0.0;
  }
  return inside;
}

}  // namespace

std::vector<int> reached_nodes(const SceneBody& body, const std::vector<int>& nodes, const Rigid& body_from_world,
                               const std::vector<SceneObject>& objects, double duration,
                               const LocalRegionOptions& options) {
  require(options.samples >= 1, "local region: at least one time sample");
  const model::Problem& problem = body.layer().problem;
  std::vector<char> reached(nodes.size(), 0);
  const int samples = std::max(1, options.samples);
  std::vector<RowMatrixX3d> skinned(static_cast<std::size_t>(samples) + 1);
  auto time_of = [&](int k) { return duration * k / samples; };
  auto at = [&](int k) -> const RowMatrixX3d& {
    auto& p = skinned[static_cast<std::size_t>(k)];
    if (p.rows() == 0) p = skinned_nodes(problem, nodes, time_of(k));
    return p;
  };
  const auto to_body = [&](const Pose& world) {
    return Pose{body_from_world.R * world.rotation, body_from_world.R * world.translation + body_from_world.t};
  };
  for (const SceneObject& object : objects) {
    const std::shared_ptr<Obstacle> shape = make_shape(object.spec);
    if (object.spec.motion != ObjectMotionKind::free) {
      for (int k = 0; k <= samples; ++k)
        mark_reached(*shape, to_body(object.motion->pose(time_of(k))), at(k), options.reach, reached);
      continue;
    }
    if (!options.free_objects) continue;
    // A free object: along its ballistic path until it is in the skin (where it lands).
    const Pose start = object.motion->pose(0.0);
    for (int k = 0; k <= samples; ++k) {
      const double t = time_of(k);
      Pose world = start;
      world.translation += object.spec.velocity * t + 0.5 * options.gravity * t * t;
      if (mark_reached(*shape, to_body(world), at(k), options.reach, reached)) break;
    }
  }
  std::vector<int> out;
  for (std::size_t k = 0; k < nodes.size(); ++k)
    if (reached[k]) out.push_back(nodes[k]);
  return out;
}

void add_local_patch(SceneBody& body, const std::vector<int>& nodes, const Rigid& body_from_world,
                     const std::vector<SceneObject>& objects, const ContactSpec& contact, double duration,
                     const Eigen::Vector3d& gravity) {
  LocalRegionOptions region;
  region.reach = contact.local_reach;
  region.free_objects = contact.local_free_objects;
  region.gravity = gravity;
  reduced::LocalBasisOptions patch;
  patch.spacing = contact.local_spacing;
  patch.depth = contact.local_depth;
  body.set_local_region(reached_nodes(body, nodes, body_from_world, objects, duration, region), patch,
                        contact.local_max_nodes);
}

}  // namespace sflsh::scene::detail
