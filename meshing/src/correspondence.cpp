// Surface-to-skeleton correspondence and the layer geometry of a shape (docs/physics.md §1.4).
#include <sflsh/core/error.hpp>
#include <sflsh/meshing/correspondence.hpp>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <set>

namespace sflsh::meshing {
namespace {

struct Bone {
  const char* joint;
  const char* child;
};

// The bone segment that carries the flesh of each region joint (joint → designated child).
constexpr Bone kBones[] = {
    {"pelvis", "spine1"},
    {"spine1", "spine2"},
    {"spine2", "spine3"},
    {"spine3", "neck"},
    {"left_collar", "left_shoulder"},
    {"right_collar", "right_shoulder"},
    {"left_shoulder", "left_elbow"},
    {"right_shoulder", "right_elbow"},
    {"left_hip", "left_knee"},
    {"right_hip", "right_knee"},
};

// Closest point parameter t ∈ [0, 1] on segment a → b.
double segment_parameter(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d d = b - a;
  const double len2 = d.squaredNorm();
  if (len2 <= 0.0) return 0.0;
  return std::clamp((p - a).dot(d) / len2, 0.0, 1.0);
}

}  // namespace

RowMatrixX3d SkeletonCorrespondence::points(const body::JointPositions& joints) const { return joint_weights * joints; }

SkeletonCorrespondence skeleton_correspondence(const body::BodyModel& model, const Region& region,
                                               int smoothing_sweeps) {
  const int count = region.num_vertices();
  const body::JointPositions joints = body::regress_joints(model, model.v_template);
  Eigen::MatrixXd weights = Eigen::MatrixXd::Zero(count, body::kNumJoints);
  for (int i = 0; i < count; ++i) {
    const int v = region.vertices[i];
    const Eigen::Vector3d s = model.v_template.row(v).transpose();
    double total = 0.0;
    int closest_bone = -1;
    double closest_distance = 0.0;
    Eigen::Matrix<double, 1, body::kNumJoints> row = Eigen::Matrix<double, 1, body::kNumJoints>::Zero();
    for (int b = 0; b < static_cast<int>(std::size(kBones)); ++b) {
      const int j = body::joint_index(kBones[b].joint), child = body::joint_index(kBones[b].child);
      const Eigen::Vector3d a = joints.row(j).transpose(), e = joints.row(child).transpose();
      const double t = segment_parameter(s, a, e);
      const double distance = (s - (a + t * (e - a))).norm();
      if (closest_bone < 0 || distance < closest_distance) {
        closest_bone = b;
        closest_distance = distance;
      }
      const double w = model.weights(v, j);
      if (w <= 0.0) continue;
      row(j) += w * (1.0 - t);
      row(child) += w * t;
      total += w;
    }
    if (total < 1e-3) {  // no region joint influences this vertex: use the closest bone alone
      const int j = body::joint_index(kBones[closest_bone].joint),
                child = body::joint_index(kBones[closest_bone].child);
      const double t = segment_parameter(s, joints.row(j).transpose(), joints.row(child).transpose());
      row.setZero();
      row(j) = 1.0 - t;
      row(child) = t;
      total = 1.0;
    }
    weights.row(i) = row / total;
  }

  // Smoothing across bones: Jacobi sweeps of the uniform Laplacian keep rows affine (Σ = 1).
  std::vector<std::set<int>> ring(count);
  for (Eigen::Index f = 0; f < region.faces.rows(); ++f)
    for (int e = 0; e < 3; ++e) {
      ring[region.faces(f, e)].insert(region.faces(f, (e + 1) % 3));
      ring[region.faces(f, (e + 1) % 3)].insert(region.faces(f, e));
    }
  for (int sweep = 0; sweep < smoothing_sweeps; ++sweep) {
    Eigen::MatrixXd next = weights;
    for (int i = 0; i < count; ++i) {
      if (ring[i].empty()) continue;
      Eigen::RowVectorXd mean = Eigen::RowVectorXd::Zero(body::kNumJoints);
      for (int k : ring[i]) mean += weights.row(k);
      next.row(i) = 0.5 * weights.row(i) + 0.5 * mean / static_cast<double>(ring[i].size());
    }
    weights = next;
  }

  SkeletonCorrespondence correspondence;
  correspondence.joint_weights = weights.sparseView(1e-12);
  const RowMatrixX3d c = correspondence.points(joints);
  for (int i = 0; i < count; ++i) {
    const double distance = (c.row(i) - model.v_template.row(region.vertices[i])).norm();
    require(distance > 2e-3,
            "skeleton correspondence: skin vertex {} ({}) is {:.4f} m from its skeleton point; expected > 0.002 m",
            region.vertices[i], part_name(region.part[i]), distance);
  }
  return correspondence;
}

Eigen::Vector3d LayerGeometry::position(const SurfaceAnchor& anchor) const {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) {
    const double w = anchor.weight(k);
    if (w == 0.0) continue;
    const int v = anchor.vertex[k];
    const Eigen::Vector3d s = skin.row(v).transpose();
    p += w * (s + anchor.depth * thickness(v) * (skeleton.row(v).transpose() - s));  // docs/physics.md §1.4
  }
  return p;
}

Eigen::VectorXd LayerGeometry::max_thickness() const { return (skeleton - skin).rowwise().norm(); }

void validate_thickness(const Eigen::VectorXd& thickness, int region_vertices, const std::string& what) {
  require(thickness.size() == region_vertices, "{}: {} values, expected one per region vertex ({})", what,
          thickness.size(), region_vertices);
  for (Eigen::Index i = 0; i < thickness.size(); ++i)
    require(std::isfinite(thickness(i)) && thickness(i) > 0.0 && thickness(i) < 1.0,
            "{}: thickness fraction h = {} at region vertex {}; expected 0 < h < 1", what, thickness(i), i);
}

LayerGeometry layer_geometry(const body::BodyModel& model, const Region& region,
                             const SkeletonCorrespondence& correspondence, const body::Betas& beta,
                             const Eigen::VectorXd& thickness) {
  validate_thickness(thickness, region.num_vertices(), "thickness");
  const body::RowMatrixX3d shaped = body::shaped_template(model, beta);
  LayerGeometry geometry;
  geometry.skin.resize(region.num_vertices(), 3);
  for (int i = 0; i < region.num_vertices(); ++i) geometry.skin.row(i) = shaped.row(region.vertices[i]);
  geometry.skeleton = correspondence.points(body::regress_joints(model, shaped));
  geometry.thickness = thickness;
  return geometry;
}

}  // namespace sflsh::meshing
