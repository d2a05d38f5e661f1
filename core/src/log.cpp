#include <sflsh/core/log.hpp>

#include <spdlog/sinks/stdout_color_sinks.h>

namespace sflsh {

std::shared_ptr<spdlog::logger> logger() {
  if (auto existing = spdlog::get("sflsh")) return existing;
  auto created = spdlog::stderr_color_mt("sflsh");
  created->set_pattern("[%H:%M:%S.%e] [%^%l%$] %v");
  return created;
}

void set_logger(std::shared_ptr<spdlog::logger> replacement) {
  spdlog::drop("sflsh");
  if (replacement) spdlog::register_logger(std::move(replacement));
}

}  // namespace sflsh
