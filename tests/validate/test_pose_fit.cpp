// Pose and shape fits on clean synthetic registrations (the body posed by a procedural motion, no soft
// tissue motion): the fitted model reproduces the registrations and the known poses, translations and β.
#include "validate_fixtures.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/validate/dynamics_metrics.hpp>
#include <sflsh/validate/pose_fit.hpp>

#include <gtest/gtest.h>

namespace sflsh::validate {
namespace {

using testing::open_body;
using testing::some_beta;
using testing::synthetic_sequence;

/// Largest vertex distance between the model posed by `fit` and the registrations [m].
double worst_vertex_error(const PoseFitResult& fit, const std::vector<RowMatrixX3d>& frames) {
  const body::Poser poser(open_body(), fit.beta);
  double worst = 0.0;
  for (std::size_t t = 0; t < frames.size(); ++t) {
    const RowMatrixX3d v =
        poser.pose(fit.motion.poses[t], fit.motion.trans[t]) * fit.motion.world_from_body.transpose();
    worst = std::max(worst, (v - frames[t]).rowwise().norm().maxCoeff());
  }
  return worst;
}

TEST(PoseFit, RecoversKnownPosesAndTranslationsWithBetaGiven) {
  const auto s = synthetic_sequence(open_body(), some_beta(), "running_on_spot", 10, {}, 0.0);
  PoseFitOptions options;
  options.soft_vertices = soft_region_vertices(open_body());
  const PoseFitResult fit = fit_motion(open_body(), s.frames, 60.0, s.beta, options);
  ASSERT_EQ(fit.frames.size(), s.frames.size());
  EXPECT_EQ(fit.unconverged_frames, 0);
  EXPECT_FALSE(fit.beta_fitted);
  // Clean data has a zero-residual minimum; LM stops once the RMS residual is below 1e-10 m (Gauss–Newton
  // converges quadratically there), so the fit reproduces the registrations to well below a micrometre.
  EXPECT_LT(fit.max_rms, 1e-7);
  EXPECT_LT(worst_vertex_error(fit, s.frames), 1e-6);
  double worst_trans = 0.0, worst_root = 0.0;
  for (std::size_t t = 0; t < s.frames.size(); ++t) {
    worst_trans = std::max(worst_trans, (fit.motion.trans[t] - s.motion.trans[t]).norm());
    const Eigen::Matrix3d r =
        body::rodrigues(fit.motion.poses[t].head<3>()).transpose() * body::rodrigues(s.motion.poses[t].head<3>());
    worst_root = std::max(worst_root, Eigen::AngleAxisd(r).angle());
  }
  // Translation and root orientation are determined by thousands of vertices: 1e-6 m / 1e-6 rad.
  EXPECT_LT(worst_trans, 1e-6);
  EXPECT_LT(worst_root, 1e-6);
  // Every joint that moves vertices is recovered (joint rotations act on ≥ 1 vertex with non-zero weight).
  for (std::size_t t = 0; t < s.frames.size(); t += 3)
    for (int k = 1; k < body::kNumJoints; ++k) {
      if (open_body().weights.col(k).maxCoeff() < 0.2) continue;  // too weakly observed to compare angles
      const Eigen::Matrix3d r = body::rodrigues(fit.motion.poses[t].segment<3>(3 * k)).transpose() *
                                body::rodrigues(s.motion.poses[t].segment<3>(3 * k));
      EXPECT_LT(Eigen::AngleAxisd(r).angle(), 1e-4)
          << "frame " << t << " joint " << body::kJointNames[static_cast<std::size_t>(k)];
    }
}

TEST(PoseFit, RecoversBetaWhenNotGiven) {
  const auto s = synthetic_sequence(open_body(), some_beta(), "shake_hips", 8, {}, 0.0);
  PoseFitOptions options;
  options.soft_vertices = soft_region_vertices(open_body());
  options.shape_frames = 4;
  const PoseFitResult fit = fit_motion(open_body(), s.frames, 60.0, std::nullopt, options);
  EXPECT_TRUE(fit.beta_fitted);
  EXPECT_TRUE(fit.shape_converged);
  // Variable projection reaches the zero-residual minimum of clean data (stopped by the 1e-10 m RMS absolute
  // test); measured max |Δβ| ≈ 2e-9 and RMS ≈ 4e-11 m, so 1e-6 and 1e-7 m fail only for a real error.
  EXPECT_LT((fit.beta - s.beta).cwiseAbs().maxCoeff(), 1e-6) << fit.beta.transpose();
  EXPECT_LT(fit.max_rms, 1e-7);
}

TEST(PoseFit, StartsFromARotatedWorldFrame) {
  // Z-up registrations: the rigid start (weighted Kabsch) finds the 90° root rotation.
  const auto s =
      synthetic_sequence(open_body(), some_beta(), "shake_shoulders", 4, {}, 0.0, 3, body::amass_world_from_body());
  const PoseFitResult fit = fit_motion(open_body(), s.frames, 60.0, s.beta, PoseFitOptions{});
  EXPECT_LT(fit.max_rms, 1e-7);  // as in the first test
}

TEST(PoseFit, RejectsNonFiniteRegistrations) {
  auto s = synthetic_sequence(open_body(), some_beta(), "shake_hips", 3, {}, 0.0);
  s.frames[1](5, 0) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(fit_motion(open_body(), s.frames, 60.0, s.beta, PoseFitOptions{}), Error);
}

}  // namespace
}  // namespace sflsh::validate
