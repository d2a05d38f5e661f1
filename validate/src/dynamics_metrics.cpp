// The dynamics metric of docs/physics.md §4 (SFLSH §3, §5): inverse skinning to the neutral pose, deviation from
// the SMPL baseline, per-vertex amplitude with the static offset removed, normal / tangential split.
#include <sflsh/core/error.hpp>
#include <sflsh/meshing/region.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/validate/dynamics_metrics.hpp>

#include <Eigen/LU>

#include <cmath>

namespace sflsh::validate {

std::vector<int> soft_region_vertices(const body::BodyModel& model, const std::vector<std::string>& region_names) {
  const std::vector<std::string> names = region_names.empty() ? meshing::default_region_names() : region_names;
  return meshing::select_region(model, names).vertices;
}

NeutralPullback::NeutralPullback(const body::BodyModel& model, const body::Betas& beta)
    : model_(model),
      shaped_(body::shaped_template(model, beta)),
      joints_(body::regress_joints(model, shaped_)),
      normals_(model::vertex_normals(shaped_, model.faces)) {}

RowMatrixX3d NeutralPullback::unposed(const body::Pose& theta, const Eigen::Vector3d& trans,
                                      const Eigen::Matrix3d& world_from_body, const RowMatrixX3d& posed) const {
  const Eigen::Index n = model_.num_vertices();
  require(posed.rows() == n, "neutral pull-back: {} posed vertices for a body of {} vertices", posed.rows(), n);
  const body::Kinematics kin = body::forward_kinematics(model_, joints_, theta, trans);  // step 1 (G'_k incl. trans)
  const std::vector<Eigen::Matrix<double, 3, 4>> blended = body::blend_transforms(model_, kin);
  RowMatrixX3d out(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Matrix<double, 3, 4>& a = blended[static_cast<std::size_t>(i)];
    const Eigen::Matrix3d linear = a.leftCols<3>();
    const double det = linear.determinant();
    require(std::abs(det) > 1e-6, "neutral pull-back: the blended transform of vertex {} is singular (det {:.3g})", i,
            det);
    const Eigen::Vector3d v_body = world_from_body.transpose() * posed.row(i).transpose();
    out.row(i) = (linear.inverse() * (v_body - a.col(3))).transpose();  // step 2: ū = A⁻¹ [v; 1]
  }
  return out;
}

RowMatrixX3d NeutralPullback::deviation(const body::Pose& theta, const Eigen::Vector3d& trans,
                                        const Eigen::Matrix3d& world_from_body, const RowMatrixX3d& posed) const {
  // Step 3: d = ū − (T̄ + B_S(β) + B_P(θ)).
  return unposed(theta, trans, world_from_body, posed) - shaped_ - body::pose_correctives(model_, theta);
}

namespace {

double mean_over(const Eigen::VectorXd& values, const std::vector<int>& vertices) {
  if (vertices.empty()) return 0.0;
  double sum = 0.0;
  for (int v : vertices) sum += values[v];
  return sum / static_cast<double>(vertices.size());
}

}  // namespace

double DynamicsResult::mean_sigma_soft() const { return mean_over(sigma, soft_vertices); }
double DynamicsResult::mean_sigma_all() const { return sigma.size() ? sigma.mean() : 0.0; }
double DynamicsResult::mean_sigma_normal_soft() const { return mean_over(sigma_normal, soft_vertices); }
double DynamicsResult::mean_sigma_tangent_soft() const { return mean_over(sigma_tangent, soft_vertices); }

std::vector<char> DynamicsResult::soft_mask() const {
  std::vector<char> mask(static_cast<std::size_t>(sigma.size()), 0);
  for (int v : soft_vertices) mask[static_cast<std::size_t>(v)] = 1;
  return mask;
}

DynamicsResult dynamics_metrics(const body::BodyModel& model, const body::Betas& beta, const body::Motion& motion,
                                const std::vector<RowMatrixX3d>& posed, const std::vector<int>& soft_vertices) {
  require(!posed.empty(), "dynamics metrics: no frames");
  require(motion.num_frames() == posed.size(), "dynamics metrics: {} frames of registrations but {} poses",
          posed.size(), motion.num_frames());
  require(motion.trans.size() == motion.poses.size(), "dynamics metrics: {} poses but {} root translations",
          motion.poses.size(), motion.trans.size());
  const Eigen::Index n = model.num_vertices();
  for (int v : soft_vertices)
    require(v >= 0 && v < n, "dynamics metrics: soft-region vertex {} outside the body's {} vertices", v, n);
  const NeutralPullback pullback(model, beta);
  model::DynamicsAmplitude amplitude(pullback.normals());  // steps 4–6
  for (std::size_t t = 0; t < posed.size(); ++t) {
    require(posed[t].rows() == n, "dynamics metrics: frame {} has {} vertices, the body has {}", t, posed[t].rows(), n);
    require(posed[t].allFinite(), "dynamics metrics: frame {} has a non-finite vertex position", t);
    require(motion.poses[t].allFinite() && motion.trans[t].allFinite(),
            "dynamics metrics: the pose of frame {} is not finite", t);
    amplitude.add(pullback.deviation(motion.poses[t], motion.trans[t], motion.world_from_body, posed[t]));
  }
  DynamicsResult result;
  result.sigma = amplitude.sigma();
  result.sigma_normal = amplitude.sigma_normal();
  result.sigma_tangent = amplitude.sigma_tangent();
  result.soft_vertices = soft_vertices;
  std::sort(result.soft_vertices.begin(), result.soft_vertices.end());
  result.frames = amplitude.frames();
  require(result.sigma.allFinite(), "dynamics metrics: σ is not finite");
  return result;
}

double fraction_recovered(const DynamicsResult& simulated, const DynamicsResult& ground_truth) {
  require(simulated.soft_vertices == ground_truth.soft_vertices,
          "fraction of dynamics recovered: the two results use different vertex sets ({} and {} vertices)",
          simulated.soft_vertices.size(), ground_truth.soft_vertices.size());
  const double reference = ground_truth.mean_sigma_soft();
  require(reference > 0.0, "fraction of dynamics recovered: the ground truth has no dynamics (mean σ = 0)");
  return simulated.mean_sigma_soft() / reference;
}

}  // namespace sflsh::validate
