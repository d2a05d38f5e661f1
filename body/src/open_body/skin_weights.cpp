#include "skin_weights.hpp"

#include "mesh_topology.hpp"

#include <algorithm>
#include <array>
#include <numeric>

namespace sflsh::body::detail {
namespace {

constexpr int kDiffusionSteps = 24;
constexpr double kDiffusionAlpha = 0.5;
constexpr int kMaxBones = 4;
constexpr double kMinWeight = 0.01;
constexpr double kSideMargin = 0.02;  // [m]

using BoneMask = std::array<bool, kNumJoints>;
using WeightRow = Eigen::Ref<Eigen::RowVectorXd, 0, Eigen::InnerStride<>>;

/// Side of a bone: +1 left limb/collar, −1 right, 0 central.
int bone_side(int bone) {
  if (bone == 0 || bone == 3 || bone == 6 || bone == 9 || bone == 12 || bone == 15) return 0;
  return mirror_joint(bone) > bone ? 1 : -1;  // left joints have the smaller index of each pair
}

/// Tree distance between every pair of joints of SMPL's kinematic tree.
std::array<std::array<int, kNumJoints>, kNumJoints> tree_distances() {
  std::array<std::array<int, kNumJoints>, kNumJoints> dist{};
  for (int a = 0; a < kNumJoints; ++a) {
    std::array<int, kNumJoints> depth_a{};
    depth_a.fill(-1);
    for (int x = a, d = 0; x >= 0; x = kJointParents[static_cast<std::size_t>(x)], ++d)
      depth_a[static_cast<std::size_t>(x)] = d;
    for (int b = 0; b < kNumJoints; ++b) {
      int d = 0, x = b;
      while (depth_a[static_cast<std::size_t>(x)] < 0) {
        x = kJointParents[static_cast<std::size_t>(x)];
        ++d;
      }
      dist[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)] = d + depth_a[static_cast<std::size_t>(x)];
    }
  }
  return dist;
}

/// Bones a vertex whose dominant bone is `primary` may receive.
std::array<BoneMask, kNumJoints> allowed_bones() {
  const auto dist = tree_distances();
  std::array<BoneMask, kNumJoints> allowed{};
  for (int p = 0; p < kNumJoints; ++p)
    for (int b = 0; b < kNumJoints; ++b) {
      const bool near = dist[static_cast<std::size_t>(p)][static_cast<std::size_t>(b)] <= 2;
      const bool same_side = bone_side(p) == 0 || bone_side(b) == 0 || bone_side(p) == bone_side(b);
      allowed[static_cast<std::size_t>(p)][static_cast<std::size_t>(b)] = near && same_side;
    }
  return allowed;
}

double smoothstep(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

/// Split of a trunk point between pelvis, spine1, spine2, spine3 (piecewise-linear in height between
/// the middles of their segments) and, at the top of the chest and back, the collar of its side
/// (ramping in from spine3 to the collar joints' height and from half to one and a half times the
/// collars' lateral offset).
void add_trunk_share(const Skeleton& sk, const Eigen::Vector3d& p, double share, WeightRow row) {
  const auto& j = sk.joints;
  const double collar = smoothstep((p.y() - j[9].y()) / (j[13].y() - j[9].y())) *
                        smoothstep((std::abs(p.x()) - 0.5 * j[13].x()) / j[13].x());
  row(p.x() >= 0.0 ? 13 : 14) += collar * share;
  share *= 1.0 - collar;
  const std::array<int, 4> bones = {0, 3, 6, 9};
  const std::array<double, 4> centers = {j[0].y(), 0.5 * (j[3].y() + j[6].y()), 0.5 * (j[6].y() + j[9].y()),
                                         0.5 * (j[9].y() + j[12].y())};
  const double y = p.y();
  if (y <= centers.front()) {
    row(bones.front()) += share;
    return;
  }
  for (std::size_t k = 0; k + 1 < centers.size(); ++k)
    if (y <= centers[k + 1]) {
      const double t = (y - centers[k]) / (centers[k + 1] - centers[k]);
      row(bones[k]) += (1.0 - t) * share;
      row(bones[k + 1]) += t * share;
      return;
    }
  row(bones.back()) += share;
}

/// Zeroes the bones outside `mask` and the limbs of the other side (beyond kSideMargin of the
/// mid-plane), then renormalises.
void apply_mask(WeightRow row, const BoneMask& mask, double x) {
  for (int b = 0; b < kNumJoints; ++b) {
    const int side = bone_side(b);
    if (!mask[static_cast<std::size_t>(b)] || side * x < -kSideMargin) row(b) = 0.0;
  }
  const double sum = row.sum();
  if (sum > 0.0) row /= sum;
}

}  // namespace

Eigen::MatrixXd skinning_weights(const RowMatrixX3d& vertices, const RowMatrixX3i& faces,
                                 const std::vector<int>& mirror, const BodyField& field, const Skeleton& skeleton) {
  const Eigen::Index n = vertices.rows();
  const auto& prims = field.primitives();
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(n, kNumJoints);
  for (Eigen::Index v = 0; v < n; ++v) {
    const Eigen::Vector3d p = vertices.row(v).transpose();
    const Eigen::VectorXd share = field.memberships(p);
    for (std::size_t i = 0; i < prims.size(); ++i) {
      const double s = share(static_cast<Eigen::Index>(i));
      if (s <= 0.0) continue;
      if (prims[i].bone == kTrunkBone)
        add_trunk_share(skeleton, p, s, w.row(v));
      else
        w(v, prims[i].bone) += s;
    }
  }

  // Each vertex keeps the mask of its dominant bone before diffusion.
  const auto allowed = allowed_bones();
  std::vector<const BoneMask*> mask(static_cast<std::size_t>(n));
  for (Eigen::Index v = 0; v < n; ++v) {
    Eigen::Index primary = 0;
    w.row(v).maxCoeff(&primary);
    mask[static_cast<std::size_t>(v)] = &allowed[static_cast<std::size_t>(primary)];
  }
  const VertexAdjacency adjacency = vertex_adjacency(n, faces);
  for (int step = 0; step < kDiffusionSteps; ++step) {
    w = laplacian_smooth_step(adjacency, w, kDiffusionAlpha);
    for (Eigen::Index v = 0; v < n; ++v) apply_mask(w.row(v), *mask[static_cast<std::size_t>(v)], vertices(v, 0));
  }

  // Mirror symmetry (the diffusion itself is symmetric only up to the meshes' vertex order).
  Eigen::MatrixXd mirrored(n, kNumJoints);
  for (Eigen::Index v = 0; v < n; ++v)
    for (int k = 0; k < kNumJoints; ++k) mirrored(mirror[static_cast<std::size_t>(v)], mirror_joint(k)) = w(v, k);
  w = 0.5 * (w + mirrored);

  // Keep the kMaxBones largest weights of each row; a tie across the cut drops all tied bones, so that
  // mid-plane vertices (whose left and right weights are equal) stay symmetric.
  for (Eigen::Index v = 0; v < n; ++v) {
    std::array<int, kNumJoints> order;
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(),
              [&](int a, int b) { return w(v, a) > w(v, b) || (w(v, a) == w(v, b) && a < b); });
    const double cut = w(v, order[kMaxBones]);
    Eigen::RowVectorXd kept = Eigen::RowVectorXd::Zero(kNumJoints);
    for (int k = 0; k < kMaxBones; ++k) {
      const int b = order[static_cast<std::size_t>(k)];
      if (w(v, b) >= kMinWeight && w(v, b) > cut) kept(b) = w(v, b);
    }
    w.row(v) = kept / kept.sum();
  }
  return w;
}

}  // namespace sflsh::body::detail
