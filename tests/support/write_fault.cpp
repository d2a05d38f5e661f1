// Fault injection for tests/cli/test_cli_write_errors.cpp, preloaded into sflsh (LD_PRELOAD): writes to files opened
// for writing under $SFLSH_FAULT_DIR fail with errno $SFLSH_FAULT_ERRNO (a number; default EIO) once more than
// $SFLSH_FAULT_AFTER bytes (default 0) went to such files; fsync on them fails from then on too. This is what a quota
// (EDQUOT) or a failing disk (EIO) answers, where neither can be made in a test: the kernel's errno reaches sflsh
// through the same calls (open/write/pwrite/fsync of core/src/atomic_file.cpp and HDF5's POSIX driver, fwrite of
// libzip).
//
// The interposed functions are C functions the dynamic linker resolves by name, so their state is file-scope: one
// table of the tracked descriptors and one byte counter (atomics: the frame writer runs on its own thread).
#include <dlfcn.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/uio.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

constexpr int kMaxDescriptor = 1 << 16;
std::array<std::atomic<bool>, kMaxDescriptor> tracked_descriptor{};
std::atomic<long long> bytes_written{0};

const char* fault_dir() {
  static const char* dir = std::getenv("SFLSH_FAULT_DIR");
  return dir;
}

int fault_errno() {
  static const int code = [] {
    const char* text = std::getenv("SFLSH_FAULT_ERRNO");
    return text && *text ? std::atoi(text) : EIO;
  }();
  return code;
}

long long fault_after() {
  static const long long after = [] {
    const char* text = std::getenv("SFLSH_FAULT_AFTER");
    return text && *text ? std::atoll(text) : 0LL;
  }();
  return after;
}

/// Whether `path` (relative to `dir_fd`) lies under $SFLSH_FAULT_DIR.
bool under_fault_dir(int dir_fd, const char* path) {
  const char* dir = fault_dir();
  if (!dir || !*dir || !path) return false;
  std::string full;
  if (path[0] == '/') {
    full = path;
  } else {
    char base[4096];
    if (dir_fd == AT_FDCWD) {
      if (!::getcwd(base, sizeof base)) return false;
    } else {
      const std::string link = "/proc/self/fd/" + std::to_string(dir_fd);
      const ssize_t n = ::readlink(link.c_str(), base, sizeof base - 1);
      if (n <= 0) return false;
      base[n] = '\0';
    }
    full = std::string(base) + "/" + path;
  }
  const std::size_t length = std::strlen(dir);
  return full.compare(0, length, dir) == 0 && (full.size() == length || full[length] == '/');
}

void track(int fd, bool writes_under_fault_dir) {
  if (fd >= 0 && fd < kMaxDescriptor) tracked_descriptor[static_cast<std::size_t>(fd)] = writes_under_fault_dir;
}

bool tracked(int fd) { return fd >= 0 && fd < kMaxDescriptor && tracked_descriptor[static_cast<std::size_t>(fd)]; }

/// Counts `count` bytes towards the limit; true when the write must fail.
bool fails(int fd, std::size_t count) {
  if (!tracked(fd)) return false;
  return bytes_written.fetch_add(static_cast<long long>(count)) + static_cast<long long>(count) > fault_after();
}

template <class Function>
Function next(const char* name) {
  return reinterpret_cast<Function>(::dlsym(RTLD_NEXT, name));
}

bool writes(int flags) { return (flags & O_ACCMODE) != O_RDONLY; }

mode_t mode_argument(int flags, va_list args) {
  return (flags & O_CREAT) || (flags & O_TMPFILE) == O_TMPFILE ? static_cast<mode_t>(va_arg(args, int)) : 0;
}

}  // namespace

