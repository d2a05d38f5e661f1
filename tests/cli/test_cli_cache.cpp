// The template-mesh cache under concurrency and kills (issue 45): eight processes building one empty entry all
// succeed and leave one whole entry; a writer killed with SIGKILL leaves nothing the next run trips on, and the
// temporaries of dead writers are removed.
#include "run_command.hpp"
#include "scratch_dir.hpp"

#include <sflsh/core/summary.hpp>

#include <fmt/format.h>
#include <gmock/gmock.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

namespace sflsh {
namespace {

namespace fs = std::filesystem;
using sflsh::testing::run_sflsh;

/// The arguments of `sflsh mesh` of the coarse layered template into cache `cache` (seconds on one core).
std::string mesh_args(const fs::path& cache, const fs::path& out) {
  return fmt::format(
      "-q mesh --subject OPEN_TRAIN_1 --thickness 0.5 --mesher layered --mesh coarse --cache {} --out {}",
      cache.string(), out.string());
}

/// The same as a shell command.
std::string mesh_command(const fs::path& cache, const fs::path& out) {
  return fmt::format("{} {}", SFLSH_CLI, mesh_args(cache, out));
}

/// The names in `dir` that start with '.' (temporaries, staging folders).
std::vector<std::string> hidden(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.path().filename().string().starts_with(".")) names.push_back(entry.path().filename().string());
  return names;
}

std::string text(const fs::path& file) {
  std::ifstream in(file);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(CliCache, EightProcessesBuildingOneEmptyEntryAllSucceed) {
  const fs::path dir = sflsh::testing::scratch_dir();
  const fs::path cache = dir / "cache";
  // Eight at once on an empty cache: each builds, writes a temporary and renames it into place.
  std::string script;
  for (int k = 0; k < 8; ++k)
    script += fmt::format("( {} > {} 2>&1; echo $? > {} ) & ", mesh_command(cache, dir / fmt::format("out{}", k)),
                          (dir / fmt::format("log{}", k)).string(), (dir / fmt::format("rc{}", k)).string());
  script += "wait";
  ASSERT_EQ(std::system(script.c_str()), 0);
  for (int k = 0; k < 8; ++k) {
    EXPECT_EQ(text(dir / fmt::format("rc{}", k)), "0\n") << text(dir / fmt::format("log{}", k));
    EXPECT_TRUE(fs::exists(dir / fmt::format("out{}", k) / "layer.vtu")) << k;
  }
  EXPECT_THAT(hidden(cache), ::testing::IsEmpty());
  // One whole entry: the next run reads it.
  const auto r = run_sflsh(mesh_args(cache, dir / "after"), dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_json(dir / "after" / "summary.json")["cache"]["outcome"], "hit");
}

TEST(CliCache, AWriterKilledMidWriteLeavesNothingTheNextRunTripsOn) {
  const fs::path dir = sflsh::testing::scratch_dir();
  const fs::path cache = dir / "cache";
  const auto first = run_sflsh(mesh_args(cache, dir / "first"), dir);
  ASSERT_EQ(first.exit_code, 0) << first.err;
  const fs::path entry = read_json(dir / "first" / "summary.json")["cache"]["path"].get<std::string>();
  // Writers rebuilding the entry (about a second each), killed with SIGKILL at several points of their build and
  // write; after each, the next run finds a whole entry (the old or the new one, never a temporary) and removes the
  // dead writer's temporaries.
  for (const char* delay : {"0.2", "0.45", "0.7", "0.95"}) {
    SCOPED_TRACE(delay);
    const std::string killed = fmt::format(
        "{} --rebuild-cache > /dev/null 2>&1 & pid=$!; sleep {}; kill -9 $pid 2>/dev/null; wait $pid; echo $pid > {}",
        mesh_command(cache, dir / "killed"), delay, (dir / "pid").string());
    ASSERT_EQ(std::system(killed.c_str()), 0);
    const std::string pid = text(dir / "pid").substr(0, text(dir / "pid").find('\n'));
    ASSERT_FALSE(pid.empty());
    // For certain, the half-written temporary such a kill leaves (a kill may miss the write).
    std::ofstream(entry.parent_path() / fmt::format(".{}.tmp-{}-0", entry.filename().string(), pid))
        << "PK\x03\x04half";
    const auto next = run_sflsh(mesh_args(cache, dir / "next"), dir);
    ASSERT_EQ(next.exit_code, 0) << next.err;
    EXPECT_EQ(read_json(dir / "next" / "summary.json")["cache"]["outcome"], "hit");
    EXPECT_THAT(hidden(cache), ::testing::IsEmpty());
  }
}

}  // namespace
}  // namespace sflsh
