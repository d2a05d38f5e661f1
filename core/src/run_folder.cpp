#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/run_folder.hpp>

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>

namespace sflsh {

namespace fs = std::filesystem;

namespace {

/// DIR without a trailing separator, so that its name and parent are what the user meant.
fs::path normalized_folder(const fs::path& dir) {
  require(!dir.empty(), "--out: an output folder is required");
  fs::path p = dir.lexically_normal();
  if (p.filename().empty()) p = p.parent_path();  // "out/run/" → "out/run"
  if (p.empty() || p.filename() == "." || p.filename() == "..")
    p = fs::absolute(p.empty() ? fs::path(".") : p).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();  // "/home/me/" → "/home/me"
  require(!p.filename().empty() && p != p.root_path(), "{}: cannot be used as a run folder (expected a folder name)",
          dir.string());
  return p;  // relative names stay relative ("run" lives in ".")
}

/// The pid in a staging folder's name (`….staging-<pid>`), or 0.
long staging_pid(const std::string& name) {
  const auto at = name.rfind(".staging-");
  if (at == std::string::npos || (at != 0 && name[0] != '.')) return 0;
  const std::string digits = name.substr(at + 9);
  if (digits.empty() || digits.size() > 10 || digits.find_first_not_of("0123456789") != std::string::npos) return 0;
  return std::strtol(digits.c_str(), nullptr, 10);
}

bool process_is_gone(long pid) { return pid > 0 && ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH; }

int remove_stale_in(const fs::path& folder) {
  int removed = 0;
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (!it->is_directory(ec) || !process_is_gone(staging_pid(name))) continue;
    std::error_code remove_ec;
    fs::remove_all(it->path(), remove_ec);
    if (!remove_ec) {
      ++removed;
      logger()->info("removed the staging folder {} of a run that did not finish", it->path().string());
    }
  }
  return removed;
}

}  // namespace

int remove_stale_staging(const fs::path& parent) { return remove_stale_in(parent); }

RunFolder::RunFolder(fs::path dir) : dir_(normalized_folder(dir)) {
  std::error_code ec;
  if (fs::exists(dir_, ec) && !fs::is_directory(dir_, ec))
    throw_error("{}: exists and is not a folder (expected an output folder)", dir_.string());
  const fs::path parent = dir_.has_parent_path() ? dir_.parent_path() : fs::path(".");
  for (fs::path p = parent; !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    created_parents_.push_back(p);
    if (p == p.parent_path()) break;
  }
  ensure_directory(parent);
  remove_stale_in(parent);
  if (fs::is_directory(dir_, ec)) remove_stale_in(dir_);  // the older layout: DIR/.staging-<pid>
  staging_ = parent / fmt::format(".{}.staging-{}", dir_.filename().string(), static_cast<long>(::getpid()));
  fs::remove_all(staging_, ec);
  fs::create_directory(staging_, ec);
  if (ec || !fs::is_directory(staging_))
    throw_error("{}: cannot create the staging folder {} ({})", dir_.string(), staging_.string(),
                ec ? ec.message() : std::string("unknown error"));
  interrupt_cleanup_ = std::make_unique<InterruptCleanup>(staging_);
}

RunFolder::~RunFolder() {
  interrupt_cleanup_.reset();
  std::error_code ec;
  fs::remove_all(staging_, ec);
  if (committed_) return;
  for (const fs::path& p : created_parents_) {  // innermost first; only folders still empty
    if (!fs::is_empty(p, ec) || ec) break;
    fs::remove(p, ec);
  }
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
  std::error_code ec;
  if (!fs::exists(dir_, ec)) {
    // The whole folder appears with one rename.
    fs::rename(staging_, dir_, ec);
    if (!ec) {
      committed_ = true;
      return;
    }
  }
  for (const std::string& relative : files_) {
    const fs::path from = staging_ / relative;
    if (!fs::exists(from)) continue;  // staged but never written
    const fs::path to = dir_ / relative;
    ensure_directory(to.parent_path());
    std::error_code move_ec;
    fs::rename(from, to, move_ec);
    if (move_ec) throw_error("{}: cannot move into place: {}", to.string(), move_ec.message());
  }
  committed_ = true;
  fs::remove_all(staging_, ec);
}

}  // namespace sflsh
