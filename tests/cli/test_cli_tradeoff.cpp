// `sflsh tradeoff`: a tiny hierarchy of models on the coarse layer — the output files with the exact columns,
// the reference scoring zero, the error of backward Euler falling with its step, the recommendation being the
// cheapest row within the budget, and one-line errors that write nothing.
#include "png_check.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"

#include <sflsh/core/summary.hpp>

#include <fmt/format.h>
#include <gmock/gmock.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

using sflsh::read_json;
using sflsh::testing::count_entries;
using sflsh::testing::run_sflsh;
using ::testing::HasSubstr;

namespace {

namespace fs = std::filesystem;

constexpr const char* kTradeoffHeader =
    "model,integrator,mesh,handles,cubature,substeps,step_s,setup_seconds,seconds_per_frame,rms_error_mm,relative_"
    "error,"
    "sigma_ratio,valid,pareto,mass";

/// A 3-frame clip on the coarse layer, scored against backward Euler at 1/120 s (4 substeps at 30 fps); one
/// reduced model (30 handles, 200 cubature tets, 1/30 s).
std::string tiny_case(int frames = 3, int reference_substeps = 4) {
  return fmt::format(
      "--subject OPEN_TRAIN_1 --motion jiggle_on_toes --frames {} --fps 30 --reference backward_euler "
      "--reference-mesh coarse --reference-substeps {} --meshes coarse --reduced-meshes coarse --handles 30 --cubature "
      "200 "
      "--reduced-substeps 1 --reference-mass lumped --integrators backward_euler --masses lumped --cache {}",
      frames, reference_substeps, SFLSH_TEST_CACHE);
}

struct Table {
  std::string header;
  std::vector<std::vector<std::string>> rows;
};

Table read_table(const fs::path& path) {
  std::ifstream in(path);
  Table t;
  std::getline(in, t.header);
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    t.rows.push_back(cells);
  }
  return t;
}

}  // namespace

