#pragma once
// Synthetic DYNA-like sequences for the validate tests, built by the tests themselves: the open body posed
// by a procedural motion, with known sinusoidal displacements added in the unposed frame before skinning
// (so the metric's pull-back must return them exactly). Per displaced vertex i:
//   δ_i(t) = A_i sin(2π m_i t / T + φ_i) (cos α_i n_i + sin α_i τ_i),
// n_i the unit normal of the shaped template, τ_i a unit tangent, m_i whole periods over the T frames, so
//   σ_i = A_i/√2, σ_i^n = A_i cos α_i/√2, σ_i^t = A_i sin α_i/√2 exactly (Σ_t sin = 0, Σ_t sin² = T/2).
#include <sflsh/body/body_io.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/body/skinning.hpp>
#include <sflsh/model/simulation_output.hpp>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace sflsh::validate::testing {

inline const body::BodyModel& open_body() {
  static const body::BodyModel model = body::load_body(std::filesystem::path(SFLSH_DATA_DIR) / "open_body.npz");
  return model;
}

inline body::Betas some_beta() {
  body::Betas beta = body::Betas::Zero();
  beta[0] = 0.8;
  beta[1] = -0.5;
  beta[3] = 0.3;
  return beta;
}

struct SyntheticSequence {
  body::Betas beta;
  body::Motion motion;
  std::vector<body::RowMatrixX3d> frames;              ///< posed (world) vertices per frame
  Eigen::VectorXd sigma, sigma_normal, sigma_tangent;  ///< the known amplitudes per body vertex [m]
};

/// `displaced`: vertices that get a displacement (others none); amplitudes A_i ∈ [amplitude/4, amplitude].
inline SyntheticSequence synthetic_sequence(const body::BodyModel& model, const body::Betas& beta,
                                            const std::string& motion_name, int frames,
                                            const std::vector<int>& displaced, double amplitude, unsigned seed = 3,
                                            const Eigen::Matrix3d& world_from_body = Eigen::Matrix3d::Identity()) {
  SyntheticSequence s;
  s.beta = beta;
  s.motion = body::make_procedural_motion(motion_name, 60.0, frames);
  s.motion.world_from_body = world_from_body;
  const Eigen::Index n = model.num_vertices();
  const body::RowMatrixX3d shaped = body::shaped_template(model, beta);
  const body::JointPositions joints = body::regress_joints(model, shaped);
  const body::RowMatrixX3d normals = model::vertex_normals(shaped, model.faces);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  const int T = static_cast<int>(s.motion.num_frames());
  struct Wave {
    int vertex;
    double a, m, phase;
    Eigen::Vector3d direction;
  };
  std::vector<Wave> waves;
  s.sigma = s.sigma_normal = s.sigma_tangent = Eigen::VectorXd::Zero(n);
  for (int v : displaced) {
    Wave w;
    w.vertex = v;
    w.a = amplitude * (0.25 + 0.75 * uniform(rng));
    w.m = 1 + static_cast<int>(3 * uniform(rng));  // 1..3 whole periods (T ≥ 8 keeps 2m < T)
    w.phase = 2 * std::numbers::pi * uniform(rng);
    const double alpha = 0.5 * std::numbers::pi * uniform(rng);
    const Eigen::Vector3d nv = normals.row(v).transpose();
    Eigen::Vector3d tangent(normal(rng), normal(rng), normal(rng));
    tangent = (tangent - tangent.dot(nv) * nv).normalized();
    w.direction = std::cos(alpha) * nv + std::sin(alpha) * tangent;
    s.sigma[v] = w.a / std::sqrt(2.0);
    s.sigma_normal[v] = w.a * std::cos(alpha) / std::sqrt(2.0);
    s.sigma_tangent[v] = w.a * std::sin(alpha) / std::sqrt(2.0);
    waves.push_back(w);
  }
  for (int t = 0; t < T; ++t) {
    const body::Pose& theta = s.motion.poses[static_cast<std::size_t>(t)];
    body::RowMatrixX3d unposed = shaped + body::pose_correctives(model, theta);
    for (const Wave& w : waves)
      unposed.row(w.vertex) += (w.a * std::sin(2 * std::numbers::pi * w.m * t / T + w.phase)) * w.direction.transpose();
    const body::Kinematics kin =
        body::forward_kinematics(model, joints, theta, s.motion.trans[static_cast<std::size_t>(t)]);
    s.frames.push_back(body::linear_blend_skinning(model, kin, unposed) * world_from_body.transpose());
  }
  return s;
}

}  // namespace sflsh::validate::testing
