#pragma once
// A run folder that appears all at once. Files are written into a hidden staging folder beside DIR
// (`<parent>/.<name>.staging-<pid>`, on the same file system, never inside the user's folder) and moved
// into DIR by commit(); when DIR did not exist, the staging folder simply becomes DIR. A run that fails
// (exception) or is interrupted (SIGINT, SIGTERM, SIGHUP: interrupt_cleanup.hpp) leaves DIR as it was:
// no partial frames, no stale summary.json, no empty folder it created. A staging folder whose process
// died without cleaning up (SIGKILL, power loss) is removed by the next RunFolder opened beside it.
#include <sflsh/core/interrupt_cleanup.hpp>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace sflsh {

class RunFolder {
 public:
  /// Prepares DIR's staging folder (creating DIR's missing parents, not DIR). Throws sflsh::Error naming
  /// the path when DIR is a file or its parent cannot be written.
  explicit RunFolder(std::filesystem::path dir);
  /// Removes the staging folder, and the parents it created, when commit() was not reached.
  ~RunFolder();
  RunFolder(const RunFolder&) = delete;
  RunFolder& operator=(const RunFolder&) = delete;

  /// Where to write `relative` while the run is in progress (parent folders are created).
  std::filesystem::path stage(const std::string& relative);
  /// Moves every staged file into DIR (replacing files of the same name) and removes the staging folder.
  void commit();
  const std::filesystem::path& dir() const { return dir_; }
  const std::filesystem::path& staging() const { return staging_; }

 private:
  std::filesystem::path dir_;
  std::filesystem::path staging_;
  std::vector<std::filesystem::path> created_parents_;  ///< innermost first
  std::vector<std::string> files_;
  std::unique_ptr<InterruptCleanup> interrupt_cleanup_;
  bool committed_ = false;
};

/// Removes the staging folders (`.<name>.staging-<pid>`, and the older `DIR/.staging-<pid>` layout) in
/// `parent` whose process no longer runs; returns how many were removed.
int remove_stale_staging(const std::filesystem::path& parent);

}  // namespace sflsh
