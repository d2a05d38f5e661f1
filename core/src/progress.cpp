#include <sflsh/core/log.hpp>
#include <sflsh/core/progress.hpp>

#include <unistd.h>

#include <cstdio>

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
  if (!enabled_ || total_ == 0) return;
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double rate = elapsed > 0 ? static_cast<double>(done_) / elapsed : 0.0;
  const double eta = rate > 0 ? static_cast<double>(total_ - std::min(done_, total_)) / rate : 0.0;
  if (terminal_) {
    if (now - last_draw_ < std::chrono::milliseconds(100) && done_ < total_) return;
    last_draw_ = now;
    std::fprintf(stderr, "\r%s %zu/%zu  %.1f/s  ETA %.0fs   ", label_.c_str(), done_, total_, rate, eta);
    std::fflush(stderr);
  } else {
    const int decile = static_cast<int>(10 * done_ / total_);
    if (decile != last_decile_) {
      last_decile_ = decile;
      logger()->info("{} {}/{} ({:.1f}/s, ETA {:.0f}s)", label_, done_, total_, rate, eta);
    }
  }
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  if (enabled_ && terminal_ && total_ > 0) std::fprintf(stderr, "\n");
}

}  // namespace sflsh
