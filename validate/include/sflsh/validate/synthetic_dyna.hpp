#pragma once
// Synthetic DYNA-layout registrations with known, localized soft-tissue motion, to check the dynamics metric
// (docs/validate.md "Recovery of known dynamics"). The body of shape β follows a procedural motion; on top,
// in the neutral pose (the frame the metric pulls back to), blobs of skin on the chest, belly, buttocks and
// thighs oscillate coherently:
//   d_i(t) = A g_i sin(2π f t + φ_b) (cos α n_i + sin α τ_i),   g_i = exp(−|x_i − x_b|² / (2 r²)),
// x_b the blob's anchor vertex, n_i the unit normal of the shaped template, τ_i the unit tangent nearest
// to −y (downwards: soft tissue sags and bounces vertically), r the blob radius, g cut below 1 % and
// restricted to the soft region on the anchor's side (n_i · n_b > 0). Then
//   v_i(t) = R_wb A_i(θ_t, trans_t) [T_S,i + B_P,i(θ_t) + d_i(t); 1]   (linear blend skinning, as SMPL),
// so that inverse skinning with the true poses returns d exactly. The known σ, σ_n, σ_t are d's, computed by
// model::DynamicsAmplitude, the accumulator of the metric itself.
#include <sflsh/body/motion.hpp>
#include <sflsh/body/skinning.hpp>
#include <sflsh/validate/dyna_file.hpp>
#include <sflsh/validate/dynamics_metrics.hpp>

#include <string>
#include <vector>

namespace sflsh::validate {

/// Blob regions: "chest" (two, left and right), "belly" (one), "buttocks" (two), "thighs" (two, front).
const std::vector<std::string>& soft_motion_region_names();

struct SyntheticSoftMotion {
  std::string motion = "running_on_spot";  ///< a procedural motion (body::make_procedural_motion)
  int frames = 300;                        ///< ≥ 2
  double fps = 60.0;                       ///< [Hz]
  body::Betas beta = body::Betas::Zero();
  std::vector<std::string> regions = soft_motion_region_names();
  double amplitude = 0.006;           ///< A [m], peak displacement at a blob's centre
  double frequency = 3.0;             ///< f [Hz]
  double angle = 0.7853981633974483;  ///< α [rad]: 0 normal only, π/2 tangential only (default π/4)
  double radius = 0.05;               ///< r [m]
  Eigen::Matrix3d world_from_body = Eigen::Matrix3d::Identity();
};

struct SyntheticSoftSequence {
  body::Betas beta;
  body::Motion motion;                     ///< the true θ_t, trans_t
  std::vector<body::RowMatrixX3d> frames;  ///< posed world vertices per frame [m]
  DynamicsResult truth;                    ///< the known σ, σ_n, σ_t [m]; soft_vertices = the soft region
  std::vector<int> moving_vertices;        ///< vertices with g_i > 0 (ascending)
};

/// Builds the sequence. Throws naming a bad field (unknown region or motion, frames < 2, non-positive
/// amplitude, frequency, fps or radius).
SyntheticSoftSequence synthetic_soft_motion(const body::BodyModel& model, const SyntheticSoftMotion& spec);

/// Pearson correlation of two per-vertex fields (e.g. known and recovered σ) over `vertices`; 0 when either is
/// constant there. How recovery of known dynamics is judged (docs/validate.md).
double sigma_correlation(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const std::vector<int>& vertices);

/// The sequence as one DYNA dataset "<subject>_<motion>" with attributes fps, beta [–], and the spec
/// (soft_amplitude [m], soft_frequency [Hz], soft_angle [rad], soft_radius [m], soft_regions).
DynaSequence to_dyna_sequence(const SyntheticSoftSequence& sequence, const SyntheticSoftMotion& spec,
                              const std::string& subject);

}  // namespace sflsh::validate
