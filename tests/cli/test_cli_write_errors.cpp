// Write errors (issue 45): a full file system, a file size limit, an I/O error and a quota while sflsh writes a run
// folder, a scene, a layer mesh and its cache. Each is one line `sflsh: error: <path>: <what> (<strerror>)`, exit code
// 1, no signal, and nothing left behind (no staging folder, no temporary or partial file).
#include "run_command.hpp"
#include "scratch_dir.hpp"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace sflsh {

using sflsh::testing::count_entries;
using sflsh::testing::run_sflsh;
using ::testing::EndsWith;
using ::testing::HasSubstr;
using ::testing::StartsWith;

namespace {

/// A tmpfs of `size` mounted on a fresh folder (with mount `flags`, e.g. MS_RDONLY), unmounted at the end; not
/// mounted when mounting is not permitted.
class SmallFileSystem {
 public:
  SmallFileSystem(const std::filesystem::path& at, const std::string& size, unsigned long flags = 0) : at_(at) {
    std::filesystem::create_directories(at_);
    mounted_ = ::mount("tmpfs", at_.c_str(), "tmpfs", flags, ("size=" + size).c_str()) == 0;
  }
  ~SmallFileSystem() {
    if (mounted_) ::umount2(at_.c_str(), MNT_DETACH);
  }
  SmallFileSystem(const SmallFileSystem&) = delete;
  SmallFileSystem& operator=(const SmallFileSystem&) = delete;
  bool mounted() const { return mounted_; }
  const std::filesystem::path& path() const { return at_; }

 private:
  std::filesystem::path at_;
  bool mounted_ = false;
};

/// Runs sflsh in a forked child after `prepare()` ran there (limits, signals, environment).
template <class Prepare>
sflsh::testing::CommandResult run_sflsh_prepared(const std::string& args, const std::filesystem::path& scratch,
                                                 const Prepare& prepare) {
  const auto out_file = scratch / "cmd.stdout";
  const auto err_file = scratch / "cmd.stderr";
  const std::string command =
      std::string(SFLSH_CLI) + " " + args + " >" + out_file.string() + " 2>" + err_file.string();
  const pid_t pid = ::fork();
  if (pid == 0) {
    prepare();
    ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  sflsh::testing::CommandResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.out = sflsh::testing::text_of(out_file);
  result.err = sflsh::testing::text_of(err_file);
  std::filesystem::remove(out_file);
  std::filesystem::remove(err_file);
  return result;
}

/// Runs sflsh with RLIMIT_FSIZE = `limit_bytes` and SIGXFSZ ignored in the child (so write() returns EFBIG).
sflsh::testing::CommandResult run_sflsh_with_file_size_limit(const std::string& args,
                                                             const std::filesystem::path& scratch, rlim_t limit_bytes) {
  return run_sflsh_prepared(args, scratch, [limit_bytes] {
    std::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{limit_bytes, limit_bytes};
    ::setrlimit(RLIMIT_FSIZE, &limit);
  });
}

/// Runs sflsh with tests/support/write_fault.cpp preloaded: writes to files under `folder` fail with `error` once
/// more than `after_bytes` went there.
sflsh::testing::CommandResult run_sflsh_with_write_fault(const std::string& args, const std::filesystem::path& scratch,
                                                         const std::filesystem::path& folder, int error,
                                                         long long after_bytes) {
  const std::filesystem::path shim =
      std::filesystem::path(SFLSH_TEST_CACHE).parent_path() / "tests" / "libsflsh_write_fault.so";
  EXPECT_TRUE(std::filesystem::exists(shim)) << shim;
  const std::string dir = std::filesystem::absolute(folder).string();
  const std::string code = std::to_string(error);
  const std::string after = std::to_string(after_bytes);
  return run_sflsh_prepared(args, scratch, [&] {
    ::setenv("LD_PRELOAD", shim.c_str(), 1);
    ::setenv("SFLSH_FAULT_DIR", dir.c_str(), 1);
    ::setenv("SFLSH_FAULT_ERRNO", code.c_str(), 1);
    ::setenv("SFLSH_FAULT_AFTER", after.c_str(), 1);
  });
}

/// One line `sflsh: error: <path under folder>…: … (<reason>)`, exit code 1.
void expect_one_line_write_error(const sflsh::testing::CommandResult& r, const std::filesystem::path& folder,
                                 const std::string& reason) {
  EXPECT_EQ(r.exit_code, 1) << r.err;
  ASSERT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  const std::string line = r.err.substr(0, r.err.size() - 1);
  EXPECT_THAT(line, StartsWith("sflsh: error: " + folder.string() + "/")) << r.err;
  EXPECT_THAT(line, EndsWith("(" + reason + ")")) << r.err;
}

std::string reduced_run(const std::filesystem::path& out, int frames = 30) {
  return fmt::format(
      "-q simulate --solver reduced --mesh coarse --subject OPEN_TRAIN_1 --motion one_leg_jump "
      "--frames {} --out {}",
      frames, out.string());
}

/// Regular files below `folder` (folders not counted).
std::size_t count_files(const std::filesystem::path& folder) {
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(folder)) files += entry.is_regular_file();
  return files;
}

}  // namespace

