// The experiment pipeline of `sflsh validate` end to end on a small configuration, pinned as an accuracy
// regression test (Table 2 of SFLSH on synthetic ground truth), and the command's input checks.
#include "long_test.hpp"
#include "png_check.hpp"
#include "run_command.hpp"
#include "scratch_dir.hpp"
#include "text_lines.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/material/material_file.hpp>
#include <sflsh/reduced/shape_model_file.hpp>
#include <sflsh/validate/experiments.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace sflsh {

namespace {

double row_value(const nlohmann::json& summary, const std::string& row, const char* split) {
  for (const auto& r : summary.at("table2"))
    if (r.at("row") == row) return r.at(split).at("avg").get<double>();
  ADD_FAILURE() << "row " << row << " missing";
  return 0.0;
}

}  // namespace

// Two train subjects, one test subject, one train and one test motion of 20 frames, uniform material
// (N = 1), four trust-region iterations, λ = 1: the whole pipeline in about a minute on 2 cores.
TEST(Experiments, SmallConfigurationReproducesPinnedTable2) {
  const std::filesystem::path dir = sflsh::testing::scratch_dir();
  validate::ValidateConfig config = validate::ValidateConfig::from_preset("quick");
  config.train_subjects = {"OPEN_TRAIN_1", "OPEN_TRAIN_2"};
  config.test_subjects = {"OPEN_TEST_1"};
  config.frames = 20;
  config.stages = {1};
  config.iterations = 4;
  config.lambdas = {1.0};
  config.threads = 2;
  config.progress = false;
  config.cache_dir = SFLSH_TEST_CACHE;
  const sflsh::testing::NoDisplay no_display;  // headless: the λ-sweep chart starts its own virtual display
  const nlohmann::json summary = validate::run_validation(config, dir, nlohmann::json::object());
  sflsh::testing::expect_drawn_png(dir / "lambda_sweep.png", 900, 600);

  for (const char* file :
       {"table2.csv", "table2.md", "table2_error.csv", "cross_validation.csv", "lambda_sweep.csv", "covariance.csv",
        "parameter_error.csv", "dynamics.vtp", "fits.csv", "summary.json", "materials/ours/OPEN_TEST_1.toml",
        "regularizer_comparison.csv", "shape_dependence_error.csv"})
    EXPECT_TRUE(std::filesystem::exists(dir / file)) << file;
  {
    std::ifstream in(dir / "table2.csv");
    std::string header;
    std::getline(in, header);
    EXPECT_EQ(header,
              "row,subjects,train_motions_subject_1,train_motions_subject_2,train_motions_avg,"
              "test_motions_subject_1,test_motions_subject_2,test_motions_avg");
    std::string line;
    std::vector<std::string> labels;
    while (std::getline(in, line)) labels.push_back(line.substr(1, line.find('"', 1) - 1));
    const std::vector<std::string> expected{"Ground truth",    "Independent",     "Cross-val. L2",
                                            "Cross-val. ours", "Full opt. L2",    "Full opt. ours",
                                            "Generaliz. L2",   "Generaliz. ours", "Ground truth (test subjects)"};
    EXPECT_EQ(labels, expected);
  }
  {
    // The sweep says how λ was chosen: one λ, so the one-standard-error rule (the default) takes it.
    const std::vector<std::string> sweep = sflsh::testing::lines_of(dir / "lambda_sweep.csv");
    ASSERT_EQ(sweep.size(), 3u);  // header, l2, ours
    EXPECT_EQ(sweep[0],
              "regularizer,lambda,cv_train_motions_rms_error_mm,cv_test_motions_rms_error_mm,"
              "cv_train_motions_standard_error_mm,chosen");
    for (std::size_t i = 1; i < sweep.size(); ++i) EXPECT_EQ(sweep[i].substr(sweep[i].rfind(',') + 1), "1") << sweep[i];
    EXPECT_EQ(summary.at("lambda_rule"), "one-se");
    for (const char* tag : {"l2", "ours"}) {
      const nlohmann::json& choice = summary.at("lambda_choice").at(tag);
      EXPECT_EQ(choice.at("lambda").get<double>(), 1.0) << tag;
      EXPECT_GE(choice.at("standard_error_mm").get<double>(), 0.0) << tag;  // two folds
      EXPECT_GE(choice.at("threshold_mm").get<double>(), choice.at("least_error_mm").get<double>()) << tag;
    }
  }
  // Pinned values (this machine kind, measured when the pipeline landed), in mm.
  // Ground truth: a deterministic full-space run (Newton to ‖∇Φ‖ ≤ 1e-8 relative); 1 % covers compiler and
  // BLAS differences. Fitted rows: the trust-region path may differ slightly across platforms; 4 % is
  // about a third of the spread between the rows and the truth.
  // Ground truth moved from 0.840 and 0.583 (−4 %) when the skin's rim was attached like the side wall
  // (issue 18): the rim no longer moves and the ring next to it moves less. It moved again from 0.805 / 0.559 to
  // 0.879 / 0.579 when the built-in truth's shape dependence became the change of the soft-tissue depth instead
  // of the surface's normal offset (true_material.hpp): OPEN_TRAIN_2 and OPEN_TEST_1 get softer flesh. The fitted
  // rows follow the truth they fit (0.753 → 0.805, 0.751 → 0.807, 0.546 → 0.567, 0.672 → 0.663; the local metric's
  // new scale had kept the N = 1 fits of ours within these pins before the truth changed).
  EXPECT_NEAR(row_value(summary, "Ground truth", "train_motions"), 0.879, 0.01 * 0.879);
  EXPECT_NEAR(row_value(summary, "Ground truth", "test_motions"), 0.579, 0.01 * 0.579);
  EXPECT_NEAR(row_value(summary, "Independent", "train_motions"), 0.805, 0.04 * 0.805);
  EXPECT_NEAR(row_value(summary, "Full opt. ours", "train_motions"), 0.807, 0.04 * 0.807);
  EXPECT_NEAR(row_value(summary, "Full opt. L2", "test_motions"), 0.567, 0.04 * 0.567);
  EXPECT_NEAR(row_value(summary, "Generaliz. ours", "train_motions"), 0.663, 0.04 * 0.663);
  // Accuracy goals independent of the pins: a fitted reduced model recovers ≥ 85 % of the ground truth's
  // dynamics on its own subjects, and fitting beats the uniform start (whose σ the first fit stage reports).
  const double truth = row_value(summary, "Ground truth", "train_motions");
  EXPECT_GT(row_value(summary, "Independent", "train_motions"), 0.85 * truth);
  EXPECT_GT(row_value(summary, "Full opt. ours", "train_motions"), 0.85 * truth);
  for (const auto& f : summary.at("fits")) EXPECT_TRUE(std::isfinite(f.at("loss_fit").get<double>()));
  // Every stage names the test that stopped it; the iteration cap is only the safety net (docs/fit.md).
  int stages = 0;
  for (const auto& f : summary.at("fits")) {
    const std::string reason = f.at("reason");
    EXPECT_TRUE(reason == "loss_decrease" || reason == "projected_gradient" || reason == "trust_radius" ||
                reason == "iteration_cap")
        << f.at("fit") << ": " << reason;
    ++stages;
  }
  int counted = 0;
  for (const auto& [reason, count] : summary.at("stage_stops").items()) counted += count.get<int>();
  EXPECT_EQ(counted, stages);
  // The regularizers paired on the test subject × (train, test) motion: 2 pairs; the sign test of a 2–0 split is
  // ½ (two-sided: 2 · ¼), of 1–1 is 1.
  {
    const nlohmann::json& c = summary.at("regularizer_comparison");
    EXPECT_EQ(c.at("pairs").get<int>(), 2);
    const int ours = c.at("wins_ours").get<int>(), l2 = c.at("wins_l2").get<int>();
    EXPECT_EQ(ours + l2 + c.at("ties").get<int>(), 2);
    if (ours + l2 == 2) {
      EXPECT_DOUBLE_EQ(c.at("sign_test_p").get<double>(), ours == 1 ? 1.0 : 0.5);
    }
    const std::vector<std::string> lines = sflsh::testing::lines_of(dir / "regularizer_comparison.csv");
    ASSERT_EQ(lines.size(), 3u);
    EXPECT_EQ(lines[0].rfind("subject,motion,error_l2,error_ours,winner,error_l2_chest,", 0), 0u) << lines[0];
    for (const char* tag : {"l2", "ours"})
      EXPECT_TRUE(std::isfinite(summary.at("shape_dependence_error").at(tag).at("thickness_rms").get<double>()));
  }
  // The truth's shape-dependent part is reported beside the independent fits' error (docs/fit.md).
  for (const char* p : {"thickness", "young_tangent", "young_normal"}) {
    const nlohmann::json& t = summary.at("truth_identifiability").at(p);
    EXPECT_GT(t.at("truth_shape_rms").get<double>(), 0.0) << p;
    EXPECT_NEAR(t.at("ratio").get<double>(),
                t.at("independent_error_rms").get<double>() / t.at("truth_shape_rms").get<double>(), 1e-12)
        << p;
  }

  // The fitted shape models give back every subject's fitted material (the files validate writes).
  const body::BodyModel body = body::load_body(body::default_body_path());
  for (const std::string tag : {"l2", "ours"}) {
    const reduced::ShapeModelFile model = reduced::load_shape_model_file(dir / "shape_models" / (tag + ".toml"));
    ASSERT_TRUE(model.fit.has_value());
    EXPECT_EQ(model.fit->lambda, 1.0);
    EXPECT_EQ(model.fit->subjects, config.train_subjects);
    for (const std::string s : {"OPEN_TRAIN_1", "OPEN_TRAIN_2", "OPEN_TEST_1"}) {
      const material::MaterialFile fitted = material::load_material_file(dir / "materials" / tag / (s + ".toml"));
      const material::MaterialFile from_model =
          reduced::material_for_beta(model, body, body::find_subject(body::default_subjects(), s).beta, s);
      EXPECT_EQ(from_model.vertices(), fitted.vertices());
      // Both are κ̂(β) clamped and de-normalized; the material file was written the same way.
      EXPECT_LT((from_model.kappa() - fitted.kappa()).cwiseQuotient(fitted.kappa()).cwiseAbs().maxCoeff(), 1e-12)
          << tag << " " << s;
    }
  }

  // A second run resumes from the state folder: no ground truth or fit is recomputed.
  const nlohmann::json again = validate::run_validation(config, dir, nlohmann::json::object());
  EXPECT_EQ(row_value(again, "Full opt. ours", "train_motions"), row_value(summary, "Full opt. ours", "train_motions"));
  EXPECT_LT(again.at("simulations").get<long>(), summary.at("simulations").get<long>() / 4);
}

