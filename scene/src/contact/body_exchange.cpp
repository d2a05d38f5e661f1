// The exchange of surfaces between touching bodies (body_exchange.hpp).
#include "contact/body_exchange.hpp"

#include "bodies/body_groups.hpp"

#include <sflsh/core/error.hpp>

#include <Eigen/QR>

#include <algorithm>
#include <array>

namespace sflsh::scene {

ExchangeAccelerator::ExchangeAccelerator(double first_relaxation, int max_columns)
    : first_relaxation_(first_relaxation), max_columns_(max_columns) {
  require(first_relaxation > 0.0 && first_relaxation <= 1.0, "exchange: first relaxation must be in (0, 1], got {}",
          first_relaxation);
  require(max_columns >= 1, "exchange: at least one column, got {}", max_columns);
}

Eigen::VectorXd ExchangeAccelerator::next(const Eigen::VectorXd& x, const Eigen::VectorXd& output) {
  require(x.size() == output.size(), "exchange: {} unknowns but {} outputs", x.size(), output.size());
  const Eigen::VectorXd residual = output - x;  // r = H(x) − x
  require(residual.allFinite(), "exchange: the surfaces are not finite");
  if (last_residual_.size() == residual.size()) {
    residual_differences_.push_back(residual - last_residual_);
    output_differences_.push_back(output - last_output_);
    if (static_cast<int>(residual_differences_.size()) > max_columns_) {
      residual_differences_.erase(residual_differences_.begin());
      output_differences_.erase(output_differences_.begin());
    }
  }
  last_residual_ = residual;
  last_output_ = output;
  if (residual_differences_.empty()) return x + first_relaxation_ * residual;
  const auto n = residual.size();
  const auto m = static_cast<Eigen::Index>(residual_differences_.size());
  Eigen::MatrixXd V(n, m), W(n, m);
  for (Eigen::Index k = 0; k < m; ++k) {
    V.col(k) = residual_differences_[static_cast<std::size_t>(k)];
    W.col(k) = output_differences_[static_cast<std::size_t>(k)];
  }
  // c = argmin ‖V c + r‖; the rank-revealing QR drops dependent columns (their c is 0).
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(V);
  qr.setThreshold(1e-10);
  const Eigen::VectorXd c = qr.solve(-residual);
  if (!c.allFinite()) return x + first_relaxation_ * residual;
  return output + W * c;  // x_{k+1} = H(x_k) + W c
}

std::vector<std::vector<std::size_t>> touching_clusters(const std::vector<std::size_t>& group,
                                                        const std::vector<std::vector<std::size_t>>& touches) {
  const std::size_t n = group.size();
  require(touches.size() == n, "exchange: {} touch lists for {} bodies", touches.size(), n);
  std::vector<std::array<std::size_t, 2>> links;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t o : touches[i]) {
      const auto it = std::find(group.begin(), group.end(), o);
      if (it == group.end()) continue;  // out of the group: out of reach
      links.push_back({i, static_cast<std::size_t>(it - group.begin())});
    }
  std::vector<std::vector<std::size_t>> clusters = detail::connected_components(n, links);
  for (auto& c : clusters)
    for (std::size_t& member : c) member = group[member];
  clusters.erase(std::remove_if(clusters.begin(), clusters.end(), [](const auto& c) { return c.size() < 2; }),
                 clusters.end());
  for (auto& c : clusters) std::sort(c.begin(), c.end());
  std::sort(clusters.begin(), clusters.end(), [](const auto& a, const auto& b) { return a.front() < b.front(); });
  return clusters;
}

// summary.json "body_exchange": the exchanges of the touching clusters, over the steps where bodies touched.
}  // namespace sflsh::scene

namespace sflsh::scene::detail {

nlohmann::json exchange_summary(const std::vector<ExchangeRecord>& records, const ContactSpec& contact,
                                const std::function<std::string(std::size_t)>& name) {
  constexpr std::size_t kListed = 5000;  // per-step entries listed (the totals cover every step)
  long total = 0, unconverged = 0, apart = 0, restarts = 0;
  int most = 0;
  double residual = 0.0, penetration = 0.0;
  nlohmann::json per_step = nlohmann::json::array();
  for (const ExchangeRecord& r : records) {
    total += r.exchanges;
    most = std::max(most, r.exchanges);
    if (!r.converged) ++unconverged;
    restarts += r.restarts;
    if (r.apart)
      ++apart;  // the solves did not feel the other surface: how far apart it ended says nothing of agreement
    else
      residual = std::max(residual, r.surface_residual);
    penetration = std::max(penetration, r.residual_penetration);
    if (per_step.size() >= kListed) continue;
    nlohmann::json names = nlohmann::json::array();
    for (std::size_t b : r.bodies) names.push_back(name(b));
    per_step.push_back({{"t", r.t},
                        {"bodies", names},
                        {"exchanges", r.exchanges},
                        {"surface_residual_mm", 1e3 * r.surface_residual},
                        {"force_change", r.force_change},
                        {"residual_penetration_mm", 1e3 * r.residual_penetration},
                        {"converged", r.converged},
                        {"apart", r.apart},
                        {"restarts", r.restarts}});
  }
  const auto n = static_cast<double>(records.size());
  return {
      {"enabled", contact.body_exchange},
      {"scheme",
       "touching bodies solved from the step's start against each other's end-of-step surfaces (block Jacobi), "
       "exchanged with interface quasi-Newton acceleration until they agree (enabled = false: one Gauss–Seidel sweep "
       "per step in scene order)"},
      {"tolerance_mm", 1e3 * contact.exchange_tolerance},
      {"force_change_tolerance", 0.02},
      {"max_exchanges", contact.max_exchanges},
      {"contact_steps", records.size()},
      {"exchanges_mean", n > 0 ? static_cast<double>(total) / n : 0.0},
      {"exchanges_max", most},
      {"surface_residual_max_mm", 1e3 * residual},
      {"apart_steps", apart},
      {"restarts", restarts},
      {"residual_penetration_max_mm", 1e3 * penetration},
      {"unconverged_steps", unconverged},
      {"converged", unconverged == 0},
      {"per_step", per_step},
      {"per_step_truncated", records.size() > kListed}};
}

}  // namespace sflsh::scene::detail