TEST(CliWriteErrors, ReducedRunOnAFullDisk) {
  const auto dir = sflsh::testing::scratch_dir();
  SmallFileSystem fs(dir / "small", "2m");
  if (!fs.mounted()) GTEST_SKIP() << "mounting a tmpfs is not permitted here (needs root)";
  for (const char* format : {"vtk", "xdmf"}) {
    SCOPED_TRACE(format);
    const auto r = run_sflsh(reduced_run(fs.path() / "run") + " --format " + format, dir);
    expect_one_line_write_error(r, fs.path(), "No space left on device");
    EXPECT_EQ(count_entries(fs.path()), 0u) << "a staging folder or partial file was left behind";
  }
}

TEST(CliWriteErrors, FullSpaceRunOnAFullDisk) {
  const auto dir = sflsh::testing::scratch_dir();
  SmallFileSystem fs(dir / "small", "2m");
  if (!fs.mounted()) GTEST_SKIP() << "mounting a tmpfs is not permitted here (needs root)";
  const auto r = run_sflsh(fmt::format("-q simulate --solver full --mesh coarse --subject OPEN_TRAIN_1 --motion "
                                       "one_leg_jump --frames 30 --out {}",
                                       (fs.path() / "run").string()),
                           dir);
  expect_one_line_write_error(r, fs.path(), "No space left on device");
  EXPECT_EQ(count_entries(fs.path()), 0u);
}

TEST(CliWriteErrors, SceneOnAFullDisk) {
  const auto dir = sflsh::testing::scratch_dir();
  SmallFileSystem fs(dir / "small", "2m");
  if (!fs.mounted()) GTEST_SKIP() << "mounting a tmpfs is not permitted here (needs root)";
  const auto r = run_sflsh(fmt::format("-q simulate --scene {}/scenes/belly_press.toml --frames 10 --out {}",
                                       SFLSH_DATA_DIR, (fs.path() / "scene").string()),
                           dir);
  expect_one_line_write_error(r, fs.path(), "No space left on device");
  EXPECT_EQ(count_entries(fs.path()), 0u);
}

TEST(CliWriteErrors, MeshAndItsCacheOnAFullDisk) {
  const auto dir = sflsh::testing::scratch_dir();
  {  // the layer files: the cache (in the build tree) is read, the run folder does not fit
    SmallFileSystem fs(dir / "small", "256k");
    if (!fs.mounted()) GTEST_SKIP() << "mounting a tmpfs is not permitted here (needs root)";
    const auto r =
        run_sflsh(fmt::format("-q mesh --subject OPEN_TEST_3 --mesher gmsh --mesh coarse --cache {} --out {}",
                              SFLSH_TEST_CACHE, (fs.path() / "layer").string()),
                  dir);
    expect_one_line_write_error(r, fs.path(), "No space left on device");
    EXPECT_EQ(count_entries(fs.path()), 0u);
  }
  {  // the cache itself does not fit
    SmallFileSystem fs(dir / "tiny", "64k");
    ASSERT_TRUE(fs.mounted());
    const auto r =
        run_sflsh(fmt::format("-q mesh --subject OPEN_TEST_3 --mesher layered --mesh coarse --cache {} --out {}",
                              (fs.path() / "cache").string(), (dir / "layer").string()),
                  dir);
    expect_one_line_write_error(r, fs.path() / "cache", "No space left on device");
    EXPECT_EQ(count_entries(fs.path() / "cache"), 0u) << "a partial cache entry was left behind";
    EXPECT_FALSE(std::filesystem::exists(dir / "layer"));
  }
}

