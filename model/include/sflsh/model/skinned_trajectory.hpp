#pragma once
// The node maps of a body layer along a motion (docs/physics.md §5): p_i(t) = A_i(t)(x_i + b_i(t)) + c_i(t) with
// [A_i | c_i] = Σ_k w_ik M_k(t) the blended skinning transforms (M_k = world_from_body · G'_k) and b_i the
// pose correctives carried into the volume, fading to zero at the bones. The motion's frames are joined by
// C¹ cubic Hermite (Catmull–Rom) curves through the per-frame M_k and pose features, so that the adaptive
// reference integrator sees a smooth forcing and every frame time reproduces the frame exactly.
#include <sflsh/body/motion.hpp>
#include <sflsh/body/skinning.hpp>
#include <sflsh/model/problem.hpp>

#include <array>
#include <vector>

namespace sflsh::model {

using Matrix34d = Eigen::Matrix<double, 3, 4>;
using JointTransforms = std::array<Matrix34d, body::kNumJoints>;
using PoseFeatures = Eigen::Matrix<double, body::kNumPoseFeatures, 1>;

/// Per-frame skinning transforms and pose features of one subject along a motion, interpolated in time.
class MotionCurve {
 public:
  MotionCurve(const body::BodyModel& model, const body::Betas& beta, const body::Motion& motion);
  double fps() const { return fps_; }
  std::size_t num_frames() const { return transforms_[0].size(); }
  double duration() const { return static_cast<double>(num_frames() - 1) / fps_; }
  /// M_k(t) for all joints and, when `rate` is not null, dM_k/dt. Times outside [0, duration] clamp to
  /// the ends (with zero rate).
  void transforms(double t, JointTransforms& m, JointTransforms* rate = nullptr) const;
  /// Pose features f(t) (docs/physics.md §3.1) and optionally df/dt; only meaningful with pose correctives.
  void features(double t, PoseFeatures& f, PoseFeatures* rate = nullptr) const;

 private:
  /// Frame index f and local parameter u ∈ [0, 1) of time t (snapped to a frame within 1e-9 frames).
  void locate(double t, std::size_t& f, double& u, bool& clamped) const;

  double fps_;
  std::array<std::vector<Matrix34d>, body::kNumJoints> transforms_;  ///< per joint, per frame
  std::vector<PoseFeatures> features_;
};

/// Per-node skinning of a layer mesh along a motion.
class SkinnedTrajectory final : public NodeTrajectory {
 public:
  /// `weights`: per node, the (joint, weight) pairs of its blend (weights sum to 1). `pose_dirs`: per node
  /// 3 rows × 207 pose-corrective directions, already faded by depth (empty: no correctives).
  SkinnedTrajectory(std::shared_ptr<const MotionCurve> curve, std::vector<std::vector<std::pair<int, double>>> weights,
                    Eigen::MatrixXd pose_dirs);
  int num_nodes() const override { return static_cast<int>(weights_.size()); }
  void evaluate(double t, NodeFrame& frame, NodeFrame* rate = nullptr) const override;
  void evaluate_nodes(double t, const std::vector<int>& nodes, NodeFrame& frame) const override;
  const MotionCurve& curve() const { return *curve_; }
  const std::vector<std::pair<int, double>>& node_weights(int node) const {
    return weights_[static_cast<std::size_t>(node)];
  }

 private:
  std::shared_ptr<const MotionCurve> curve_;
  std::vector<std::vector<std::pair<int, double>>> weights_;
  Eigen::MatrixXd pose_dirs_;  ///< (3N) × 207, or empty
};

/// Sparse blend weights from a dense per-node table (N × 24): negatives clamped, entries below `drop`
/// removed, rows renormalized. Throws when a row has no positive weight.
std::vector<std::vector<std::pair<int, double>>> sparse_blend_weights(const Eigen::MatrixXd& dense, double drop = 1e-4);

}  // namespace sflsh::model
