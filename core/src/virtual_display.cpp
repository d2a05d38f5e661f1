// A virtual X display started on demand (virtual_display.hpp).
//
// The display belongs to the process, as $DISPLAY does: it is started once (a function-local static, so
// the start is thread-safe) and stopped by the static's destructor at exit. The Xvfb child asks the
// kernel to stop it when its parent dies (PR_SET_PDEATHSIG), so not even a killed run leaves it behind.
// Xvfb picks a free display number itself and reports it on a pipe (-displayfd).
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/virtual_display.hpp>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <string>

namespace sflsh {

namespace {

class VirtualDisplay {
 public:
  VirtualDisplay() { start(); }
  ~VirtualDisplay() {
    if (pid_ > 0) {
      ::kill(pid_, SIGTERM);
      int status = 0;
      ::waitpid(pid_, &status, 0);
    }
  }
  VirtualDisplay(const VirtualDisplay&) = delete;
  VirtualDisplay& operator=(const VirtualDisplay&) = delete;

  const std::string& error() const { return error_; }

 private:
  void start() {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) {
      error_ = "cannot create a pipe for Xvfb";
      return;
    }
    const pid_t parent = ::getpid();
    pid_ = ::fork();
    if (pid_ < 0) {
      error_ = "cannot start Xvfb (fork failed)";
      return;
    }
    if (pid_ == 0) {
      ::prctl(PR_SET_PDEATHSIG, SIGTERM);
      if (::getppid() != parent) std::_Exit(1);  // the parent died before prctl took effect
      const int null = ::open("/dev/null", O_RDWR);
      if (null >= 0) {
        ::dup2(null, STDIN_FILENO);
        ::dup2(null, STDOUT_FILENO);
        ::dup2(null, STDERR_FILENO);
      }
      ::dup2(fds[1], 3);  // the display number is written to fd 3 (dup2 clears close-on-exec)
      ::execlp("Xvfb", "Xvfb", "-displayfd", "3", "-screen", "0", "1920x1080x24", "-nolisten", "tcp", "-noreset",
               static_cast<char*>(nullptr));
      std::_Exit(127);
    }
    ::close(fds[1]);
    std::string number;
    pollfd p{fds[0], POLLIN, 0};
    for (int waited_ms = 0; waited_ms < 15000 && number.find('\n') == std::string::npos;) {
      const int ready = ::poll(&p, 1, 250);
      waited_ms += 250;
      if (ready <= 0) continue;
      char buffer[32];
      const ssize_t n = ::read(fds[0], buffer, sizeof(buffer));
      if (n <= 0) break;  // Xvfb ended (not installed, or failed)
      number.append(buffer, static_cast<std::size_t>(n));
    }
    ::close(fds[0]);
    while (!number.empty() && (number.back() == '\n' || number.back() == '\r')) number.pop_back();
    if (number.empty() || number.find_first_not_of("0123456789") != std::string::npos) {
      ::kill(pid_, SIGTERM);
      int status = 0;
      ::waitpid(pid_, &status, 0);
      const bool missing = WIFEXITED(status) && WEXITSTATUS(status) == 127;
      pid_ = -1;
      error_ = missing ? "no X display and Xvfb is not installed (apt install xvfb, or run scripts/setup.sh)"
                       : "no X display, and Xvfb did not start";
      return;
    }
    ::setenv("DISPLAY", (":" + number).c_str(), 1);
    logger()->debug("started a virtual display :{} (Xvfb pid {}) for offscreen rendering", number,
                    static_cast<long>(pid_));
  }

  pid_t pid_ = -1;
  std::string error_;
};

}  // namespace

void require_display(std::string_view what) {
  const char* display = std::getenv("DISPLAY");
  if (display != nullptr && *display) return;
  static VirtualDisplay virtual_display;  // NOLINT: the process's display, like $DISPLAY itself
  require(virtual_display.error().empty(), "{}: {}", what, virtual_display.error());
}

}  // namespace sflsh