TEST(CliWriteErrors, ReadOnlyFolderForARunARenderAndACache) {
  const auto dir = sflsh::testing::scratch_dir();
  SmallFileSystem fs(dir / "ro", "1m", MS_RDONLY);
  if (!fs.mounted()) GTEST_SKIP() << "mounting a tmpfs is not permitted here (needs root)";
  const std::string reason = "Read-only file system";
  expect_one_line_write_error(run_sflsh(reduced_run(fs.path() / "run", 5), dir), fs.path(), reason);
  expect_one_line_write_error(
      run_sflsh(fmt::format("-q mesh --subject OPEN_TEST_3 --mesher layered --mesh coarse --cache {} --out {}",
                            (fs.path() / "cache").string(), (dir / "layer").string()),
                dir),
      fs.path(), reason);
  EXPECT_FALSE(std::filesystem::exists(dir / "layer"));
  const auto run = run_sflsh(reduced_run(dir / "run", 5), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  expect_one_line_write_error(
      run_sflsh(fmt::format("-q render --run {} --out {}", (dir / "run").string(), (fs.path() / "pic.png").string()),
                dir),
      fs.path(), reason);
}

TEST(CliWriteErrors, RenderedPictureOnAFullDisk) {
  const auto dir = sflsh::testing::scratch_dir();
  SmallFileSystem fs(dir / "tiny", "64k");  // the picture takes ~110 kB
  if (!fs.mounted()) GTEST_SKIP() << "mounting a tmpfs is not permitted here (needs root)";
  const auto run = run_sflsh(reduced_run(dir / "run", 5), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto r = run_sflsh(
      fmt::format("-q render --run {} --out {}", (dir / "run").string(), (fs.path() / "pic.png").string()), dir);
  expect_one_line_write_error(r, fs.path(), "No space left on device");
  EXPECT_EQ(count_entries(fs.path()), 0u) << "a partial picture was left behind";
}

TEST(CliWriteErrors, ValidateCheckpointOnAFullDisk) {
  const auto dir = sflsh::testing::scratch_dir();
  SmallFileSystem fs(dir / "tiny", "64k");  // the first ground-truth checkpoint takes more than 700 kB
  if (!fs.mounted()) GTEST_SKIP() << "mounting a tmpfs is not permitted here (needs root)";
  const auto r = run_sflsh(fmt::format("-q validate --train-subjects OPEN_TRAIN_1,OPEN_TRAIN_2 --test-subjects "
                                       "OPEN_TEST_1 --frames 10 --stages 1 --iterations 2 --lambdas 1 "
                                       "--no-cross-validation --threads 1 --mesh coarse --out {}",
                                       (fs.path() / "v").string()),
                           dir);
  expect_one_line_write_error(r, fs.path(), "No space left on device");
  EXPECT_THAT(r.err, HasSubstr("/state/"));
  // The resumable state folder may stay (an interrupted run resumes from it), but holds no partial checkpoint.
  EXPECT_EQ(count_files(fs.path()), 0u) << "a partial checkpoint was left behind";
}

TEST(CliWriteErrors, FileSizeLimitInVtkAndHdf5Output) {
  const auto dir = sflsh::testing::scratch_dir();
  // 4 MiB: MPI starts (its shared-memory files fit), a 60-frame uncompressed body.h5 does not.
  const auto xdmf = run_sflsh_with_file_size_limit(reduced_run(dir / "xdmf", 60) + " --format xdmf --compression none",
                                                   dir, 4u << 20);
  expect_one_line_write_error(xdmf, dir, "File too large");
  EXPECT_THAT(xdmf.err, HasSubstr("body.h5"));
  EXPECT_FALSE(std::filesystem::exists(dir / "xdmf"));
}

// An I/O error and an exhausted quota, which no test machine gives on demand: the preloaded shim answers sflsh's
// writes under one folder with EIO or EDQUOT after the first megabyte (a frame or two in: the background writer's
// files) or at once (the cache entry). The same one line, exit code 1, nothing left behind.
TEST(CliWriteErrors, IoErrorAndQuotaInARunAndACache) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "a preloaded library cannot come before AddressSanitizer's runtime";
#endif
  const auto dir = sflsh::testing::scratch_dir();
  const auto faulty = dir / "faulty";
  std::filesystem::create_directories(faulty);
  struct Case {
    int error;
    const char* reason;
  };
  for (const Case c : {Case{EIO, "Input/output error"}, Case{EDQUOT, "Disk quota exceeded"}}) {
    SCOPED_TRACE(c.reason);
    for (const char* format : {"vtk", "xdmf"}) {
      SCOPED_TRACE(format);
      const auto r = run_sflsh_with_write_fault(reduced_run(faulty / "run") + " --format " + format, dir, faulty,
                                                c.error, 1 << 20);
      expect_one_line_write_error(r, faulty, c.reason);
      EXPECT_EQ(count_entries(faulty), 0u) << "a staging folder or partial file was left behind";
    }
    const auto r = run_sflsh_with_write_fault(
        fmt::format("-q mesh --subject OPEN_TEST_3 --mesher layered --mesh coarse --cache {} --out {}",
                    (faulty / "cache").string(), (dir / "layer").string()),
        dir, faulty, c.error, 0);
    expect_one_line_write_error(r, faulty / "cache", c.reason);
    EXPECT_EQ(count_entries(faulty / "cache"), 0u) << "a partial cache entry was left behind";
    EXPECT_FALSE(std::filesystem::exists(dir / "layer"));
    std::filesystem::remove_all(faulty / "cache");
  }
}

}  // namespace sflsh