TEST(CliTradeoff, ScoresEveryModelAgainstTheReferenceAndRecommendsTheCheapestWithinBudget) {
  const fs::path dir = sflsh::testing::scratch_dir();
  const fs::path out = dir / "tr";
  // Budget 0.05 mm. Measured on this clip: backward Euler 1/30 s 0.076 mm, 1/60 s 0.032 mm, reduced 30
  // handles 0.11 mm at 1 ms per frame: the cheapest row overall is outside the budget, so a recommendation
  // that ignored it would fail the check below.
  const sflsh::testing::NoDisplay no_display;  // headless: sflsh starts its own virtual display for the chart
  const auto result =
      run_sflsh(fmt::format("-q tradeoff {} --substeps 1,2 --budget-mm 0.05 --out {}", tiny_case(), out.string()), dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  for (const char* file : {"tradeoff.csv", "tradeoff.md", "summary.json"}) EXPECT_TRUE(fs::exists(out / file)) << file;
  sflsh::testing::expect_drawn_png(out / "tradeoff.png", 900, 600);  // the error–time chart, drawn

  const Table t = read_table(out / "tradeoff.csv");
  EXPECT_EQ(t.header, kTradeoffHeader);
  ASSERT_EQ(t.rows.size(), 4u);  // reference, full 1/30, full 1/60, reduced
  for (const auto& r : t.rows) ASSERT_EQ(r.size(), 15u);
  // The reference scores itself: exactly zero error, σ ratio 1, and it is on the front.
  EXPECT_EQ(t.rows[0][0], "reference");
  EXPECT_EQ(std::stod(t.rows[0][9]), 0.0);
  EXPECT_EQ(std::stod(t.rows[0][10]), 0.0);
  EXPECT_EQ(std::stod(t.rows[0][11]), 1.0);
  EXPECT_EQ(t.rows[0][13], "yes");
  // Backward Euler converges to the reference as its step shrinks (first order; measured 0.076 → 0.032 mm).
  ASSERT_EQ(t.rows[1][0], "full");
  ASSERT_EQ(t.rows[2][0], "full");
  EXPECT_EQ(t.rows[1][5], "1");
  EXPECT_EQ(t.rows[2][5], "2");
  const double e1 = std::stod(t.rows[1][9]), e2 = std::stod(t.rows[2][9]);
  EXPECT_GT(e1, 0.0);
  EXPECT_LT(e2, 0.8 * e1);  // first order would halve it; 0.8 leaves room for the reference's own error
  EXPECT_EQ(t.rows[3][0], "reduced");
  EXPECT_EQ(t.rows[3][3], "30");
  for (std::size_t i = 1; i < t.rows.size(); ++i) {
    EXPECT_GT(std::stod(t.rows[i][8]), 0.0) << i;  // seconds per frame
    EXPECT_GT(std::stod(t.rows[i][7]), 0.0) << i;  // setup seconds
    const double rel = std::stod(t.rows[i][10]);
    EXPECT_GT(rel, 0.0) << i;
    EXPECT_LT(rel, 1.0) << i;  // closer to the reference than no soft tissue at all (which scores 1)
  }

  // The recommendation: the cheapest tested row within the budget, read back from the table.
  const nlohmann::json summary = read_json(out / "summary.json");
  std::optional<std::size_t> expected;
  for (std::size_t i = 1; i < t.rows.size(); ++i)
    if (t.rows[i][12] == "yes" && std::stod(t.rows[i][9]) <= 0.05 &&
        (!expected || std::stod(t.rows[i][8]) < std::stod(t.rows[*expected][8])))
      expected = i;
  ASSERT_TRUE(expected.has_value()) << "no row within 0.05 mm: the clip's numbers moved, retune the budget";
  ASSERT_FALSE(summary["recommendation"]["row"].is_null()) << summary["recommendation"]["message"];
  EXPECT_EQ(summary["recommendation"]["row"].get<std::size_t>(), *expected);
  EXPECT_EQ(summary["rows"].size(), 4u);
  EXPECT_EQ(summary["reference"]["integrator"], "backward_euler");
  EXPECT_EQ(summary["reference"]["mesh"], "coarse");
  std::ifstream md(out / "tradeoff.md");
  std::stringstream text;
  text << md.rdbuf();
  EXPECT_THAT(text.str(), HasSubstr("Recommended for RMS error ≤ 0.05 mm"));
}

TEST(CliTradeoff, SweepsIntegratorsAndMassesAndChecksTheReference) {
  // Reference: Newmark with consistent masses at 1/240 s; rows: backward Euler and Newmark × lumped and consistent at
  // 1/30 s, full space and one reduced model. Newmark keeps the dynamics backward Euler damps away, so at the same
  // step its σ ratio is closer to 1; the time check (1/480 s against 1/240 s) shows the reference's own error is
  // far below the rows' errors.
  const fs::path dir = sflsh::testing::scratch_dir();
  const fs::path out = dir / "tr";
  const auto result = run_sflsh(
      fmt::format(
          "-q tradeoff --subject OPEN_TRAIN_1 --motion jiggle_on_toes --frames 4 --fps 30 --reference newmark "
          "--reference-mass "
          "consistent --reference-mesh coarse --reference-substeps 8 --reference-check time --reference-check-frames 3 "
          "--meshes coarse --substeps 1 --integrators backward_euler,newmark --masses lumped,consistent "
          "--reduced-meshes coarse "
          "--handles 30 --cubature 200 --reduced-substeps 1 --cache {} --out {}",
          SFLSH_TEST_CACHE, out.string()),
      dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const nlohmann::json summary = read_json(out / "summary.json");
  ASSERT_EQ(summary["rows"].size(), 9u);  // the reference, 4 full-space rows, 4 reduced rows
  EXPECT_EQ(summary["reference"]["integrator"], "newmark");
  EXPECT_EQ(summary["reference"]["mass"], "consistent");
  std::map<std::string, double> sigma_ratio, error;
  for (const auto& row : summary["rows"]) {
    if (row["model"] != "full") continue;
    const std::string key = row["integrator"].get<std::string>() + "/" + row["mass"].get<std::string>();
    sigma_ratio[key] = row["sigma_ratio"].get<double>();
    error[key] = row["rms_error_mm"].get<double>();
  }
  ASSERT_EQ(sigma_ratio.size(), 4u);
  EXPECT_GT(sigma_ratio["newmark/consistent"], sigma_ratio["backward_euler/consistent"]);
  EXPECT_GT(sigma_ratio["newmark/lumped"], sigma_ratio["backward_euler/lumped"]);
  ASSERT_EQ(summary["reference"]["checks"].size(), 1u);
  const double check_mm = summary["reference"]["checks"][0]["rms_difference_mm"].get<double>();
  EXPECT_LT(check_mm, 0.25 * error["newmark/consistent"])
      << "the reference is not converged in time against the rows it scores";
  const Table t = read_table(out / "tradeoff.csv");
  EXPECT_EQ(t.header, kTradeoffHeader);
  for (std::size_t i = 0; i < t.rows.size(); ++i)
    EXPECT_THAT(t.rows[i].back(), ::testing::AnyOf("lumped", "consistent")) << i;
}

TEST(CliTradeoff, SaysSoWhenNoConfigurationMeetsTheBudget) {
  const fs::path dir = sflsh::testing::scratch_dir();
  const fs::path out = dir / "tr";
  const auto result = run_sflsh(
      fmt::format("-q tradeoff {} --substeps 1 --budget-mm 1e-9 --out {}", tiny_case(3, 2), out.string()), dir);
  ASSERT_EQ(result.exit_code, 0) << result.err;
  const nlohmann::json summary = read_json(out / "summary.json");
  EXPECT_TRUE(summary["recommendation"]["row"].is_null());
  EXPECT_THAT(summary["recommendation"]["message"].get<std::string>(),
              HasSubstr("No tested configuration meets RMS error ≤ 1e-09 mm"));
  EXPECT_EQ(summary["rows"].size(), 3u);
}

TEST(CliTradeoff, BadOptionsGiveOneLineAndWriteNothing) {
  const fs::path dir = sflsh::testing::scratch_dir();
  const fs::path out = dir / "never";
  struct Case {
    std::string args;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"--substeps 1 --budget-mm -1", "--budget-mm and --budget-relative must be positive"},
      {"--substeps 0,2", "0 is outside [1, 10⁶]"},
      {"--substeps 1,8", "must take a smaller step than every tested model"},
      {"--substeps 1 --budget-relative -0.5", "must be positive"},
      {"--substeps 1 --handles 100000", "100000 point handles requested"},
  };
  for (const Case& c : cases) {
    const auto result = run_sflsh(fmt::format("-q tradeoff {} {} --out {}", tiny_case(), c.args, out.string()), dir);
    EXPECT_NE(result.exit_code, 0) << c.args;
    EXPECT_THAT(result.err, HasSubstr(c.message)) << c.args;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_EQ(count_entries(out), 0u) << c.args;
    EXPECT_FALSE(fs::exists(out)) << c.args;
  }
}
