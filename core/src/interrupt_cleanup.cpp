// Removal of registered folders on an interrupting signal (interrupt_cleanup.hpp).
//
// The registry is the one piece of process-wide state in core: a signal handler cannot be handed a
// context, so the folders it removes must be reachable from a fixed place. It is a fixed array of slots
// (no allocation, no locks), each with an atomic state, so the handler may run at any moment.
#include <sflsh/core/error.hpp>
#include <sflsh/core/interrupt_cleanup.hpp>

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cstring>

namespace sflsh {

namespace {

constexpr int kSlots = 32;
constexpr std::size_t kPathBytes = 4096;
constexpr std::array<int, 5> kSignals{SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGABRT};

enum SlotState : int { kFree = 0, kFilling = 1, kArmed = 2 };

struct Slot {
  std::atomic<int> state{kFree};
  char path[kPathBytes] = {};
};

Slot g_slots[kSlots];                  // NOLINT: reachable from the signal handler (see the header comment)
std::atomic<bool> g_installed{false};  // NOLINT

/// Removes every entry of the open directory `dir_fd` and, recursively, its subfolders; closes nothing.
bool remove_entries(int dir_fd, int depth) {
  if (depth > 64) return false;
  bool ok = true;
  alignas(8) char buffer[8192];
  for (;;) {
    const long n = ::syscall(SYS_getdents64, dir_fd, buffer, sizeof(buffer));
    if (n <= 0) break;
    bool removed_any = false;
    for (long offset = 0; offset < n;) {
      // struct linux_dirent64: d_ino (8), d_off (8), d_reclen (2), d_type (1), d_name
      unsigned short reclen = 0;
      std::memcpy(&reclen, buffer + offset + 16, sizeof(reclen));
      const unsigned char type = static_cast<unsigned char>(buffer[offset + 18]);
      const char* name = buffer + offset + 19;
      offset += reclen;
      if (std::strcmp(name, ".") == 0 || std::strcmp(name, "..") == 0) continue;
      bool is_dir = type == DT_DIR;
      if (type == DT_UNKNOWN) {
        struct stat st;
        is_dir = ::fstatat(dir_fd, name, &st, AT_SYMLINK_NOFOLLOW) == 0 && S_ISDIR(st.st_mode);
      }
      if (is_dir) {
        const int sub = ::openat(dir_fd, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
        if (sub >= 0) {
          ok = remove_entries(sub, depth + 1) && ok;
          ::close(sub);
        }
        ok = ::unlinkat(dir_fd, name, AT_REMOVEDIR) == 0 && ok;
      } else {
        ok = ::unlinkat(dir_fd, name, 0) == 0 && ok;
      }
      removed_any = true;
    }
    // Entries were removed while reading: start the listing again so none is skipped.
    if (removed_any) ::lseek(dir_fd, 0, SEEK_SET);
  }
  return ok;
}

void on_signal(int signal_number) {
  const int saved_errno = errno;
  for (Slot& slot : g_slots) {
    if (slot.state.load(std::memory_order_acquire) == kArmed) remove_tree_signal_safe(slot.path);
  }
  // Die of the same signal, as the process would have without us.
  struct sigaction dfl;
  std::memset(&dfl, 0, sizeof(dfl));
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  ::sigaction(signal_number, &dfl, nullptr);
  errno = saved_errno;
  ::raise(signal_number);
}

void install_handlers() {
  for (const int s : kSignals) {
    struct sigaction previous;
    if (::sigaction(s, nullptr, &previous) != 0) continue;
    if (previous.sa_handler == SIG_IGN) continue;  // nohup and friends: keep ignoring
    struct sigaction action;
    std::memset(&action, 0, sizeof(action));
    action.sa_handler = on_signal;
    sigemptyset(&action.sa_mask);
    for (const int other : kSignals) sigaddset(&action.sa_mask, other);  // one cleanup at a time
    action.sa_flags = SA_RESTART;
    ::sigaction(s, &action, nullptr);
  }
}

}  // namespace

bool remove_tree_signal_safe(const char* path) {
  const int fd = ::open(path, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) return ::unlink(path) == 0 || errno == ENOENT;
  const bool ok = remove_entries(fd, 0);
  ::close(fd);
  return ::rmdir(path) == 0 && ok;
}

InterruptCleanup::InterruptCleanup(const std::filesystem::path& dir) {
  std::error_code ec;
  const std::string absolute = std::filesystem::absolute(dir, ec).string();
  require(!ec && absolute.size() < kPathBytes, "{}: path too long for the interrupt cleanup", dir.string());
  for (int i = 0; i < kSlots; ++i) {
    int expected = kFree;
    if (!g_slots[i].state.compare_exchange_strong(expected, kFilling, std::memory_order_acq_rel)) continue;
    std::memcpy(g_slots[i].path, absolute.c_str(), absolute.size() + 1);
    g_slots[i].state.store(kArmed, std::memory_order_release);
    slot_ = i;
    break;
  }
  require(slot_ >= 0, "{}: more than {} run folders open at once", dir.string(), kSlots);
  if (!g_installed.exchange(true)) install_handlers();
}

InterruptCleanup::~InterruptCleanup() {
  if (slot_ >= 0) g_slots[slot_].state.store(kFree, std::memory_order_release);
}

void reinstall_interrupt_cleanup() {
  if (g_installed.load()) install_handlers();  // nothing registered yet: the first InterruptCleanup installs them
}

}  // namespace sflsh
