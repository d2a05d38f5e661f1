#pragma once
// Logging goes through one spdlog logger named "sflsh" that the host application may replace
// (apps/sflsh sets level and sinks from --log-level / --quiet). Library code calls sflsh::logger().
#include <spdlog/spdlog.h>

#include <memory>

namespace sflsh {

/// The project logger; created on first use with a stderr sink when the host did not register one.
std::shared_ptr<spdlog::logger> logger();

/// Replaces the project logger (tests and hosts use this to redirect or silence output).
void set_logger(std::shared_ptr<spdlog::logger> logger);

}  // namespace sflsh
