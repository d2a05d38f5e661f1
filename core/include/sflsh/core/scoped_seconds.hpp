#pragma once
// Wall time: `seconds_since(t0)` and `seconds_between(t0, t1)` [s], and a scope's wall time added to a counter (`const
// ScopedSeconds timer(total);` adds the seconds until the end of the scope to `total` [s]).
#include <chrono>

namespace sflsh {

/// Seconds of wall time from t0 to t1 (steady clock) [s].
inline double seconds_between(std::chrono::steady_clock::time_point t0, std::chrono::steady_clock::time_point t1) {
  return std::chrono::duration<double>(t1 - t0).count();
}

/// Seconds of wall time since t0 (steady clock) [s].
inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return seconds_between(t0, std::chrono::steady_clock::now());
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