extern "C" {

int open(const char* path, int flags, ...) {
  va_list args;
  va_start(args, flags);
  const mode_t mode = mode_argument(flags, args);
  va_end(args);
  static const auto real = next<int (*)(const char*, int, ...)>("open");
  const int fd = real(path, flags, mode);
  track(fd, writes(flags) && under_fault_dir(AT_FDCWD, path));
  return fd;
}

int open64(const char* path, int flags, ...) {
  va_list args;
  va_start(args, flags);
  const mode_t mode = mode_argument(flags, args);
  va_end(args);
  static const auto real = next<int (*)(const char*, int, ...)>("open64");
  const int fd = real(path, flags, mode);
  track(fd, writes(flags) && under_fault_dir(AT_FDCWD, path));
  return fd;
}

int openat(int dir_fd, const char* path, int flags, ...) {
  va_list args;
  va_start(args, flags);
  const mode_t mode = mode_argument(flags, args);
  va_end(args);
  static const auto real = next<int (*)(int, const char*, int, ...)>("openat");
  const int fd = real(dir_fd, path, flags, mode);
  track(fd, writes(flags) && under_fault_dir(dir_fd, path));
  return fd;
}

int openat64(int dir_fd, const char* path, int flags, ...) {
  va_list args;
  va_start(args, flags);
  const mode_t mode = mode_argument(flags, args);
  va_end(args);
  static const auto real = next<int (*)(int, const char*, int, ...)>("openat64");
  const int fd = real(dir_fd, path, flags, mode);
  track(fd, writes(flags) && under_fault_dir(dir_fd, path));
  return fd;
}

int close(int fd) {
  static const auto real = next<int (*)(int)>("close");
  track(fd, false);
  return real(fd);
}

ssize_t write(int fd, const void* data, size_t count) {
  static const auto real = next<ssize_t (*)(int, const void*, size_t)>("write");
  if (fails(fd, count)) {
    errno = fault_errno();
    return -1;
  }
  return real(fd, data, count);
}

ssize_t pwrite(int fd, const void* data, size_t count, off_t offset) {
  static const auto real = next<ssize_t (*)(int, const void*, size_t, off_t)>("pwrite");
  if (fails(fd, count)) {
    errno = fault_errno();
    return -1;
  }
  return real(fd, data, count, offset);
}

ssize_t pwrite64(int fd, const void* data, size_t count, off64_t offset) {
  static const auto real = next<ssize_t (*)(int, const void*, size_t, off64_t)>("pwrite64");
  if (fails(fd, count)) {
    errno = fault_errno();
    return -1;
  }
  return real(fd, data, count, offset);
}

ssize_t writev(int fd, const struct iovec* vectors, int count) {
  static const auto real = next<ssize_t (*)(int, const struct iovec*, int)>("writev");
  std::size_t total = 0;
  for (int i = 0; i < count; ++i) total += vectors[i].iov_len;
  if (fails(fd, total)) {
    errno = fault_errno();
    return -1;
  }
  return real(fd, vectors, count);
}

// stdio, which libzip writes its archives through (fdopen on a descriptor it opened, then fwrite): stdio's own
// writes do not come back through write(), so fwrite is answered here.
FILE* fopen(const char* path, const char* mode) {
  static const auto real = next<FILE* (*)(const char*, const char*)>("fopen");
  FILE* file = real(path, mode);
  if (file) track(::fileno(file), std::strpbrk(mode, "wa+") != nullptr && under_fault_dir(AT_FDCWD, path));
  return file;
}

FILE* fopen64(const char* path, const char* mode) {
  static const auto real = next<FILE* (*)(const char*, const char*)>("fopen64");
  FILE* file = real(path, mode);
  if (file) track(::fileno(file), std::strpbrk(mode, "wa+") != nullptr && under_fault_dir(AT_FDCWD, path));
  return file;
}

size_t fwrite(const void* data, size_t size, size_t count, FILE* file) {
  static const auto real = next<size_t (*)(const void*, size_t, size_t, FILE*)>("fwrite");
  if (file && fails(::fileno(file), size * count)) {
    errno = fault_errno();
    return 0;
  }
  return real(data, size, count, file);
}

int fclose(FILE* file) {
  static const auto real = next<int (*)(FILE*)>("fclose");
  if (file) track(::fileno(file), false);
  return real(file);
}

int fsync(int fd) {
  static const auto real = next<int (*)(int)>("fsync");
  if (tracked(fd) && bytes_written.load() > fault_after()) {
    errno = fault_errno();
    return -1;
  }
  return real(fd);
}

}  // extern "C"
