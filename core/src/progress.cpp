#include <sflsh/core/log.hpp>
#include <sflsh/core/progress.hpp>
#include <sflsh/core/scoped_seconds.hpp>

#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>
#include <string>

namespace sflsh {

Progress::Progress(std::string label, std::size_t total, bool enabled)
    : label_(std::move(label)),
      total_(total),
      enabled_(enabled && logger()->should_log(spdlog::level::info)),
      terminal_(::isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

Progress::~Progress() { finish(); }

void Progress::advance(std::size_t count) {
  done_ += count;
  draw();
}

void Progress::skip(std::size_t count) {
  if (done_ == skipped_) start_ = std::chrono::steady_clock::now();  // the rate starts with the first real item
  done_ += count;
  skipped_ += count;
  draw();
}

void Progress::draw() {
  if (!enabled_ || total_ == 0) return;
  const auto now = std::chrono::steady_clock::now();
  int decile = last_decile_;
  if (terminal_) {
    if (now - last_draw_ < std::chrono::milliseconds(100) && done_ < total_) return;
    last_draw_ = now;
  } else {
    decile = static_cast<int>(10 * done_ / total_);
    if (decile == last_decile_) return;
  }
  last_decile_ = decile;
  const double elapsed = seconds_between(start_, now);
  const std::size_t worked = done_ - skipped_;
  const double rate = elapsed > 0 ? static_cast<double>(worked) / elapsed : 0.0;
  const std::string eta = rate > 0
                              ? fmt::format("{:.0f}s", static_cast<double>(total_ - std::min(done_, total_)) / rate)
                              : std::string(done_ < total_ ? "unknown" : "0s");
  const std::string skipped = skipped_ > 0 ? fmt::format(", {} done earlier", skipped_) : std::string();
  if (terminal_) {
    std::fprintf(stderr, "\r%s %zu/%zu%s  %.1f/s  ETA %s   ", label_.c_str(), done_, total_, skipped.c_str(), rate,
                 eta.c_str());
    std::fflush(stderr);
  } else {
    logger()->info("{} {}/{}{} ({:.1f}/s, ETA {})", label_, done_, total_, skipped, rate, eta);
  }
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  if (enabled_ && terminal_ && total_ > 0) std::fprintf(stderr, "\n");
}

}  // namespace sflsh
