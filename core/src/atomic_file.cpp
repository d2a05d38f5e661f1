#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/error.hpp>

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <system_error>

namespace sflsh {

namespace fs = std::filesystem;

fs::path temporary_sibling(const fs::path& target) {
  static std::atomic<unsigned long> counter{0};
  return target.parent_path() /
         fmt::format(".{}.tmp-{}-{}", target.filename().string(), static_cast<long>(::getpid()), counter.fetch_add(1));
}

void write_atomically(const fs::path& target, const std::function<void(const fs::path&)>& write) {
  const fs::path tmp = temporary_sibling(target);
  try {
    write(tmp);
    if (!fs::exists(tmp)) throw_error("{}: writer produced no file", target.string());
    std::error_code ec;
    fs::rename(tmp, target, ec);
    if (ec) throw_error("{}: cannot move finished file into place ({})", target.string(), ec.message());
  } catch (...) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw;
  }
}

int remove_stale_temporaries(const fs::path& target) {
  const std::string prefix = fmt::format(".{}.tmp-", target.filename().string());  // as temporary_sibling names them
  std::error_code ec;
  int removed = 0;
  for (fs::directory_iterator it(target.parent_path().empty() ? "." : target.parent_path(), ec), end; !ec && it != end;
       it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (!name.starts_with(prefix)) continue;
    const std::string rest = name.substr(prefix.size());  // "<pid>-<n>[.XXXXXX]"
    long pid = 0;
    try {
      pid = std::stol(rest.substr(0, rest.find('-')));
    } catch (const std::exception&) {
      continue;  // not one of ours
    }
    if (pid <= 0 || (::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH)) {
      std::error_code ignored;
      if (fs::remove(it->path(), ignored)) ++removed;
    }
  }
  return removed;
}

void throw_write_error(const fs::path& target, std::string_view what, int error_number) {
  throw_error("{}: {} ({})", target.string(), what, std::strerror(error_number));
}

void write_file_checked(const fs::path& file, const fs::path& target, std::string_view contents) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw_write_error(target, "cannot create file", errno);
  // The blocks reserved before the first byte: a full disk or an exhausted quota is reported here, not later by
  // delayed allocation. Where the file system cannot reserve (EOPNOTSUPP: e.g. NFSv3), fsync after the writes.
  // A reservation instead of an fsync per file: 11 against 3 ms per 1.6 MB frame file on this machine's ext4, which
  // made fsync three quarters of the crowd's writer time (docs/output.md).
  bool reserved = contents.empty();
  if (!reserved) {
    int r = 0;
    do r = ::fallocate(fd, 0, 0, static_cast<off_t>(contents.size()));
    while (r != 0 && errno == EINTR);
    if (r != 0 && errno != EOPNOTSUPP && errno != ENOSYS) {
      const int e = errno;
      ::close(fd);
      throw_write_error(target, "write failed", e);
    }
    reserved = r == 0;
  }
  const char* data = contents.data();
  std::size_t left = contents.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, data, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int e = n < 0 ? errno : ENOSPC;
      ::close(fd);
      throw_write_error(target, "write failed", e);
    }
    data += n;
    left -= static_cast<std::size_t>(n);
  }
  // Without a reservation, delayed allocation (and NFS) can report a full disk only at fsync or close.
  if (!reserved && ::fsync(fd) != 0 && errno != EINVAL && errno != EROFS) {
    const int e = errno;
    ::close(fd);
    throw_write_error(target, "write failed", e);
  }
  if (::close(fd) != 0) throw_write_error(target, "write failed", errno);
}

void write_text_atomically(const fs::path& target, std::string_view contents) {
  write_atomically(target, [&](const fs::path& tmp) { write_file_checked(tmp, target, contents); });
}

void ensure_directory(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) {
    throw_error("{}: cannot create output directory ({})", dir.string(),
                ec ? ec.message() : std::string("a file is in the way"));
  }
}

}  // namespace sflsh
