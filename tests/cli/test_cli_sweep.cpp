// `sflsh sweep`: a representative slice (2 subjects × 2 motions × 40 frames on the coarse layer) runs without a
// failure and writes the report with its exact columns; a failing case is reported in the table and the exit code
// while the report is still written; bad lists fail at once with one line and write nothing.
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "text_lines.hpp"

#include <sflsh/core/summary.hpp>

#include <fmt/format.h>
#include <gmock/gmock.h>

#include <cmath>
#include <fstream>
#include <sstream>

using sflsh::read_json;
using sflsh::testing::count_entries;
using sflsh::testing::run_sflsh;
using ::testing::HasSubstr;

namespace {

namespace fs = std::filesystem;
using sflsh::testing::text_of;

constexpr const char* kSweepHeader =
    "mesh,subject,motion,status,error,frames,sigma_mm,newton_per_frame,seconds,fps,sigma_max_mm,solve_seconds,"
    "failed_attempts,factorizations,tets,coordinates,cubature_tets";

/// A CSV line split at commas outside double quotes (quotes kept out of the cells).
std::vector<std::string> cells_of(const std::string& line) {
  std::vector<std::string> cells(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (c == '"') {
      if (quoted && i + 1 < line.size() && line[i + 1] == '"') {
        cells.back() += '"';
        ++i;
      } else {
        quoted = !quoted;
      }
    } else if (c == ',' && !quoted) {
      cells.emplace_back();
    } else {
      cells.back() += c;
    }
  }
  return cells;
}

using sflsh::testing::lines_of;

/// The report files and nothing else (no staging folder left behind).
void expect_report(const fs::path& out) {
  for (const char* file : {"sweep.csv", "sweep.md", "summary.json"}) EXPECT_TRUE(fs::exists(out / file)) << file;
  EXPECT_EQ(count_entries(out), 3u);
}

}  // namespace

TEST(CliSweep, ARepresentativeSliceRunsWithoutFailures) {
  const fs::path dir = sflsh::testing::scratch_dir();
  const fs::path out = dir / "sweep";
  const auto result =
      run_sflsh(fmt::format("-q sweep --mesh coarse --subjects DYNA_1,OPEN_TEST_3 --motions shake_hips,dance "
                            "--frames 40 --threads 2 --cache {} --out {}",
                            SFLSH_TEST_CACHE, out.string()),
                dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  expect_report(out);

  const std::vector<std::string> lines = lines_of(out / "sweep.csv");
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_EQ(lines[0], kSweepHeader);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"DYNA_1", "shake_hips"}, {"DYNA_1", "dance"}, {"OPEN_TEST_3", "shake_hips"}, {"OPEN_TEST_3", "dance"}};
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> c = cells_of(lines[i]);
    ASSERT_EQ(c.size(), 17u) << lines[i];
    EXPECT_EQ(c[0], "coarse");
    EXPECT_EQ(c[1], cases[i - 1].first);
    EXPECT_EQ(c[2], cases[i - 1].second);
    EXPECT_EQ(c[3], "ok") << c[4];
    EXPECT_EQ(c[4], "");
    EXPECT_EQ(std::stoi(c[5]), 40);
    for (std::size_t k : {6u, 7u, 8u, 9u, 10u, 11u}) {
      const double v = std::stod(c[k]);
      EXPECT_TRUE(std::isfinite(v)) << lines[i];
      EXPECT_GT(v, 0.0) << lines[i];
    }
    EXPECT_LT(std::stod(c[6]), 50.0) << lines[i];  // mean σ in mm: the tissue moves and stays on the body
    EXPECT_GE(std::stod(c[10]), std::stod(c[6])) << lines[i];
    EXPECT_GE(std::stoi(c[12]), 0);
    EXPECT_GT(std::stoi(c[14]), 0);
    EXPECT_EQ(std::stoi(c[15]), 3 * 86);  // 86 translational point handles
    EXPECT_GE(std::stoi(c[16]), 200);     // the automatic cubature: max(200, 0.8 × coordinates)
  }

  const nlohmann::json summary = read_json(out / "summary.json");
  EXPECT_EQ(summary["command"], "sweep");
  EXPECT_EQ(summary["runs"].get<int>(), 4);
  EXPECT_EQ(summary["failures"].get<int>(), 0);
  EXPECT_EQ(summary["counts"]["coarse"]["runs"].get<int>(), 4);
  EXPECT_EQ(summary["counts"]["coarse"]["failures"].get<int>(), 0);
  EXPECT_EQ(summary["sweep"]["solver"], "reduced");
  EXPECT_TRUE(summary["failed_runs"].empty());
  const std::string md = text_of(out / "sweep.md");
  EXPECT_THAT(md, HasSubstr("| coarse | 4 | 4 | 0 |"));
  EXPECT_THAT(md, HasSubstr("| coarse | OPEN_TEST_3 | dance | ok | 40 |"));
  EXPECT_THAT(md, HasSubstr("No run failed."));
}

