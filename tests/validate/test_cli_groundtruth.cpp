// `sflsh groundtruth`: the synthetic ground truth in the DYNA layout with the true parameters beside it.
#include "run_command.hpp"
#include "scratch_dir.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/npz.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/validate/dyna_file.hpp>

#include <gtest/gtest.h>

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

TEST(GroundTruthCommand, UnknownSubjectFailsWithoutOutput) {
  const std::filesystem::path dir = sflsh::testing::scratch_dir();
  const auto r = sflsh::testing::run_sflsh(
      "groundtruth --subjects NOBODY --motions running_on_spot --frames 4 --out " + (dir / "gt").string(), dir);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("NOBODY"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "gt" / "groundtruth.h5"));
}

}  // namespace sflsh
