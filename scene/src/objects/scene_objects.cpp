// The scene's rigid objects (scene_objects.hpp).
#include "objects/scene_objects.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/scene/rigid_body.hpp>

namespace sflsh::scene::detail {

Pose spec_pose(const Eigen::Vector3d& position, const Eigen::Vector3d& rotation_degrees) {
  Pose pose;
  pose.translation = position;
  const double angle = rotation_degrees.norm() * EIGEN_PI / 180.0;
  if (angle > 0.0) pose.rotation = Eigen::AngleAxisd(angle, rotation_degrees.normalized()).toRotationMatrix();
  return pose;
}

namespace {

/// A free mesh object's file, moved so that its local origin is its centre of mass (the rigid body's frame,
/// rigid_body.hpp); `centre` [m] is that point in the file's frame.
std::shared_ptr<TriangleMesh> centred_mesh(const ObjectSpec& spec, Eigen::Vector3d& centre) {
  const std::unique_ptr<TriangleMesh> file = TriangleMesh::load(spec.mesh_path, spec.scale);
  require(file->closed(), "object '{}': {} is not a closed surface; a free mesh needs one (its volume gives its mass)",
          spec.name, spec.mesh_path);
  mesh_properties(file->vertices(), file->triangles(), 1.0, centre);
  return std::make_shared<TriangleMesh>(RowMatrixX3d(file->vertices().rowwise() - centre.transpose()),
                                        file->triangles());
}

}  // namespace

Pose free_start_pose(const ObjectSpec& spec) {
  Pose pose = spec_pose(spec.position, spec.rotation);
  if (spec.shape == ShapeKind::mesh) {  // `position` places the file's origin; the body's frame is its centre
    Eigen::Vector3d centre;
    centred_mesh(spec, centre);
    pose.translation += pose.rotation * centre;
  }
  return pose;
}

std::shared_ptr<Obstacle> make_shape(const ObjectSpec& spec) {
  switch (spec.shape) {
    case ShapeKind::plane:
      return std::make_shared<HalfSpace>(spec.normal, 0.0, 2.0);
    case ShapeKind::sphere:
      return std::make_shared<Sphere>(spec.radius);
    case ShapeKind::box:
      return std::make_shared<Box>(spec.half_extents);
    case ShapeKind::capsule:
      return std::make_shared<Capsule>(spec.radius, 0.5 * spec.length);
    case ShapeKind::mesh: {
      if (spec.motion == ObjectMotionKind::free) {
        Eigen::Vector3d centre;
        return centred_mesh(spec, centre);
      }
      std::unique_ptr<TriangleMesh> mesh = TriangleMesh::load(spec.mesh_path, spec.scale);
      return std::shared_ptr<Obstacle>(std::move(mesh));
    }
  }
  throw_error("object '{}': unknown shape", spec.name);
}

SceneObject make_object(const ObjectSpec& spec) {
  SceneObject object;
  object.spec = spec;
  object.world_shape = make_shape(spec);
  // A plane's normal is given in the world: its rotation would turn it.
  const Pose start =
      spec.motion == ObjectMotionKind::free
          ? free_start_pose(spec)
          : spec_pose(spec.position, spec.shape == ShapeKind::plane ? Eigen::Vector3d::Zero() : spec.rotation);
  switch (spec.motion) {
    case ObjectMotionKind::fixed:
      object.motion = std::make_shared<FixedMotion>(start);
      break;
    case ObjectMotionKind::prescribed: {
      std::vector<Keyframe> keys;
      for (const SceneKeyframe& k : spec.keyframes) {
        const Pose p = spec_pose(k.position, k.rotation);
        keys.push_back({k.t, p.translation, Eigen::Quaterniond(p.rotation)});
      }
      object.motion = std::make_shared<KeyframeMotion>(
          std::move(keys), spec.smooth ? KeyframeInterpolation::catmull_rom : KeyframeInterpolation::linear);
      break;
    }
    case ObjectMotionKind::free:
      // Held at its start until FreeObjects (free_objects.hpp) replaces it with the solved rigid motion.
      object.motion = std::make_shared<FixedMotion>(start);
      break;
  }
  object.world_shape->set_pose(object.motion->pose(0.0));
  return object;
}

Surface merged_object_surfaces(const std::vector<SceneObject>& objects, Eigen::MatrixXd& ids) {
  std::vector<Surface> surfaces;
  Eigen::Index vertices = 0, triangles = 0;
  for (const SceneObject& o : objects) {
    surfaces.push_back(o.world_shape->surface(32));
    vertices += surfaces.back().vertices.rows();
    triangles += surfaces.back().triangles.rows();
  }
  Surface merged;
  merged.vertices.resize(vertices, 3);
  merged.triangles.resize(triangles, 3);
  ids.resize(triangles, 1);
  Eigen::Index v0 = 0, f0 = 0;
  for (std::size_t j = 0; j < surfaces.size(); ++j) {
    merged.vertices.middleRows(v0, surfaces[j].vertices.rows()) = surfaces[j].vertices;
    merged.triangles.middleRows(f0, surfaces[j].triangles.rows()) =
        surfaces[j].triangles.array() + static_cast<int>(v0);
    ids.middleRows(f0, surfaces[j].triangles.rows()).setConstant(static_cast<double>(j));
    v0 += surfaces[j].vertices.rows();
    f0 += surfaces[j].triangles.rows();
  }
  return merged;
}

}  // namespace sflsh::scene::detail