TEST(CliSweep, AFailedRunIsReportedAndTheExitCodeSaysSo) {
  const fs::path dir = sflsh::testing::scratch_dir();
  const fs::path out = dir / "sweep";
  // More point handles than the layer has nodes for: the run fails after its layer is built (a per-run error).
  const auto result =
      run_sflsh(fmt::format("-q sweep --subjects OPEN_TEST_3 --motions shake_hips --frames 3 --handles 100000 "
                            "--cache {} --out {}",
                            SFLSH_TEST_CACHE, out.string()),
                dir);
  EXPECT_NE(result.exit_code, 0);
  EXPECT_THAT(result.err, HasSubstr("sweep: 1 of 1 runs failed (coarse 1/1); see " + (out / "sweep.md").string()));
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
  expect_report(out);

  const std::vector<std::string> lines = lines_of(out / "sweep.csv");
  ASSERT_EQ(lines.size(), 2u);
  const std::vector<std::string> c = cells_of(lines[1]);
  ASSERT_EQ(c.size(), 17u) << lines[1];
  EXPECT_EQ(c[3], "failed");
  EXPECT_THAT(c[4], HasSubstr("100000 point handles requested"));
  EXPECT_EQ(c[6], "");  // no σ for a failed run
  const nlohmann::json summary = read_json(out / "summary.json");
  EXPECT_EQ(summary["failures"].get<int>(), 1);
  EXPECT_EQ(summary["counts"]["coarse"]["failures"].get<int>(), 1);
  ASSERT_EQ(summary["failed_runs"].size(), 1u);
  EXPECT_EQ(summary["failed_runs"][0]["subject"], "OPEN_TEST_3");
  const std::string md = text_of(out / "sweep.md");
  EXPECT_THAT(md, HasSubstr("## Failures (1)"));
  EXPECT_THAT(md, HasSubstr("coarse · OPEN_TEST_3 · shake_hips"));
}

TEST(CliSweep, BadListsGiveOneLineAndWriteNothing) {
  const fs::path dir = sflsh::testing::scratch_dir();
  const fs::path out = dir / "never";
  struct Case {
    std::string args;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"--subjects DYNA_1,NOBODY", "unknown subject 'NOBODY'"},
      {"--motions shake_hips,no_such_motion", "no_such_motion"},
      {"--mesh coarse,huge", "'huge' is not coarse, default or fine"},
      {"--subjects ,", "--subjects ,: no subject"},
      {"--frames 1", "--frames must be at least 2"},
  };
  for (const Case& c : cases) {
    const auto result =
        run_sflsh(fmt::format("-q sweep {} --cache {} --out {}", c.args, SFLSH_TEST_CACHE, out.string()), dir);
    EXPECT_NE(result.exit_code, 0) << c.args;
    EXPECT_THAT(result.err, HasSubstr(c.message)) << c.args;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_FALSE(fs::exists(out)) << c.args;
  }
}
