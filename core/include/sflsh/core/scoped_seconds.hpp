#pragma once
// Wall time: `seconds_since(t0)` [s], and a scope's wall time added to a counter (`const ScopedSeconds
// timer(total);` adds the seconds until the end of the scope to `total` [s]).
#include <chrono>

namespace sflsh {

/// Seconds of wall time since t0 (steady clock) [s].
inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

class ScopedSeconds {
 public:
  explicit ScopedSeconds(double& total) : total_(total), start_(std::chrono::steady_clock::now()) {}
  ~ScopedSeconds() { total_ += seconds_since(start_); }
  ScopedSeconds(const ScopedSeconds&) = delete;
  ScopedSeconds& operator=(const ScopedSeconds&) = delete;

 private:
  double& total_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace sflsh
