// Rigidity weights of body vertices from their distance to the bones (see rigidity.hpp).
#include <sflsh/core/error.hpp>
#include <sflsh/validate/rigidity.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace sflsh::validate {

Eigen::VectorXd bone_distance(const body::BodyModel& model, const RowMatrixX3d& shaped,
                              const body::JointPositions& joints) {
  Eigen::VectorXd distance = Eigen::VectorXd::Constant(shaped.rows(), std::numeric_limits<double>::infinity());
  for (int k = 1; k < body::kNumJoints; ++k) {
    const int parent = model.parents[static_cast<std::size_t>(k)];
    if (parent < 0) continue;
    const Eigen::Vector3d a = joints.row(parent).transpose();
    const Eigen::Vector3d b = joints.row(k).transpose();
    const Eigen::Vector3d ab = b - a;
    const double length2 = ab.squaredNorm();
    for (Eigen::Index i = 0; i < shaped.rows(); ++i) {
      const Eigen::Vector3d p = shaped.row(i).transpose();
      // Closest point of the segment: a + s (b − a), s = clamp((p − a)·(b − a) / |b − a|², 0, 1).
      const double s = length2 > 0.0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
      distance[i] = std::min(distance[i], (p - a - s * ab).norm());
    }
  }
  return distance;
}

Eigen::VectorXd rigidity_weights(const body::BodyModel& model, const std::vector<int>& soft_vertices,
                                 double reference_depth) {
  require(reference_depth > 0.0 && std::isfinite(reference_depth),
          "rigidity weights: the reference depth must be positive, got {}", reference_depth);
  const Eigen::Index n = model.num_vertices();
  const RowMatrixX3d shaped = body::shaped_template(model, body::Betas::Zero());
  const Eigen::VectorXd depth = bone_distance(model, shaped, body::regress_joints(model, shaped));
  Eigen::VectorXd weights = Eigen::VectorXd::Ones(n);
  for (int v : soft_vertices) {
    require(v >= 0 && v < n, "rigidity weights: soft-region vertex {} outside the body's {} vertices", v, n);
    weights[v] = std::pow(reference_depth / std::max(depth[v], reference_depth), 4);  // (D_0 / D_i)⁴, ≤ 1
  }
  return weights;
}

}  // namespace sflsh::validate
