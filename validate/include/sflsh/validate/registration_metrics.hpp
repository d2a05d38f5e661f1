#pragma once
// The dynamics metric of registrations (docs/physics.md §4, docs/validate.md): fit pose (and β when not given)
// per frame, pull the registrations back to the neutral pose and measure σ, σ_n, σ_t per vertex. `sflsh metrics`
// and the Python module's metrics() run this one pipeline.
#include <sflsh/validate/dynamics_metrics.hpp>
#include <sflsh/validate/pose_fit.hpp>

#include <optional>
#include <vector>

namespace sflsh::validate {

struct RegistrationMetrics {
  PoseFitResult fit;             ///< β, θ_t, trans_t and the per-frame fit reports
  DynamicsResult dynamics;       ///< σ, σ_n, σ_t per body vertex [m]
  double metrics_seconds = 0.0;  ///< the pull-back and σ (the fit's own time is fit.seconds)
};

/// σ of `registered` (T ≥ 2 frames of n×3 vertex positions [m], n the body's vertex count) at `fps`, with β
/// fixed when given and fitted otherwise. `options.soft_vertices` empty: the soft region of `model`
/// (soft_region_vertices). Throws sflsh::Error with a one-line message on bad input.
RegistrationMetrics registration_metrics(const body::BodyModel& model, const std::vector<RowMatrixX3d>& registered,
                                         double fps, const std::optional<body::Betas>& beta, PoseFitOptions options);

}  // namespace sflsh::validate
