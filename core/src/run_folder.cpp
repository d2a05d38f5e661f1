#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/run_folder.hpp>

#include <unistd.h>

namespace sflsh {

namespace fs = std::filesystem;

RunFolder::RunFolder(fs::path dir) : dir_(std::move(dir)) {
  ensure_directory(dir_);
  staging_ = dir_ / fmt::format(".staging-{}", static_cast<long>(::getpid()));
  std::error_code ec;
  fs::remove_all(staging_, ec);
  ensure_directory(staging_);
}

RunFolder::~RunFolder() {
  std::error_code ec;
  fs::remove_all(staging_, ec);
}

fs::path RunFolder::stage(const std::string& relative) {
  require(!committed_, "{}: run folder already committed", dir_.string());
  const fs::path p = staging_ / relative;
  ensure_directory(p.parent_path());
  files_.push_back(relative);
  return p;
}

void RunFolder::commit() {
  require(!committed_, "{}: run folder already committed", dir_.string());
  for (const std::string& relative : files_) {
    const fs::path from = staging_ / relative;
    if (!fs::exists(from)) continue;  // staged but never written
    const fs::path to = dir_ / relative;
    ensure_directory(to.parent_path());
    std::error_code ec;
    fs::rename(from, to, ec);
    if (ec) throw_error("{}: cannot move into place: {}", to.string(), ec.message());
  }
  committed_ = true;
  std::error_code ec;
  fs::remove_all(staging_, ec);
}

}  // namespace sflsh
