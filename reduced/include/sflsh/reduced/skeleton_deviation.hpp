#pragma once
// The tracking skeleton's deviation from its motion (docs/reduced.md "Tracking skeleton"): the root and, per tracked
// joint j, a rotation φ_j about the motion's posed joint centre c_j(t), blended over the layer like the skinning.
//   root:   D_0(p) = R(θ)(p − c_0) + c_0 + τ                      (c_0 the posed pelvis)
//   joint:  S_j(p) = R(φ_j)(p − c_j) + c_j,   D_j = D_parent(j) ∘ S_j  (parent: the nearest tracked ancestor, else
//   root) node:   y_i(p) = Σ_b ω_ib D_b(p),  ω_ib = Σ of the node's skinning weights w_ik over the joints k whose
//   nearest
//           tracked ancestor-or-self is b (the root when none is)
// applied to the motion-posed position p = z_i + A_i u_i(q). The coordinates r = (θ, τ, φ_1, …, φ_J) follow q in the
// solver's unknowns. Each D_b is affine in p, so its value and its first and second derivatives in r are 3×4 maps of
// [p; 1], composed from 4×4 factors per chain level. With no tracked joint this is the rigid root deviation.
#include <Eigen/Core>

#include <utility>
#include <vector>

namespace sflsh::reduced {

using Matrix34d = Eigen::Matrix<double, 3, 4>;
using JointBlend = std::vector<std::pair<int, double>>;  ///< (joint or bone, weight) pairs summing to 1

/// The deviation of one bone (the root or a tracked joint) at given coordinates: D_b(p) = map [p; 1], its
/// derivatives in the coordinates it depends on (the root's six, then three per tracked joint on its chain).
struct BoneDeviation {
  Matrix34d map = Matrix34d::Zero();
  std::vector<int> coordinates;   ///< indices into r
  std::vector<Matrix34d> first;   ///< ∂D_b/∂r_coordinates[k]
  std::vector<Matrix34d> second;  ///< ∂²D_b/∂r_k∂r_l, row-major n_b × n_b (only when asked for)
};

class SkeletonDeviation;

/// The deviation at coordinates r (x[offset .. offset + size)), per bone.
class DeviationFrame {
 public:
  Eigen::Index offset = 0;
  int size = 6;
  std::vector<BoneDeviation> bones;
  const SkeletonDeviation* skeleton = nullptr;

  /// Node `node`'s (a mesh node) deviated position y(p), its linear part L = ∂y/∂p.
  Eigen::Vector3d apply(int node, const Eigen::Vector3d& p) const { return apply_blend(blend(node), p); }
  Eigen::Matrix3d linear(int node) const { return linear_blend(blend(node)); }
  /// ∂y/∂r (3 × size).
  void jacobian(int node, const Eigen::Vector3d& p, Eigen::Matrix<double, 3, Eigen::Dynamic>& J) const;
  /// ∂L/∂r_k for every coordinate k (size entries; zero where the node does not depend on r_k).
  void linear_derivatives(int node, std::vector<Eigen::Matrix3d>& dL) const;
  /// block += scale Σ_c g_c ∂²y_c/∂r∂r (size × size).
  void add_second(int node, const Eigen::Vector3d& p, const Eigen::Vector3d& g, double scale,
                  Eigen::Ref<Eigen::MatrixXd> block) const;
  /// The same for any blend of bones (the body's surface vertices).
  Eigen::Vector3d apply_blend(const JointBlend& blend, const Eigen::Vector3d& p) const;
  Eigen::Matrix3d linear_blend(const JointBlend& blend) const;
  /// The affine map of a blend, [L | y(0)].
  Matrix34d map_blend(const JointBlend& blend) const;
  const JointBlend& blend(int node) const;
};

struct JointTrackingSetup {
  /// The parent of every joint of the skeleton (−1 for the root, parents before children).
  std::vector<int> parents;
  /// The tracked joints (indices into parents; never the root), ascending.
  std::vector<int> joints;
  /// Per mesh node, its skinning weights over the skeleton's joints.
  std::vector<JointBlend> node_weights;
};

/// The static part: which bone carries each joint, each bone's chain and every node's blend over the bones.
class SkeletonDeviation {
 public:
  /// The root alone (rigid deviation).
  SkeletonDeviation() = default;
  explicit SkeletonDeviation(const JointTrackingSetup& setup);

  int num_joints() const { return static_cast<int>(tracked_.size()); }
  int size() const { return 6 + 3 * num_joints(); }
  /// The tracked joints (skeleton indices) in the order of their coordinates.
  const std::vector<int>& tracked() const { return tracked_; }
  /// A node's blend over the bones (bone 0 is the root, bone 1 + j the tracked joint j).
  const JointBlend& node_blend(int node) const;
  /// The tracked joints (indices into tracked()) whose rotation moves bone b, from the outermost.
  const std::vector<int>& chain(int bone) const { return chains_.at(static_cast<std::size_t>(bone)); }
  /// Skinning weights over the skeleton's joints → a blend over the bones.
  JointBlend bone_blend(const JointBlend& joint_weights) const;

  /// The frame at r = x[offset .. offset + size()): pivot c_0 and the tracked joints' centres c_j (one per tracked
  /// joint) in the problem's posed frame [m]; `second`: also the second derivatives.
  DeviationFrame frame(const Eigen::VectorXd& x, Eigen::Index offset, const Eigen::Vector3d& pivot,
                       const std::vector<Eigen::Vector3d>& centres, bool second) const;

 private:
  std::vector<int> tracked_;
  std::vector<int> bone_of_joint_;  ///< per skeleton joint: its bone
  std::vector<std::vector<int>> chains_{
      std::vector<int>{}};               ///< per bone: its tracked joints (into tracked_), outermost first
  std::vector<JointBlend> node_blends_;  ///< per mesh node (empty: every node on the root)
  JointBlend root_blend_{{0, 1.0}};
};

}  // namespace sflsh::reduced
