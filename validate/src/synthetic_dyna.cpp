// Synthetic registrations with known localized soft-tissue motion over procedural poses (synthetic_dyna.hpp).
#include <sflsh/core/error.hpp>
#include <sflsh/model/simulation_output.hpp>
#include <sflsh/validate/synthetic_dyna.hpp>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace sflsh::validate {

namespace {

/// One blob: where its anchor lies (a point in the x–y plane of the shaped template and the side it faces).
struct BlobSite {
  double x, y;
  double facing;  ///< +1 front (+z), −1 back
};

std::vector<BlobSite> blob_sites(const std::string& region, const body::JointPositions& j) {
  // SMPL joints: 0 pelvis, 1/2 left/right hip, 3 spine1, 4/5 knees, 9 spine3, 16/17 shoulders. Body axes:
  // +x the body's left, +y up, +z forward.
  const auto x = [&](int k) { return j(k, 0); };
  const auto y = [&](int k) { return j(k, 1); };
  if (region == "chest") {
    const double half = 0.5 * (x(16) - x(17)) * 0.55;  // pectorals about halfway to the shoulders
    return {{x(9) + half, y(9) - 0.03, 1.0}, {x(9) - half, y(9) - 0.03, 1.0}};
  }
  if (region == "belly") return {{x(3), 0.5 * (y(0) + y(3)), 1.0}};
  if (region == "buttocks") return {{x(1), y(1), -1.0}, {x(2), y(2), -1.0}};
  if (region == "thighs")
    return {{0.5 * (x(1) + x(4)), 0.5 * (y(1) + y(4)), 1.0}, {0.5 * (x(2) + x(5)), 0.5 * (y(2) + y(5)), 1.0}};
  throw Error(fmt::format("synthetic soft motion: unknown region '{}', expected one of {}", region,
                          fmt::join(soft_motion_region_names(), ", ")));
}

/// The soft-region vertex facing the site's side (n_z · facing > 0.5) nearest to the site in the x–y plane.
int anchor_vertex(const BlobSite& site, const RowMatrixX3d& shaped, const RowMatrixX3d& normals,
                  const std::vector<int>& soft) {
  int best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  for (int v : soft) {
    if (normals(v, 2) * site.facing < 0.5) continue;
    const double d = std::hypot(shaped(v, 0) - site.x, shaped(v, 1) - site.y);
    if (d < best_d) {
      best_d = d;
      best = v;
    }
  }
  require(best >= 0, "synthetic soft motion: no soft-region vertex faces the blob at ({:.3f}, {:.3f})", site.x, site.y);
  return best;
}

}  // namespace

const std::vector<std::string>& soft_motion_region_names() {
  static const std::vector<std::string> names = {"chest", "belly", "buttocks", "thighs"};
  return names;
}