TEST(Experiments, BadArgumentsGiveOneLineErrors) {
  const std::filesystem::path dir = sflsh::testing::scratch_dir();
  const auto bad_preset = sflsh::testing::run_sflsh("validate --preset huge --out " + (dir / "a").string(), dir);
  EXPECT_NE(bad_preset.exit_code, 0);
  const auto bad_lambda = sflsh::testing::run_sflsh("validate --lambdas 0.1,x --out " + (dir / "b").string(), dir);
  EXPECT_NE(bad_lambda.exit_code, 0);
  EXPECT_NE(bad_lambda.err.find("--lambdas"), std::string::npos) << bad_lambda.err;
  const auto bad_subject =
      sflsh::testing::run_sflsh("validate --train-subjects NOBODY,OPEN_TRAIN_1 --out " + (dir / "c").string(), dir);
  EXPECT_NE(bad_subject.exit_code, 0);
  EXPECT_NE(bad_subject.err.find("NOBODY"), std::string::npos) << bad_subject.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "c" / "summary.json"));
}

// DYNA files as ground truth: our own synthetic truth written in the DYNA layout and read back through the
// pose and β fit and the metric (the path real DYNA data takes), for one train subject.
TEST(Experiments, DynaFilesAreTheGroundTruthWhenGiven) {
  const std::filesystem::path dir = sflsh::testing::scratch_dir();
  const auto gt = sflsh::testing::run_sflsh(
      "groundtruth --subjects OPEN_TRAIN_2 --motions running_on_spot,jiggle_on_toes "
      "--frames 12 --mesh coarse --out " +
          (dir / "gt").string(),
      dir);
  ASSERT_EQ(gt.exit_code, 0) << gt.err;
  const nlohmann::json truth = read_json(dir / "gt" / "summary.json");
  double synthetic = 0.0;
  for (const auto& c : truth.at("cases"))
    if (c.at("motion") == "running_on_spot") synthetic = c.at("sigma_mean_mm").get<double>();
  ASSERT_GT(synthetic, 0.0);

  validate::ValidateConfig config = validate::ValidateConfig::from_preset("quick");
  config.dyna = {dir / "gt" / "groundtruth.h5"};
  config.test_subjects = {"OPEN_TEST_1"};
  config.frames = 12;
  config.stages = {1};
  config.iterations = 2;
  config.lambdas = {1.0};
  config.cross_validation = false;  // one train subject
  config.threads = 2;
  config.progress = false;
  config.cache_dir = SFLSH_TEST_CACHE;
  const nlohmann::json summary = validate::run_validation(config, dir / "validate", nlohmann::json::object());
  // The train subjects are the file's: OPEN_TRAIN_2 (the only one with both motions).
  EXPECT_EQ(summary.at("table2").at(0).at("subjects"), nlohmann::json::array({"OPEN_TRAIN_2"}));
  // β is recovered from the registrations (measured within 0.005 of the subject's).
  const body::Betas beta = body::find_subject(body::default_subjects(), "OPEN_TRAIN_2").beta;
  const std::vector<double> fitted = summary.at("dyna").at("subjects").at("OPEN_TRAIN_2").at("beta");
  for (int k = 0; k < 10; ++k) EXPECT_NEAR(fitted[static_cast<std::size_t>(k)], beta[k], 0.05) << "β" << k;
  // σ* measured from the registrations is the synthetic truth's σ minus what the per-frame pose fit absorbs:
  // on these 12 frames the dynamics (0.15 mm) are as large as the pose-fit residual, and the fit absorbs
  // 38 % (measured: 0.095 vs 0.153 mm). The bounds catch a lost or doubled signal, not that absorption.
  const double measured = row_value(summary, "Ground truth", "train_motions");
  EXPECT_GT(measured, 0.45 * synthetic);
  EXPECT_LT(measured, 1.1 * synthetic);
  // Test subjects have no truth in DYNA data: their truth row is empty, their model rows are not.
  for (const auto& r : summary.at("table2")) {
    if (r.at("row") == "Ground truth (test subjects)") {
      const nlohmann::json& avg = r.at("train_motions").at("avg");
      EXPECT_TRUE(avg.is_null() || !std::isfinite(avg.get<double>()));
    }
  }
  EXPECT_GT(row_value(summary, "Generaliz. ours", "train_motions"), 0.0);
  EXPECT_FALSE(std::filesystem::exists(dir / "validate" / "parameter_error.csv"));  // no true parameters
  EXPECT_TRUE(std::filesystem::exists(dir / "validate" / "table2.csv"));
}

