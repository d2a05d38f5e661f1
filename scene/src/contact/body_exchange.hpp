#pragma once
// Internal to the scene runner: what the exchange between touching bodies reports (exchange_accelerator.hpp has
// the method).
#include <sflsh/scene/exchange_accelerator.hpp>
#include <sflsh/scene/scene_file.hpp>

#include <nlohmann/json.hpp>

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace sflsh::scene::detail {

/// One touching cluster's exchange in one step (summary.json "body_exchange").
struct ExchangeRecord {
  double t = 0.0;                     ///< the step's end [s]
  std::vector<std::size_t> bodies;    ///< the cluster (scene indices, ascending)
  int exchanges = 0;                  ///< solves of every body in the cluster (1: the first solve was kept)
  double surface_residual = 0.0;      ///< [m] largest move of a surface vertex in the last exchange
  double force_change = 0.0;          ///< relative change of the cluster's summed contact force in the last exchange
  double residual_penetration = 0.0;  ///< [m] deepest skin vertex inside another body's final surface
  bool converged = false;
  bool apart = false;  ///< converged because no force acted and the surfaces ended apart (surface_residual moot)
  int restarts = 0;    ///< times the quasi-Newton history was dropped after it stopped reducing the residual
};

/// summary.json "body_exchange": the exchanges over the steps where bodies touched (`name`: a body's name by
/// scene index).
nlohmann::json exchange_summary(const std::vector<ExchangeRecord>& records, const ContactSpec& contact,
                                const std::function<std::string(std::size_t)>& name);

}  // namespace sflsh::scene::detail
