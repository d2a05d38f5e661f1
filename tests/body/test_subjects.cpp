#include "scratch_dir.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/error.hpp>

#include <gmock/gmock.h>

#include <fstream>

namespace sflsh {

using ::testing::HasSubstr;

TEST(Subjects, PaperTableOneIsShipped) {
  const auto subjects = body::load_subjects(std::filesystem::path(SFLSH_DATA_DIR) / "subjects.toml");
  ASSERT_EQ(subjects.size(), 10u);
  const body::Subject& dyna1 = body::find_subject(subjects, "DYNA_1");
  EXPECT_EQ(dyna1.split, "train");
  EXPECT_DOUBLE_EQ(dyna1.beta(4), 2.74);
  EXPECT_DOUBLE_EQ(body::find_subject(subjects, "TEST_3").beta(9), 3.41);
  EXPECT_THAT([&] { body::find_subject(subjects, "NOBODY"); },
              ::testing::ThrowsMessage<Error>(HasSubstr("unknown subject 'NOBODY' (known: DYNA_1")));
}

TEST(Subjects, SaveLoadRoundTrip) {
  const auto dir = sflsh::testing::scratch_dir();
  body::Subject s{"A", "test", "open", "a \"quoted\" description", body::Betas::LinSpaced(10, -1.0, 1.0)};
  body::save_subjects(dir / "s.toml", {s}, "header line 1\nheader line 2");
  const auto back = body::load_subjects(dir / "s.toml");
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].description, s.description);
  EXPECT_TRUE(back[0].beta.isApprox(s.beta, 1e-4));
}

TEST(Subjects, ErrorsNameFileLineAndField) {
  const auto dir = sflsh::testing::scratch_dir();
  auto expect_error = [&](const std::string& text, const std::string& message) {
    std::ofstream(dir / "s.toml") << text;
    EXPECT_THAT([&] { body::load_subjects(dir / "s.toml"); }, ::testing::ThrowsMessage<Error>(HasSubstr(message)))
        << text;
  };
  expect_error("[[subject]]\nname = \"A\"\nsplit = \"train\"\nbeta = [1, 2]\n",
               "s.toml:4: subject 'A' has 2 beta values, expected 10");
  expect_error("[[subject]]\nname = \"A\"\nsplit = \"val\"\nbeta = [0,0,0,0,0,0,0,0,0,0]\n",
               "split 'val', expected train or test");
  expect_error("[[subject]]\nname = \"A\"\nsplit = \"train\"\nheight = 3\nbeta = [0,0,0,0,0,0,0,0,0,0]\n",
               "s.toml:4: unknown field 'height'");
  expect_error("[[subject]]\nsplit = \"train\"\nbeta = [0,0,0,0,0,0,0,0,0,0]\n", "missing field 'name'");
  expect_error("[[subject]]\nname = \"A\"\nsplit = \"train\"\nbeta = [0,0,\"x\",0,0,0,0,0,0,0]\n",
               "beta[2] is not a finite number");
  expect_error("[[subject]\n", "s.toml:1:");
  EXPECT_THAT([&] { body::load_subjects(dir / "none.toml"); },
              ::testing::ThrowsMessage<Error>(HasSubstr("none.toml: subjects file not found")));
}

TEST(Subjects, ParseBetas) {
  EXPECT_TRUE(body::parse_betas("1 2 3").isApprox((body::Betas() << 1, 2, 3, 0, 0, 0, 0, 0, 0, 0).finished()));
  EXPECT_TRUE(body::parse_betas("[1.5, -2e-1]").head<2>().isApprox(Eigen::Vector2d(1.5, -0.2)));
  EXPECT_THAT([] { body::parse_betas("1 2 x"); }, ::testing::ThrowsMessage<Error>(HasSubstr("'x' is not a number")));
  EXPECT_THAT([] { body::parse_betas("1 2 3 4 5 6 7 8 9 10 11"); },
              ::testing::ThrowsMessage<Error>(HasSubstr("more than 10")));
  EXPECT_THAT([] { body::parse_betas("nan"); }, ::testing::ThrowsMessage<Error>(HasSubstr("not a number")));
  EXPECT_THROW(body::parse_betas(""), Error);
}

}  // namespace sflsh