namespace {

/// Runs `sflsh ARGS --out DIR/one` as one process and `mpiexec -n 2 sflsh ARGS --out DIR/two EXTRA` (logs beside).
/// The test process is an MPI singleton: its OMPI_*/PMIX_* variables must not reach the nested mpiexec.
void run_one_and_two_processes(const std::filesystem::path& dir, const std::string& args,
                               const std::string& two_extra = "") {
  const std::string clean = "for v in $(env | sed -n 's/^\\(OMPI_[^=]*\\|PMIX_[^=]*\\)=.*/\\1/p'); do unset $v; done; ";
  const std::string one = clean + std::string(SFLSH_CLI) + args + " --out " + (dir / "one").string() + " >" +
                          (dir / "one.log").string() + " 2>&1";
  ASSERT_EQ(std::system(one.c_str()), 0) << "see " << (dir / "one.log");
  const std::string two = clean +
                          "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
                          "OMPI_MCA_rmaps_base_oversubscribe=1 mpiexec -n 2 " +
                          std::string(SFLSH_CLI) + args + " --out " + (dir / "two").string() + two_extra + " >" +
                          (dir / "two.log").string() + " 2>&1";
  ASSERT_EQ(std::system(two.c_str()), 0) << "mpiexec -n 2 failed; see " << (dir / "two.log");
}

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

// The fit shares its simulations among MPI ranks: two processes give exactly the table of one (every result
// is computed by one rank and summed with zeros, so each rank takes the same trust-region steps).
TEST(Experiments, TwoMpiProcessesGiveTheSameTable) {
  SFLSH_LONG_TEST();  // tens of seconds on 2 cores: label long
  if (std::system("command -v mpiexec >/dev/null 2>&1") != 0) GTEST_SKIP() << "mpiexec not found";
  const std::filesystem::path dir = sflsh::testing::scratch_dir();
  run_one_and_two_processes(dir,
                            " validate --train-subjects OPEN_TRAIN_1,OPEN_TRAIN_2 --test-subjects OPEN_TEST_1 "
                            "--frames 10 --stages 1 --iterations 2 --lambdas 1 --no-cross-validation --threads 1 -q");
  if (HasFatalFailure()) return;
  EXPECT_EQ(slurp(dir / "one" / "table2.csv"), slurp(dir / "two" / "table2.csv"));
  const nlohmann::json s1 = read_json(dir / "one" / "summary.json"), s2 = read_json(dir / "two" / "summary.json");
  EXPECT_EQ(s2.at("ranks").get<int>(), 2);
  EXPECT_EQ(s1.at("simulations"), s2.at("simulations"));
}

// Fit groups (--fit-groups): with two ranks in two groups each rank runs whole fits (the independent fits and the
// leave-one-out chains round robin, each λ after the first warm-started from the previous one), then reads the
// other group's fits back from their checkpoints. One rank per group and one thread do the arithmetic of a single
// one-thread process, so the tables are identical, and so is the number of simulations.
TEST(Experiments, FitGroupsGiveTheTableOfOneProcess) {
  SFLSH_LONG_TEST();  // about a minute on 2 cores: label long
  if (std::system("command -v mpiexec >/dev/null 2>&1") != 0) GTEST_SKIP() << "mpiexec not found";
  const std::filesystem::path dir = sflsh::testing::scratch_dir();
  run_one_and_two_processes(dir,
                            " validate --train-subjects OPEN_TRAIN_1,OPEN_TRAIN_2 --test-subjects OPEN_TEST_1 "
                            "--frames 10 --stages 1 --iterations 2 --lambdas 1,0.1 --threads 1 -q",
                            " --fit-groups 2");
  if (HasFatalFailure()) return;
  for (const char* file : {"table2.csv", "table2_error.csv", "cross_validation.csv", "lambda_sweep.csv"}) {
    EXPECT_FALSE(slurp(dir / "one" / file).empty()) << file;
    EXPECT_EQ(slurp(dir / "one" / file), slurp(dir / "two" / file)) << file;
  }
  const nlohmann::json s1 = read_json(dir / "one" / "summary.json"), s2 = read_json(dir / "two" / "summary.json");
  EXPECT_EQ(s2.at("config").at("fit_groups").get<int>(), 2);
  EXPECT_EQ(s1.at("simulations"), s2.at("simulations"));
  // Every fit's parameters and stage losses bit for bit, not only the tables' rounded digits: the leave-one-out
  // fits are flat enough that a one-ulp difference upstream (a thread-count-dependent sum in the ground truth,
  // docs/decisions.md "Deterministic sums") moved their parameters in the second decimal on the quick preset
  // while these small tables stayed the same.
  int compared = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir / "one" / "state" / "fits")) {
    const nlohmann::json a = read_json(entry.path()),
                         b = read_json(dir / "two" / "state" / "fits" / entry.path().filename());
    EXPECT_EQ(a.at("p"), b.at("p")) << entry.path().filename();
    ASSERT_EQ(a.at("done").size(), b.at("done").size()) << entry.path().filename();
    for (std::size_t s = 0; s < a.at("done").size(); ++s)  // the stage's seconds differ, its losses must not
      for (const char* loss : {"loss_fit", "loss_reg"})
        EXPECT_EQ(a.at("done")[s].at(loss), b.at("done")[s].at(loss)) << entry.path().filename() << " stage " << s;
    ++compared;
  }
  EXPECT_EQ(compared, 2 + 2 * 2 * 2 + 2);  // independent, leave-one-out (2 regularizers × 2 folds × 2 λ), full
  // The warm start: each fold's smaller λ continued from the larger one's result.
  const nlohmann::json cp = read_json(dir / "two" / "state" / "fits" / "cv_ours_lambda0.1_without_OPEN_TRAIN_1.json");
  EXPECT_NE(cp.at("fingerprint").get<std::string>().find("cv_ours_lambda1_without_OPEN_TRAIN_1"), std::string::npos);
}

}  // namespace sflsh
