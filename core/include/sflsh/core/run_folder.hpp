#pragma once
// A run folder that appears all at once: files are written into a hidden staging folder inside
// DIR and moved into DIR by commit(). A run that fails (exception, Ctrl-C before commit) leaves DIR
// as it was: no partial frames, no stale summary.json.
#include <filesystem>
#include <string>
#include <vector>

namespace sflsh {

class RunFolder {
 public:
  /// Creates DIR (and parents) and a fresh staging folder inside it.
  explicit RunFolder(std::filesystem::path dir);
  /// Removes the staging folder when commit() was not reached.
  ~RunFolder();
  RunFolder(const RunFolder&) = delete;
  RunFolder& operator=(const RunFolder&) = delete;

  /// Where to write `relative` while the run is in progress (parent folders are created).
  std::filesystem::path stage(const std::string& relative);
  /// Moves every staged file into DIR (replacing files of the same name) and removes the staging folder.
  void commit();
  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
  std::filesystem::path staging_;
  std::vector<std::string> files_;
  bool committed_ = false;
};

}  // namespace sflsh