SyntheticSoftSequence synthetic_soft_motion(const body::BodyModel& model, const SyntheticSoftMotion& spec) {
  require(spec.frames >= 2, "synthetic soft motion: frames must be at least 2, got {}", spec.frames);
  require(spec.fps > 0.0 && spec.amplitude > 0.0 && spec.frequency > 0.0 && spec.radius > 0.0,
          "synthetic soft motion: fps, amplitude, frequency and radius must be positive (got {}, {}, {}, {})", spec.fps,
          spec.amplitude, spec.frequency, spec.radius);
  require(!spec.regions.empty(), "synthetic soft motion: no region given (expected some of {})",
          fmt::join(soft_motion_region_names(), ", "));
  SyntheticSoftSequence s;
  s.beta = spec.beta;
  s.motion = body::make_procedural_motion(spec.motion, spec.fps, spec.frames);
  s.motion.world_from_body = spec.world_from_body;
  const Eigen::Index n = model.num_vertices();
  const RowMatrixX3d shaped = body::shaped_template(model, spec.beta);
  const body::JointPositions joints = body::regress_joints(model, shaped);
  const RowMatrixX3d normals = model::vertex_normals(shaped, model.faces);
  const std::vector<int> soft = soft_region_vertices(model);

  // Per vertex: the displacement direction times g_i, and the blob's phase (blobs barely overlap; where they
  // do, the stronger one wins so that each vertex oscillates with one phase).
  RowMatrixX3d shape = RowMatrixX3d::Zero(n, 3);
  Eigen::VectorXd strength = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd phase = Eigen::VectorXd::Zero(n);
  int blob = 0;
  for (const std::string& region : spec.regions)
    for (const BlobSite& site : blob_sites(region, joints)) {
      const int anchor = anchor_vertex(site, shaped, normals, soft);
      const Eigen::Vector3d centre = shaped.row(anchor).transpose();
      const Eigen::Vector3d facing = normals.row(anchor).transpose();
      const double blob_phase = 0.9 * blob++;  // distinct, deterministic phases φ_b [rad]
      for (int v : soft) {
        const Eigen::Vector3d nv = normals.row(v).transpose();
        if (nv.dot(facing) <= 0.0) continue;
        const double g =
            std::exp(-(shaped.row(v).transpose() - centre).squaredNorm() / (2 * spec.radius * spec.radius));
        if (g < 0.01 || g <= strength[v]) continue;                         // cut below 1 % (|x − x_b| > 3 r)
        Eigen::Vector3d tangent = Eigen::Vector3d(0, -1, 0) + nv.y() * nv;  // −y minus its normal part
        if (tangent.norm() < 1e-6) tangent = Eigen::Vector3d::UnitX() - nv.x() * nv;
        tangent.normalize();
        strength[v] = g;
        phase[v] = blob_phase;
        shape.row(v) = (g * (std::cos(spec.angle) * nv + std::sin(spec.angle) * tangent)).transpose();
      }
    }
  for (Eigen::Index v = 0; v < n; ++v)
    if (strength[v] > 0.0) s.moving_vertices.push_back(static_cast<int>(v));

  model::DynamicsAmplitude amplitude(normals);
  const double omega = 2 * std::numbers::pi * spec.frequency;
  for (int t = 0; t < spec.frames; ++t) {
    const double time = static_cast<double>(t) / spec.fps;
    RowMatrixX3d d = RowMatrixX3d::Zero(n, 3);
    for (int v : s.moving_vertices) d.row(v) = spec.amplitude * std::sin(omega * time + phase[v]) * shape.row(v);
    amplitude.add(d);  // the known σ accumulates d itself
    const body::Pose& theta = s.motion.poses[static_cast<std::size_t>(t)];
    const RowMatrixX3d unposed = shaped + body::pose_correctives(model, theta) + d;
    const body::Kinematics kin =
        body::forward_kinematics(model, joints, theta, s.motion.trans[static_cast<std::size_t>(t)]);
    s.frames.push_back(body::linear_blend_skinning(model, kin, unposed) * spec.world_from_body.transpose());
  }
  s.truth.sigma = amplitude.sigma();
  s.truth.sigma_normal = amplitude.sigma_normal();
  s.truth.sigma_tangent = amplitude.sigma_tangent();
  s.truth.soft_vertices = soft;
  std::sort(s.truth.soft_vertices.begin(), s.truth.soft_vertices.end());
  s.truth.frames = amplitude.frames();
  return s;
}

DynaSequence to_dyna_sequence(const SyntheticSoftSequence& sequence, const SyntheticSoftMotion& spec,
                              const std::string& subject) {
  DynaSequence out;
  out.key = subject + "_" + spec.motion;
  out.frames = sequence.frames;
  out.fps = spec.fps;
  out.attributes.numbers["fps"] = {spec.fps};
  out.attributes.numbers["beta"] =
      std::vector<double>(sequence.beta.data(), sequence.beta.data() + sequence.beta.size());
  out.attributes.numbers["soft_amplitude"] = {spec.amplitude};
  out.attributes.numbers["soft_frequency"] = {spec.frequency};
  out.attributes.numbers["soft_angle"] = {spec.angle};
  out.attributes.numbers["soft_radius"] = {spec.radius};
  out.attributes.strings["soft_regions"] = fmt::format("{}", fmt::join(spec.regions, ","));
  out.attributes.strings["source"] = "sflsh synthetic soft-tissue motion";
  return out;
}

double sigma_correlation(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const std::vector<int>& vertices) {
  Eigen::VectorXd x(static_cast<Eigen::Index>(vertices.size())), y(x.size());
  for (std::size_t k = 0; k < vertices.size(); ++k) {
    x[static_cast<Eigen::Index>(k)] = a[vertices[k]];
    y[static_cast<Eigen::Index>(k)] = b[vertices[k]];
  }
  const Eigen::VectorXd dx = x.array() - x.mean(), dy = y.array() - y.mean();
  const double norms = std::sqrt(dx.squaredNorm() * dy.squaredNorm());
  return norms > 0.0 ? dx.dot(dy) / norms : 0.0;
}

}  // namespace sflsh::validate
