#pragma once
// Folders removed when the process is interrupted: a run's staging folder must not outlive a Ctrl-C, a
// `kill` or a closed terminal. While an InterruptCleanup is alive, SIGINT, SIGTERM, SIGHUP, SIGQUIT and
// SIGABRT remove its folder (with async-signal-safe system calls only) and the process then dies of the
// same signal as it would have. SIGKILL cannot be caught: RunFolder removes the staging folders of dead
// processes on its next start instead. Signals the process ignores (nohup) stay ignored.
#include <filesystem>

namespace sflsh {

class InterruptCleanup {
 public:
  /// Registers `dir` (absolute or relative to the current directory at construction) for removal on a signal.
  explicit InterruptCleanup(const std::filesystem::path& dir);
  /// Unregisters the folder (it is not removed: the owner decides).
  ~InterruptCleanup();
  InterruptCleanup(const InterruptCleanup&) = delete;
  InterruptCleanup& operator=(const InterruptCleanup&) = delete;

 private:
  int slot_ = -1;
};

/// Installs the handlers again, on top of handlers a library installed since (PETSc installs its own for
/// SIGTERM and SIGHUP when it initializes). Called by the code that initializes such libraries; does nothing
/// before the first InterruptCleanup.
void reinstall_interrupt_cleanup();

/// Removes a folder tree with system calls that are safe inside a signal handler (openat, getdents64,
/// unlinkat). Returns false when something could not be removed. Usable outside handlers too.
bool remove_tree_signal_safe(const char* path);

}  // namespace sflsh
