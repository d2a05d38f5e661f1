// Runs that are interrupted leave nothing behind (label `fuzz`): SIGTERM and SIGINT during a run remove its
// staging folder and create no output folder; after SIGKILL, which cannot be caught, the next run beside
// it removes the dead run's staging folder.
#include "fuzz_harness.hpp"
#include "scratch_dir.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <thread>

namespace sflsh::testing::fuzz {
namespace {

namespace fs = std::filesystem;

/// Starts sflsh with `args` (stdout and stderr to /dev/null); returns its pid.
pid_t start_sflsh(const std::vector<std::string>& args) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::vector<char*> argv;
    std::string exe = SFLSH_CLI;
    argv.push_back(exe.data());
    std::vector<std::string> copy = args;
    for (std::string& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    std::FILE* null_out = std::freopen("/dev/null", "w", stdout);
    std::FILE* null_err = std::freopen("/dev/null", "w", stderr);
    (void)null_out;
    (void)null_err;
    ::execv(SFLSH_CLI, argv.data());
    std::_Exit(127);
  }
  return pid;
}

/// Waits until `parent` holds a staging folder of `pid` (true) or the process has ended (false).
bool wait_for_staging(const fs::path& parent, pid_t pid) {
  const std::string suffix = fmt::format(".staging-{}", static_cast<long>(pid));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (std::chrono::steady_clock::now() < deadline) {
    std::error_code ec;
    for (fs::directory_iterator it(parent, ec), end; !ec && it != end; it.increment(ec)) {
      const std::string name = it->path().filename().string();
      if (name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
        return true;
    }
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

/// A run long enough to be caught in the middle: the reduced model along 20 s of a motion.
std::vector<std::string> long_run(const fs::path& out) {
  return {"-q",       "simulate", "--solver", "reduced", "--mesh",  "coarse",         "--subject", "OPEN_TRAIN_1",
          "--motion", "dance",    "--frames", "1200",    "--cache", SFLSH_TEST_CACHE, "--out",     out.string()};
}

void interrupt_and_check(int signal_number) {
  const fs::path parent = scratch_dir();
  const fs::path out = parent / "interrupted";
  const pid_t pid = start_sflsh(long_run(out));
  ASSERT_GT(pid, 0);
  ASSERT_TRUE(wait_for_staging(parent, pid)) << "the run ended before its staging folder was seen";
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // let it write a few frames
  ::kill(pid, signal_number);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == signal_number)
      << "the process should die of the signal it got";
  EXPECT_TRUE(leftovers_in(parent).empty()) << leftovers_in(parent).front();
  EXPECT_FALSE(fs::exists(out)) << "an interrupted run created its output folder";
}

TEST(FuzzInterrupt, SigtermLeavesNothing) { interrupt_and_check(SIGTERM); }

TEST(FuzzInterrupt, SigintLeavesNothing) { interrupt_and_check(SIGINT); }

TEST(FuzzInterrupt, StagingOfAKilledRunIsRemovedByTheNextRun) {
  const fs::path parent = scratch_dir();
  const pid_t pid = start_sflsh(long_run(parent / "killed"));
  ASSERT_GT(pid, 0);
  ASSERT_TRUE(wait_for_staging(parent, pid));
  ::kill(pid, SIGKILL);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_FALSE(leftovers_in(parent).empty()) << "SIGKILL cannot be caught: its staging folder should still be there";
  const std::string next =
      fmt::format("{} -q motion export --subject OPEN_TRAIN_1 --motion dance --frames 2 --out '{}' >/dev/null 2>&1",
                  SFLSH_CLI, (parent / "next").string());
  ASSERT_EQ(std::system(next.c_str()), 0);
  EXPECT_TRUE(leftovers_in(parent).empty()) << leftovers_in(parent).front();
  EXPECT_TRUE(fs::exists(parent / "next" / "summary.json"));
}

}  // namespace
}  // namespace sflsh::testing::fuzz
