#pragma once
// Progress of long loops: a live "label k/n · rate · ETA" line on a terminal, plain log lines
// (every ~10%) when stderr is not a terminal. Hand-written: Debian 12 packages no C++ progress-bar
// library (indicators, tqdm-cpp and the like are absent), and this needs ~60 lines.
#include <chrono>
#include <cstddef>
#include <string>

namespace sflsh {

class Progress {
 public:
  Progress(std::string label, std::size_t total, bool enabled = true);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  /// Marks `count` more items done (call from one thread).
  void advance(std::size_t count = 1);
  /// Marks `count` items done that took no work (e.g. read back from a checkpoint): they count toward k/n but
  /// not toward the rate, so a resumed loop's ETA comes from the items it runs.
  void skip(std::size_t count = 1);
  /// Ends the line (called by the destructor too).
  void finish();

 private:
  std::string label_;
  std::size_t total_ = 0;
  std::size_t done_ = 0;
  std::size_t skipped_ = 0;
  bool enabled_ = true;
  bool terminal_ = false;
  bool finished_ = false;
  int last_decile_ = -1;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;

  void draw();
};

}  // namespace sflsh
