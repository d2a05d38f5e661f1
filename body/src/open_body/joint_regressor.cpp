#include "joint_regressor.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

namespace sflsh::body::detail {
namespace {

constexpr double kRidge = 1e-5;  // λ [m²]
constexpr int kIterations = 4000;

/// Euclidean projection onto the probability simplex (Duchi et al. 2008).
Eigen::VectorXd project_to_simplex(const Eigen::VectorXd& y) {
  std::vector<double> sorted(y.data(), y.data() + y.size());
  std::sort(sorted.begin(), sorted.end(), std::greater<>());
  double cumulative = 0.0, theta = 0.0;
  for (std::size_t k = 0; k < sorted.size(); ++k) {
    cumulative += sorted[k];
    const double t = (cumulative - 1.0) / static_cast<double>(k + 1);
    if (sorted[k] - t > 0.0) theta = t;
  }
  return (y.array() - theta).max(0.0).matrix();
}

/// Template vertices around joint `center` in every direction: rays along kRayCount directions
/// (a Fibonacci sphere) leave the body at a hit point; the vertex nearest to each hit within
/// max(2.5 d, d + 5 cm) of the joint (d: distance to the nearest vertex) is a candidate.
std::vector<int> ring_candidates(const RowMatrixX3d& vertices, const BodyField& field, const Eigen::Vector3d& center) {
  constexpr int kRayCount = 256;
  constexpr double kStep = 0.003;
  const Eigen::VectorXd dist = (vertices.rowwise() - center.transpose()).rowwise().norm();
  const double nearest = dist.minCoeff();
  const double reach = std::max(2.5 * nearest, nearest + 0.05);
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  std::vector<int> found;
  for (int r = 0; r < kRayCount; ++r) {
    const double y = 1.0 - 2.0 * (r + 0.5) / kRayCount, radius = std::sqrt(1.0 - y * y);
    const Eigen::Vector3d dir(radius * std::cos(golden * r), y, radius * std::sin(golden * r));
    double t = 0.0;
    while (t < reach && field.value(center + t * dir) < 0.0) t += kStep;
    if (t >= reach) continue;
    const Eigen::Vector3d hit = center + t * dir;
    Eigen::Index best = 0;
    (vertices.rowwise() - hit.transpose()).rowwise().squaredNorm().minCoeff(&best);
    found.push_back(static_cast<int>(best));
  }
  std::sort(found.begin(), found.end());
  found.erase(std::unique(found.begin(), found.end()), found.end());
  return found;
}

/// Convex weights over `ring` reproducing joint j of every sample; returns the population rms [m].
double fit_joint(const std::vector<int>& ring, const Eigen::Vector3d& center, const Eigen::MatrixXd& sample_vertices,
                 const std::vector<JointArray>& sample_joints, int j, Eigen::VectorXd& w) {
  const auto samples = static_cast<Eigen::Index>(sample_joints.size());
  const auto k = static_cast<Eigen::Index>(ring.size());
  const auto target = [&](Eigen::Index s) {
    return sample_joints[static_cast<std::size_t>(s)][static_cast<std::size_t>(j)];
  };
  // Normal equations of the population term: H = (2/N) Σ P_kᵀP_k + 2λI, g = −(2/N) Σ P_kᵀ y_k − 2λu.
  const Eigen::VectorXd uniform = Eigen::VectorXd::Constant(k, 1.0 / static_cast<double>(k));
  Eigen::MatrixXd hessian = Eigen::MatrixXd::Zero(k, k);
  Eigen::VectorXd linear = Eigen::VectorXd::Zero(k);
  Eigen::Matrix<double, 3, Eigen::Dynamic> p(3, k);
  for (Eigen::Index s = 0; s < samples; ++s) {
    for (Eigen::Index i = 0; i < k; ++i)
      p.col(i) = sample_vertices.block<3, 1>(3 * ring[static_cast<std::size_t>(i)], s) - center;
    hessian.noalias() += p.transpose() * p;
    linear.noalias() -= p.transpose() * (target(s) - center);
  }
  hessian *= 2.0 / static_cast<double>(samples);
  linear *= 2.0 / static_cast<double>(samples);
  hessian.diagonal().array() += 2.0 * kRidge;
  linear -= 2.0 * kRidge * uniform;
  const double lipschitz =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(hessian, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
  // FISTA on the simplex.
  w = uniform;
  Eigen::VectorXd z = uniform;
  double t = 1.0;
  for (int it = 0; it < kIterations; ++it) {
    const Eigen::VectorXd next = project_to_simplex(z - (hessian * z + linear) / lipschitz);
    const double t_next = 0.5 * (1.0 + std::sqrt(1.0 + 4.0 * t * t));
    z = next + ((t - 1.0) / t_next) * (next - w);
    w = next;
    t = t_next;
  }
  w = (w.array() > 1e-6).select(w, 0.0);
  w /= w.sum();
  double sq = 0.0;
  for (Eigen::Index s = 0; s < samples; ++s) {
    Eigen::Vector3d fit = Eigen::Vector3d::Zero();
    for (Eigen::Index i = 0; i < k; ++i)
      fit += w(i) * sample_vertices.block<3, 1>(3 * ring[static_cast<std::size_t>(i)], s);
    sq += (fit - target(s)).squaredNorm();
  }
  return std::sqrt(sq / static_cast<double>(samples));
}

}  // namespace

Eigen::SparseMatrix<double, Eigen::RowMajor> fit_joint_regressor(const RowMatrixX3d& template_vertices,
                                                                 const std::vector<int>& mirror,
                                                                 const BodyField& template_field,
                                                                 const Skeleton& template_skeleton,
                                                                 const Eigen::MatrixXd& sample_vertices,
                                                                 const std::vector<JointArray>& sample_joints) {
  const auto samples = static_cast<Eigen::Index>(sample_joints.size());
  require(samples > 0 && sample_vertices.cols() == samples && sample_vertices.rows() == 3 * template_vertices.rows(),
          "open body: joint regressor needs 3n×N sample vertices matching N joint sets");
  require(static_cast<Eigen::Index>(mirror.size()) == template_vertices.rows(),
          "open body: joint regressor needs the mirror map of the template vertices");
  std::vector<Eigen::Triplet<double>> triplets;
  double worst_rms = 0.0;
  for (int j = 0; j < kNumJoints; ++j) {
    const int partner = mirror_joint(j);
    if (partner < j) continue;  // right joints mirror their left partners
    const Eigen::Vector3d center = template_skeleton.joints[static_cast<std::size_t>(j)];
    const std::vector<int> ring = ring_candidates(template_vertices, template_field, center);
    require(ring.size() >= 3, "open body: joint {} sees only {} surface vertices",
            kJointNames[static_cast<std::size_t>(j)], ring.size());
    Eigen::VectorXd w;
    const double rms = fit_joint(ring, center, sample_vertices, sample_joints, j, w);
    worst_rms = std::max(worst_rms, rms);
    logger()->debug("open body: joint {} regressed from {} vertices, rms {:.2f} mm",
                    kJointNames[static_cast<std::size_t>(j)], ring.size(), 1e3 * rms);
    for (std::size_t i = 0; i < ring.size(); ++i) {
      const double wi = w(static_cast<Eigen::Index>(i));
      if (wi == 0.0) continue;
      const int v = ring[i], v_mirror = mirror[static_cast<std::size_t>(v)];
      if (partner == j) {  // central joint: symmetrised weights
        triplets.emplace_back(j, v, 0.5 * wi);
        triplets.emplace_back(j, v_mirror, 0.5 * wi);
      } else {
        triplets.emplace_back(j, v, wi);
        triplets.emplace_back(partner, v_mirror, wi);
      }
    }
  }
  Eigen::SparseMatrix<double, Eigen::RowMajor> regressor(kNumJoints, template_vertices.rows());
  regressor.setFromTriplets(triplets.begin(), triplets.end());
  logger()->info("open body: joint regressor fitted, worst joint rms over the population {:.2f} mm", 1e3 * worst_rms);
  return regressor;
}

}  // namespace sflsh::body::detail
