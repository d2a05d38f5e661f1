#include <sflsh/core/error.hpp>
#include <sflsh/model/skinned_trajectory.hpp>

#include <cmath>

namespace sflsh::model {

namespace {

/// Cubic Hermite basis on u ∈ [0, 1] and its derivative (d/du).
struct Hermite {
  double h00, h10, h01, h11;
  double d00, d10, d01, d11;
  explicit Hermite(double u) {
    const double u2 = u * u, u3 = u2 * u;
    h00 = 2 * u3 - 3 * u2 + 1;
    h10 = u3 - 2 * u2 + u;
    h01 = -2 * u3 + 3 * u2;
    h11 = u3 - u2;
    d00 = 6 * u2 - 6 * u;
    d10 = 3 * u2 - 4 * u + 1;
    d01 = -6 * u2 + 6 * u;
    d11 = 3 * u2 - 2 * u;
  }
};

/// Catmull–Rom interpolation of a sampled curve P_f (uniform spacing 1/fps), C¹ in t: tangents are central
/// differences inside and one-sided at the ends. Exact at the samples.
template <typename T>
void hermite(const std::vector<T>& samples, std::size_t f, double u, double fps, bool clamped, T& value, T* rate) {
  const std::size_t n = samples.size();
  if (n == 1 || clamped) {
    value = samples[f];
    if (rate) rate->setZero();
    return;
  }
  auto tangent = [&](std::size_t k) -> T {  // dP/d(frame) at sample k
    if (k == 0) return samples[1] - samples[0];
    if (k == n - 1) return samples[n - 1] - samples[n - 2];
    return 0.5 * (samples[k + 1] - samples[k - 1]);
  };
  const T m0 = tangent(f), m1 = tangent(f + 1);
  const Hermite b(u);
  value = b.h00 * samples[f] + b.h10 * m0 + b.h01 * samples[f + 1] + b.h11 * m1;
  if (rate) *rate = fps * (b.d00 * samples[f] + b.d10 * m0 + b.d01 * samples[f + 1] + b.d11 * m1);
}

}  // namespace

MotionCurve::MotionCurve(const body::BodyModel& model, const body::Betas& beta, const body::Motion& motion)
    : fps_(motion.fps) {
  motion.validate();
  const body::Poser poser(model, beta);
  const std::size_t frames = motion.num_frames();
  for (auto& joint : transforms_) joint.resize(frames);
  if (model.has_pose_correctives()) features_.resize(frames);
  for (std::size_t f = 0; f < frames; ++f) {
    const body::Kinematics kin = body::forward_kinematics(model, poser.joints_rest(), motion.poses[f], motion.trans[f]);
    for (int k = 0; k < body::kNumJoints; ++k) {
      const auto sk = static_cast<std::size_t>(k);
      transforms_[sk][f] = motion.world_from_body * kin.skinning[sk].matrix().topRows<3>();
    }
    if (model.has_pose_correctives()) features_[f] = body::pose_features(motion.poses[f]);
  }
}

void MotionCurve::locate(double t, std::size_t& f, double& u, bool& clamped) const {
  const double s = t * fps_;
  const auto last = static_cast<double>(num_frames() - 1);
  clamped = false;
  if (!(s > 0.0)) {  // also NaN: the start
    f = 0;
    u = 0.0;
    clamped = s < 0.0 || num_frames() == 1;
    return;
  }
  if (s >= last) {
    f = num_frames() - 1;
    u = 0.0;
    clamped = true;
    return;
  }
  double whole = std::floor(s);
  u = s - whole;
  if (u > 1.0 - 1e-9) {  // a frame time that rounding put just below its frame
    whole += 1.0;
    u = 0.0;
  } else if (u < 1e-9) {
    u = 0.0;
  }
  f = static_cast<std::size_t>(whole);
  if (f >= num_frames() - 1) {  // the last frame itself: evaluate the last interval at u = 1
    f = num_frames() - 2;
    u = 1.0;
  }
}

void MotionCurve::transforms(double t, JointTransforms& m, JointTransforms* rate) const {
  require(std::isfinite(t), "motion curve: time is not finite");
  std::size_t f;
  double u;
  bool clamped;
  locate(t, f, u, clamped);
  for (int k = 0; k < body::kNumJoints; ++k) {
    const auto sk = static_cast<std::size_t>(k);
    Matrix34d value, d;
    hermite(transforms_[sk], f, u, fps_, clamped, value, rate ? &d : nullptr);
    m[sk] = value;
    if (rate) (*rate)[sk] = d;
  }
}

void MotionCurve::features(double t, PoseFeatures& value, PoseFeatures* rate) const {
  if (features_.empty()) {
    value.setZero();
    if (rate) rate->setZero();
    return;
  }
  std::size_t f;
  double u;
  bool clamped;
  locate(t, f, u, clamped);
  hermite(features_, f, u, fps_, clamped, value, rate);
}

SkinnedTrajectory::SkinnedTrajectory(std::shared_ptr<const MotionCurve> curve,
                                     std::vector<std::vector<std::pair<int, double>>> weights,
                                     Eigen::MatrixXd pose_dirs)
    : curve_(std::move(curve)), weights_(std::move(weights)), pose_dirs_(std::move(pose_dirs)) {
  require(curve_ != nullptr, "skinned trajectory: no motion curve");
  require(
      pose_dirs_.size() == 0 || (pose_dirs_.rows() == 3 * num_nodes() && pose_dirs_.cols() == body::kNumPoseFeatures),
      "skinned trajectory: pose directions are {}×{}, expected {}×{}", pose_dirs_.rows(), pose_dirs_.cols(),
      3 * num_nodes(), body::kNumPoseFeatures);
}

// p_i = A_i (x_i + b_i) + c_i = A_i x_i + d_i with d_i = A_i b_i + c_i (docs/physics.md §5).
void SkinnedTrajectory::evaluate(double t, NodeFrame& frame, NodeFrame* rate) const {
  JointTransforms m, dm;
  curve_->transforms(t, m, rate ? &dm : nullptr);
  const int n = num_nodes();
  frame.A.resize(static_cast<std::size_t>(n));
  frame.d.resize(n, 3);
  if (rate) {
    rate->A.resize(static_cast<std::size_t>(n));
    rate->d.resize(n, 3);
  }
  Eigen::VectorXd b, db;
  if (pose_dirs_.size() > 0) {
    PoseFeatures f, df;
    curve_->features(t, f, rate ? &df : nullptr);
    b = pose_dirs_ * f;
    if (rate) db = pose_dirs_ * df;
  }
  for (int i = 0; i < n; ++i) {
    const auto si = static_cast<std::size_t>(i);
    Matrix34d blend = Matrix34d::Zero(), dblend = Matrix34d::Zero();
    for (const auto& [joint, w] : weights_[si]) {
      blend += w * m[static_cast<std::size_t>(joint)];
      if (rate) dblend += w * dm[static_cast<std::size_t>(joint)];
    }
    const Eigen::Matrix3d A = blend.leftCols<3>();
    Eigen::Vector3d d = blend.col(3);
    if (b.size() > 0) d += A * b.segment<3>(3 * i);
    frame.A[si] = A;
    frame.d.row(i) = d.transpose();
    if (rate) {
      Eigen::Vector3d dd = dblend.col(3);
      if (b.size() > 0) dd += dblend.leftCols<3>() * b.segment<3>(3 * i) + A * db.segment<3>(3 * i);
      rate->A[si] = dblend.leftCols<3>();
      rate->d.row(i) = dd.transpose();
    }
  }
}

void SkinnedTrajectory::evaluate_nodes(double t, const std::vector<int>& nodes, NodeFrame& frame) const {
  JointTransforms m;
  curve_->transforms(t, m);
  frame.A.resize(nodes.size());
  frame.d.resize(static_cast<Eigen::Index>(nodes.size()), 3);
  Eigen::VectorXd b;
  if (pose_dirs_.size() > 0) {
    PoseFeatures f;
    curve_->features(t, f);
    b = pose_dirs_ * f;
  }
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const auto si = static_cast<std::size_t>(nodes[k]);
    Matrix34d blend = Matrix34d::Zero();
    for (const auto& [joint, w] : weights_[si]) blend += w * m[static_cast<std::size_t>(joint)];
    frame.A[k] = blend.leftCols<3>();
    Eigen::Vector3d d = blend.col(3);
    if (b.size() > 0) d += frame.A[k] * b.segment<3>(3 * nodes[k]);
    frame.d.row(static_cast<Eigen::Index>(k)) = d.transpose();
  }
}

std::vector<std::vector<std::pair<int, double>>> sparse_blend_weights(const Eigen::MatrixXd& dense, double drop) {
  std::vector<std::vector<std::pair<int, double>>> out(static_cast<std::size_t>(dense.rows()));
  for (Eigen::Index i = 0; i < dense.rows(); ++i) {
    auto& row = out[static_cast<std::size_t>(i)];
    double sum = 0.0;
    for (Eigen::Index k = 0; k < dense.cols(); ++k) {
      const double w = dense(i, k);
      require(std::isfinite(w), "blend weights: node {} has a non-finite weight", i);
      if (w > drop) {
        row.emplace_back(static_cast<int>(k), w);
        sum += w;
      }
    }
    if (row.empty()) {  // every weight tiny: keep the largest
      Eigen::Index best;
      const double w = dense.row(i).maxCoeff(&best);
      require(w > 0.0, "blend weights: node {} has no positive weight", i);
      row.emplace_back(static_cast<int>(best), w);
      sum = w;
    }
    for (auto& entry : row) entry.second /= sum;
  }
  return out;
}

}  // namespace sflsh::model
