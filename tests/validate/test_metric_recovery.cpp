// The dynamics metric keeps the dynamics it is given: synthetic DYNA-layout sequences with known, localized soft-
// tissue motion (chest, belly, buttocks, thighs; synthetic_dyna.hpp) over procedural poses, fitted with the default
// rigidity-weighted pose fit, β given and fitted (docs/validate.md "Recovery of known dynamics").
#include "scratch_dir.hpp"
#include "validate_fixtures.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/validate/dyna_file.hpp>
#include <sflsh/validate/registration_metrics.hpp>
#include <sflsh/validate/rigidity.hpp>
#include <sflsh/validate/synthetic_dyna.hpp>

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace sflsh::validate {
namespace {

using testing::open_body;

TEST(SyntheticSoftMotion, KnownSigmaIsWhatTheMetricMeasuresWithTheTruePoses) {
  SyntheticSoftMotion spec;
  spec.motion = "one_leg_jump";
  spec.frames = 40;
  spec.beta = testing::some_beta();
  const SyntheticSoftSequence s = synthetic_soft_motion(open_body(), spec);
  ASSERT_EQ(s.frames.size(), 40u);
  // Localized: every moving vertex lies in the soft region, a few hundred move (seven blobs of r = 5 cm), and
  // σ vanishes elsewhere.
  const std::vector<char> soft = s.truth.soft_mask();
  EXPECT_GT(s.moving_vertices.size(), 200u);
  EXPECT_LT(s.moving_vertices.size(), s.truth.soft_vertices.size() / 2);
  for (int v : s.moving_vertices) EXPECT_TRUE(soft[static_cast<std::size_t>(v)]) << v;
  std::vector<char> moving(soft.size(), 0);
  for (int v : s.moving_vertices) moving[static_cast<std::size_t>(v)] = 1;
  for (Eigen::Index v = 0; v < s.truth.sigma.size(); ++v) {
    if (!moving[static_cast<std::size_t>(v)]) {
      EXPECT_EQ(s.truth.sigma[v], 0.0);
    }
  }
  // A sinusoid of peak A at the blob centres: σ ≤ A (its RMS over a window is near A/√2).
  EXPECT_LT(s.truth.sigma.maxCoeff(), spec.amplitude);
  EXPECT_GT(s.truth.sigma.maxCoeff(), 0.5 * spec.amplitude);
  // Normal and tangential at α = 45°: both parts carry about half of σ² (the tangent is the unit vector nearest −y).
  EXPECT_NEAR(s.truth.mean_sigma_normal_soft() / s.truth.mean_sigma_tangent_soft(), 1.0, 1e-9);
  // With the true poses, inverse skinning undoes the skinning to round-off: the metric returns the known σ.
  const DynamicsResult r = dynamics_metrics(open_body(), s.beta, s.motion, s.frames, s.truth.soft_vertices);
  EXPECT_LT((r.sigma - s.truth.sigma).cwiseAbs().maxCoeff(), 1e-10);  // 1e-7 of mm amplitudes
}

TEST(SyntheticSoftMotion, WritesADynaFileAndRejectsBadSpecs) {
  SyntheticSoftMotion spec;
  spec.frames = 6;
  spec.regions = {"belly"};
  const SyntheticSoftSequence s = synthetic_soft_motion(open_body(), spec);
  const auto path = sflsh::testing::scratch_dir() / "soft.h5";
  write_dyna_file(path, open_body().faces, {to_dyna_sequence(s, spec, "SYNTH")});
  const DynaFile file(path);
  const DynaSequence back = file.read("SYNTH_running_on_spot");
  ASSERT_EQ(back.num_frames(), 6);
  EXPECT_LT((back.frames[5] - s.frames[5]).cwiseAbs().maxCoeff(), 1e-15);  // float64 in the file
  EXPECT_EQ(back.attributes.strings.at("soft_regions"), "belly");
  EXPECT_DOUBLE_EQ(*back.attributes.number("soft_frequency"), 3.0);
  spec.regions = {"elbow"};
  EXPECT_THROW(synthetic_soft_motion(open_body(), spec), Error);
  spec.regions = {"belly"};
  spec.frequency = 0.0;
  EXPECT_THROW(synthetic_soft_motion(open_body(), spec), Error);
}

TEST(RigidityWeights, FollowTheDistanceToTheBones) {
  const std::vector<int> soft = soft_region_vertices(open_body());
  const Eigen::VectorXd w = rigidity_weights(open_body(), soft, 0.03);
  std::vector<char> is_soft(static_cast<std::size_t>(w.size()), 0);
  for (int v : soft) is_soft[static_cast<std::size_t>(v)] = 1;
  const RowMatrixX3d shaped = body::shaped_template(open_body(), body::Betas::Zero());
  const Eigen::VectorXd depth = bone_distance(open_body(), shaped, body::regress_joints(open_body(), shaped));
  for (Eigen::Index v = 0; v < w.size(); ++v) {
    if (!is_soft[static_cast<std::size_t>(v)])
      EXPECT_EQ(w[v], 1.0);
    else
      EXPECT_NEAR(w[v], std::pow(0.03 / std::max(depth[v], 0.03), 4), 1e-15);
  }
  EXPECT_THROW(rigidity_weights(open_body(), soft, 0.0), Error);
}

struct RecoveryCase {
  const char* motion;
  double amplitude, frequency;
  std::vector<std::string> regions = soft_motion_region_names();
};

/// The acceptance: the mean σ over the soft region within 5 % and σ per vertex correlated at ≥ 0.95.
/// Measured (docs/validate.md table): errors ≤ 0.11 % and correlations ≥ 0.9999 on every row; the earlier
/// soft-weight fit is 21 % off with every region moving (correlation 0.957), so the 5 % bound separates a fit that
/// keeps the dynamics from one that absorbs them into the joints.
constexpr double kAcceptedError = 0.05;
constexpr double kAcceptedCorrelation = 0.95;

/// Fits the sequence with the default options and checks the recovery of the mean σ and of σ per vertex.
void expect_recovery(const RecoveryCase& c, bool beta_given, int frames, double max_error = kAcceptedError,
                     double min_correlation = kAcceptedCorrelation) {
  SyntheticSoftMotion spec;
  spec.motion = c.motion;
  spec.frames = frames;
  spec.amplitude = c.amplitude;
  spec.frequency = c.frequency;
  spec.regions = c.regions;
  const SyntheticSoftSequence s = synthetic_soft_motion(open_body(), spec);
  const RegistrationMetrics m = registration_metrics(
      open_body(), s.frames, spec.fps, beta_given ? std::optional<body::Betas>(s.beta) : std::nullopt, {});
  const double truth = s.truth.mean_sigma_soft();
  const double error = m.dynamics.mean_sigma_soft() / truth - 1.0;
  const double r = sigma_correlation(s.truth.sigma, m.dynamics.sigma, s.truth.soft_vertices);
  SCOPED_TRACE(::testing::Message() << c.motion << " A " << c.amplitude << " m, f " << c.frequency << " Hz, "
                                    << c.regions.size() << " region(s), β " << (beta_given ? "given" : "fitted")
                                    << ": error " << 100 * error << " %, correlation " << r);
  EXPECT_LT(std::abs(error), max_error);
  EXPECT_GE(r, min_correlation);
  EXPECT_EQ(m.fit.unconverged_frames, 0);
}

TEST(MetricRecovery, BetaGivenSeveralMotionsAmplitudesAndFrequencies) {
  // 90 frames (1.5 s): at least three periods of the slowest oscillation (2 Hz) after the 0.5 s ease-in.
  for (const RecoveryCase& c : {RecoveryCase{"running_on_spot", 0.006, 3.0}, RecoveryCase{"one_leg_jump", 0.002, 6.0},
                                RecoveryCase{"shake_hips", 0.008, 2.0}})
    expect_recovery(c, true, 90);
}

TEST(MetricRecovery, BetaFitted) {
  for (const RecoveryCase& c :
       {RecoveryCase{"jiggle_on_toes", 0.006, 4.0}, RecoveryCase{"shake_shoulders", 0.004, 2.0}})
    expect_recovery(c, false, 90);
}

TEST(MetricRecovery, ThighsAloneKeepTheStillSoftVerticesStill) {
  // One region alone has a small mean over the soft region (0.13 mm here), so what the fit leaves on its ~3 800
  // still soft vertices weighs in it. The thighs were the worst case: +5.5 % (correlation 0.99977) at these 90
  // frames with a fixed σ_0 = 0.2 mm and a reweighting floor of 0.02 (the blobs' fringe and their floored centres
  // steered the pelvis and the hips by 0.15–0.2 mrad, which left 0.01–0.02 mm on the still vertices around them);
  // +0.10 % (correlation 1 − 1e-7) with σ_0 measured off the soft region and the prior scaled with it. The data
  // are noise-free, so 1 % is 10× the present error and fails the old fit 5×; 0.9999 fails its correlation too.
  expect_recovery({"running_on_spot", 0.006, 3.0, {"thighs"}}, true, 90, 0.01, 0.9999);
}

}  // namespace
}  // namespace sflsh::validate
