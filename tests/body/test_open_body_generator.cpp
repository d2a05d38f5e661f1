// `sflsh body generate` reproduces the shipped open body: one generation with default options is
// compared with data/open_body.npz and data/open_body_subjects.toml (which also proves the
// generator deterministic across runs), plus the PCA's explained variance and option checks.
#include <sflsh/body/body_io.hpp>
#include <sflsh/body/open_body.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/error.hpp>

#include <gtest/gtest.h>

#include <filesystem>

using namespace sflsh::body;

TEST(OpenBodyGenerator, ReproducesTheShippedDataAndExplainsThePopulation) {
  const OpenBodyResult generated = generate_open_body();
  const BodyModel shipped = load_body(std::filesystem::path(SFLSH_DATA_DIR) / "open_body.npz");
  const BodyModel& g = generated.model;
  ASSERT_EQ(g.num_vertices(), shipped.num_vertices()) << "regenerate with `sflsh body generate`";
  EXPECT_TRUE(g.faces == shipped.faces);
  // The .npz stores float64 exactly; the tolerance only absorbs summation-order differences of
  // threaded reductions on another CPU (far below the 0.1 mm that would be visible).
  EXPECT_LT((g.v_template - shipped.v_template).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((g.shapedirs - shipped.shapedirs).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((g.weights - shipped.weights).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((Eigen::MatrixXd(g.joint_regressor) - Eigen::MatrixXd(shipped.joint_regressor)).cwiseAbs().maxCoeff(),
            1e-9);

  const auto subjects = load_subjects(std::filesystem::path(SFLSH_DATA_DIR) / "open_body_subjects.toml");
  ASSERT_EQ(subjects.size(), generated.subjects.size());
  for (std::size_t s = 0; s < subjects.size(); ++s) {
    EXPECT_EQ(subjects[s].name, generated.subjects[s].name);
    EXPECT_LT((subjects[s].beta - generated.subjects[s].beta).cwiseAbs().maxCoeff(), 1e-4)  // 4 decimals in TOML
        << subjects[s].name;
  }

  const Eigen::VectorXd& ev = generated.explained_variance;
  for (Eigen::Index m = 0; m + 1 < ev.size(); ++m) EXPECT_GE(ev(m), ev(m + 1));
  EXPECT_GT(ev(0), 0.3);
  EXPECT_GT(ev.sum(), 0.99) << "10 components should capture the 10-factor population";
}

TEST(OpenBodyGenerator, RejectsTooSmallPopulation) {
  OpenBodyOptions options;
  options.population = 5;
  EXPECT_THROW(generate_open_body(options), sflsh::Error);
}
