#include <sflsh/core/error.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/validate/registration_metrics.hpp>

#include <chrono>

namespace sflsh::validate {

RegistrationMetrics registration_metrics(const body::BodyModel& model, const std::vector<RowMatrixX3d>& registered,
                                         double fps, const std::optional<body::Betas>& beta, PoseFitOptions options) {
  require(registered.size() >= 2, "metrics: {} frame(s) of registrations, σ needs at least 2", registered.size());
  for (std::size_t t = 0; t < registered.size(); ++t)
    require(registered[t].rows() == model.num_vertices(),
            "metrics: frame {} has {} vertices, the body model '{}' has {}", t, registered[t].rows(), model.name,
            model.num_vertices());
  if (options.soft_vertices.empty()) options.soft_vertices = soft_region_vertices(model);
  RegistrationMetrics result;
  result.fit = fit_motion(model, registered, fps, beta, options);
  const auto t_metrics = std::chrono::steady_clock::now();
  result.dynamics = dynamics_metrics(model, result.fit.beta, result.fit.motion, registered, options.soft_vertices);
  result.metrics_seconds = seconds_since(t_metrics);
  return result;
}

}  // namespace sflsh::validate
