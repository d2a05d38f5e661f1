// `sflsh groundtruth`: the synthetic ground truth in the DYNA layout with the true parameters beside it.
#include "run_command.hpp"
#include "scratch_dir.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/npz.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/reduced/shape_model_file.hpp>
#include <sflsh/validate/dyna_file.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>

namespace sflsh {

TEST(GroundTruthCommand, WritesDynaLayoutAndTrueParameters) {
  const std::filesystem::path dir = sflsh::testing::scratch_dir();
  const auto r = sflsh::testing::run_sflsh(
      "groundtruth --subjects OPEN_TRAIN_2,OPEN_TEST_1 --motions running_on_spot --frames 6 --mesh coarse --out " +
          (dir / "gt").string(),
      dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const validate::DynaFile file(dir / "gt" / "groundtruth.h5");
  const body::BodyModel model = body::load_body(std::filesystem::path(SFLSH_DATA_DIR) / "open_body.npz");
  EXPECT_NO_THROW(file.require_vertices(model));
  EXPECT_EQ(file.keys(), (std::vector<std::string>{"OPEN_TEST_1_running_on_spot", "OPEN_TRAIN_2_running_on_spot"}));
  EXPECT_EQ(file.faces().rows(), model.faces.rows());
  const validate::DynaSequence seq = file.read("OPEN_TRAIN_2_running_on_spot");
  EXPECT_EQ(seq.num_frames(), 6);
  EXPECT_DOUBLE_EQ(seq.fps, 60.0);
  const body::Betas beta = body::find_subject(body::default_subjects(), "OPEN_TRAIN_2").beta;
  ASSERT_EQ(seq.attributes.numbers.at("beta").size(), 10u);
  for (int k = 0; k < 10; ++k)
    EXPECT_DOUBLE_EQ(seq.attributes.numbers.at("beta")[static_cast<std::size_t>(k)], beta[k]);
  // The body moves (posed frames, not the template) and stays a body: stature within 1.4–2.1 m.
  const double height = seq.frames[3].col(1).maxCoeff() - seq.frames[3].col(1).minCoeff();
  EXPECT_GT(height, 1.4);
  EXPECT_LT(height, 2.1);
  EXPECT_GT((seq.frames[5] - seq.frames[0]).norm(), 1e-3);
  // True parameters: κ per region vertex inside the ranges, and the description.
  const npz::Reader truth(dir / "gt" / "truth" / "OPEN_TRAIN_2.npz");
  const std::vector<double> kappa = truth.read("kappa").to_doubles();
  ASSERT_EQ(kappa.size() % 3, 0u);
  EXPECT_EQ(truth.read("region_vertices").size() * 3, kappa.size());
  for (std::size_t i = 0; i < kappa.size(); i += 3) {
    EXPECT_GE(kappa[i], 0.1);
    EXPECT_LE(kappa[i], 0.6);  // the coarse mesh's thickness range
    EXPECT_GE(kappa[i + 1], 500.0);
    EXPECT_LE(kappa[i + 2], 50000.0);
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "gt" / "truth" / "true_material.json"));
  const nlohmann::json summary = read_json(dir / "gt" / "summary.json");
  ASSERT_EQ(summary.at("cases").size(), 2u);
  for (const auto& c : summary.at("cases")) EXPECT_GT(c.at("sigma_mean_mm").get<double>(), 0.0);
}

// A user's truth (`--truth-model`): the truth's κ at the model's control points is the model's κ(β) (SFLSH eq. 1),
// and a rerun into the same folder with the built-in truth does not reuse the cached cases of the other truth.
TEST(GroundTruthCommand, TruthModelRoundTripsAtItsControlPoints) {
  const std::filesystem::path dir = sflsh::testing::scratch_dir();
  const std::filesystem::path model_path = std::filesystem::path(SFLSH_DATA_DIR) / "shape_models" / "default.toml";
  const std::string common =
      "groundtruth --subjects OPEN_TRAIN_2 --motions running_on_spot --frames 4 --mesh coarse --out " +
      (dir / "gt").string();
  auto r = sflsh::testing::run_sflsh(common + " --truth-model " + model_path.string(), dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const body::BodyModel body = body::load_body(std::filesystem::path(SFLSH_DATA_DIR) / "open_body.npz");
  const reduced::ShapeModelFile model = reduced::load_shape_model_file(model_path);
  const body::Betas beta = body::find_subject(body::default_subjects(), "OPEN_TRAIN_2").beta;
  const material::KappaMatrix expected = reduced::material_for_beta(model, body, beta).kappa();
  auto truth_at_controls = [&] {
    const npz::Reader truth(dir / "gt" / "truth" / "OPEN_TRAIN_2.npz");
    const std::vector<double> kappa = truth.read("kappa").to_doubles();
    const std::vector<double> region = truth.read("region_vertices").to_doubles();
    material::KappaMatrix out(model.num_controls(), 3);
    for (int i = 0; i < model.num_controls(); ++i) {
      const auto at = std::find(region.begin(), region.end(), static_cast<double>(model.control_points[i].vertex));
      EXPECT_NE(at, region.end()) << "control point " << i << " is not a region vertex";
      const auto row = static_cast<std::size_t>(at - region.begin());
      for (int c = 0; c < 3; ++c) out(i, c) = kappa[3 * row + static_cast<std::size_t>(c)];
    }
    return out;
  };
  const material::KappaMatrix got = truth_at_controls();
  // The basis interpolates its control points (φ_i(s_j) = δ_ij), so only rounding separates the two.
  EXPECT_LT((got - expected).cwiseQuotient(expected).cwiseAbs().maxCoeff(), 1e-9) << got << "\n" << expected;
  EXPECT_NE(sflsh::testing::text_of(dir / "gt" / "truth" / "true_material.json").find("shape model"),
            std::string::npos);
  // The built-in truth into the same folder: recomputed, not read from the other truth's cache.
  r = sflsh::testing::run_sflsh(common, dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_GT((truth_at_controls() - expected).cwiseQuotient(expected).cwiseAbs().maxCoeff(), 1e-3);
}

TEST(GroundTruthCommand, BadTruthModelFailsWithOneLineAndNoOutput) {
  const std::filesystem::path dir = sflsh::testing::scratch_dir();
  const std::filesystem::path bad = dir / "truth.toml";
  {
    std::string text = sflsh::testing::text_of(std::filesystem::path(SFLSH_DATA_DIR) / "shape_models" / "default.toml");
    text.replace(text.find("body = 'open_body'"), 18, "body = 'someone'");
    std::ofstream(bad) << text;
  }
  const auto r = sflsh::testing::run_sflsh(
      "groundtruth --subjects OPEN_TRAIN_2 --motions running_on_spot --frames 4 "
      "--mesh coarse --truth-model " +
          bad.string() + " --out " + (dir / "gt").string(),
      dir);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(bad.string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("body"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "gt" / "groundtruth.h5"));
}

TEST(GroundTruthCommand, UnknownSubjectFailsWithoutOutput) {
  const std::filesystem::path dir = sflsh::testing::scratch_dir();
  const auto r = sflsh::testing::run_sflsh(
      "groundtruth --subjects NOBODY --motions running_on_spot --frames 4 --out " + (dir / "gt").string(), dir);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("NOBODY"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "gt" / "groundtruth.h5"));
}

}  // namespace sflsh
