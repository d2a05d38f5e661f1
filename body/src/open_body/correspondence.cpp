#include "correspondence.hpp"

#include <Eigen/Geometry>

#include <span>

namespace sflsh::body::detail {
namespace {

constexpr int kRelaxSteps = 10;
constexpr double kRelaxRate = 0.5;
constexpr double kMaxSlide = 0.04;  // bound of a vertex's tangential travel during relaxation [m]

/// Frame with first axis along `along`, the third as close to +Z as possible.
Eigen::Matrix3d axes_along(const Eigen::Vector3d& along) {
  const Eigen::Vector3d u = along.normalized();
  Eigen::Vector3d w = Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitZ().dot(u) * u;
  if (w.norm() < 1e-6) w = Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitX().dot(u) * u;
  w.normalize();
  Eigen::Matrix3d axes;
  axes.col(0) = u;
  axes.col(1) = w.cross(u);
  axes.col(2) = w;
  return axes;
}

BoneFrame limb(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double girth) {
  return {from, axes_along(to - from), Eigen::Vector3d((to - from).norm(), girth, girth)};
}

/// Trunk bone: identity axes, extents (half-width, segment height, half-depth) at mid-segment.
BoneFrame trunk(const Skeleton& sk, const Eigen::Vector3d& origin, double y_low, double y_high) {
  const TrunkSection s = sk.trunk_at(0.5 * (y_low + y_high));
  return {origin, Eigen::Matrix3d::Identity(), Eigen::Vector3d(s.a, y_high - y_low, s.b)};
}

}  // namespace

std::array<BoneFrame, kNumJoints> bone_frames(const Skeleton& sk) {
  const auto& j = sk.joints;
  const double e = sk.scales.extremities;
  std::array<BoneFrame, kNumJoints> f;
  f[0] = trunk(sk, j[0], sk.trunk.front().y, j[3].y());
  f[3] = trunk(sk, j[3], j[3].y(), j[6].y());
  f[6] = trunk(sk, j[6], j[6].y(), j[9].y());
  f[9] = trunk(sk, j[9], j[9].y(), sk.trunk.back().y);
  f[12] = limb(j[12], j[15], sk.neck_base);
  f[15] = {j[15], Eigen::Matrix3d::Identity(), Eigen::Vector3d::Constant(1.0 + 0.5 * (e - 1.0))};
  for (int side = 0; side < 2; ++side) {
    const auto at = [side](int left) { return side == 0 ? left : mirror_joint(left); };
    f[at(1)] = limb(j[at(1)], j[at(4)], 0.5 * (sk.thigh_top + sk.thigh_knee));
    f[at(4)] = limb(j[at(4)], j[at(7)], 0.5 * (sk.shank_knee + sk.shank_ankle));
    f[at(7)] = limb(j[at(7)], j[at(10)], e);
    f[at(10)] = {j[at(10)], f[at(7)].axes, Eigen::Vector3d::Constant(e)};
    f[at(13)] = limb(j[at(13)], j[at(16)], sk.scales.girth);
    f[at(16)] = limb(j[at(16)], j[at(18)], 0.5 * (sk.upper_arm_top + sk.upper_arm_elbow));
    f[at(18)] = limb(j[at(18)], j[at(20)], 0.5 * (sk.forearm_elbow + sk.forearm_wrist));
    f[at(20)] = limb(j[at(20)], j[at(22)], e);
    f[at(22)] = {j[at(22)], f[at(20)].axes, Eigen::Vector3d::Constant(e)};
  }
  return f;
}

RowMatrixX3d carry_template(const RowMatrixX3d& template_vertices, const Eigen::MatrixXd& weights,
                            const VertexAdjacency& adjacency, const Skeleton& template_skeleton,
                            const Skeleton& sample_skeleton, const BodyField& sample_field) {
  const auto from = bone_frames(template_skeleton);
  const auto to = bone_frames(sample_skeleton);
  std::array<Eigen::Matrix3d, kNumJoints> linear;
  std::array<Eigen::Vector3d, kNumJoints> shift;
  for (std::size_t k = 0; k < from.size(); ++k) {
    linear[k] = to[k].axes * to[k].extents.cwiseQuotient(from[k].extents).asDiagonal() * from[k].axes.transpose();
    shift[k] = to[k].origin - linear[k] * from[k].origin;
  }
  const Eigen::Index n = template_vertices.rows();
  RowMatrixX3d warped(n, 3), out(n, 3);
  // Each vertex evaluates only the primitives that can reach it while it moves (projection moves it by
  // about |f|, relaxation by at most a few centimetres).
  std::vector<int> active_offsets(static_cast<std::size_t>(n) + 1, 0), active;
  active.reserve(static_cast<std::size_t>(12 * n));
  const auto field_at = [&](Eigen::Index v) {
    const std::span<const int> list(active.data() + active_offsets[static_cast<std::size_t>(v)],
                                    active.data() + active_offsets[static_cast<std::size_t>(v) + 1]);
    return [&sample_field, list](const Eigen::Vector3d& x) { return sample_field.evaluate(x, list); };
  };
  for (Eigen::Index v = 0; v < n; ++v) {
    const Eigen::Vector3d x = template_vertices.row(v).transpose();
    Eigen::Vector3d y = Eigen::Vector3d::Zero();
    for (int k = 0; k < kNumJoints; ++k) {
      const double w = weights(v, k);
      if (w != 0.0) y += w * (linear[static_cast<std::size_t>(k)] * x + shift[static_cast<std::size_t>(k)]);
    }
    warped.row(v) = y.transpose();
    sample_field.active_near(y, std::abs(sample_field.value(y)) + kMaxSlide, active);
    active_offsets[static_cast<std::size_t>(v) + 1] = static_cast<int>(active.size());
  }
  for (Eigen::Index v = 0; v < n; ++v) out.row(v) = newton_project(field_at(v), warped.row(v).transpose()).transpose();

  // Tangential relaxation: each vertex slides along the surface so that its offset from the mean of its
  // neighbours (its uniform-Laplacian coordinate) approaches the warped template's. This undoes the
  // bunching that projection causes in concave creases (armpits, crotch) where the sample's surface
  // is tighter than the template's.
  const auto laplacian = [&adjacency](const RowMatrixX3d& x, Eigen::Index v) {
    const int begin = adjacency.offsets[static_cast<std::size_t>(v)];
    const int end = adjacency.offsets[static_cast<std::size_t>(v) + 1];
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int k = begin; k < end; ++k) mean += x.row(adjacency.indices[static_cast<std::size_t>(k)]).transpose();
    return Eigen::Vector3d(mean / static_cast<double>(end - begin) - x.row(v).transpose());
  };
  // One field evaluation per vertex and step: its gradient gives the tangent plane, and a Newton
  // correction with the same value keeps the vertex on f = 0; a full projection closes.
  RowMatrixX3d next(n, 3);
  for (int step = 0; step < kRelaxSteps; ++step) {
    for (Eigen::Index v = 0; v < n; ++v) {
      const Eigen::Vector3d x = out.row(v).transpose();
      const FieldSample f = field_at(v)(x);
      const double g2 = f.gradient.squaredNorm();
      if (g2 < 1e-12) {
        next.row(v) = out.row(v);
        continue;
      }
      Eigen::Vector3d delta = kRelaxRate * (laplacian(out, v) - laplacian(warped, v));
      delta -= delta.dot(f.gradient) / g2 * f.gradient;
      next.row(v) = (x + delta - f.value / g2 * f.gradient).transpose();
    }
    out.swap(next);
  }
  for (Eigen::Index v = 0; v < n; ++v) out.row(v) = newton_project(field_at(v), out.row(v).transpose()).transpose();
  return out;
}

}  // namespace sflsh::body::detail
