// Choosing λ from a leave-one-out sweep: the least-error rule and the one-standard-error rule on sweeps whose
// answers are worked out by hand.
#include <sflsh/core/error.hpp>
#include <sflsh/reduced/lambda_choice.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace validate = sflsh::reduced;  // validate chooses λ with these (and shapefit)

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

TEST(LambdaChoice, StandardErrorOfTheMeanSkipsMissingFolds) {
  // {1, 2, 3}: sample standard deviation 1, so the standard error of the mean is 1/√3.
  EXPECT_NEAR(validate::standard_error_of_mean({1.0, kNaN, 2.0, 3.0}), 1.0 / std::sqrt(3.0), 1e-15);
  EXPECT_EQ(validate::standard_error_of_mean({2.5}), 0.0);
  EXPECT_TRUE(std::isnan(validate::standard_error_of_mean({kNaN})));
}

TEST(LambdaChoice, FlatSweepTakesTheLargestLambdaWithinOneStandardError) {
  // The shape of the paper preset's sweep: means 2.500 … 2.502 mm, folds spread by about a millimetre.
  const std::vector<validate::LambdaScore> sweep{{0.001, {1.5, 2.5, 3.5}},
                                                 {0.01, {1.5, 2.5, 3.5}},
                                                 {1.0, {1.49, 2.5, 3.5}},  // the least: 2.49667
                                                 {10.0, {1.51, 2.5, 3.5}}};
  const validate::LambdaChoice one_se = validate::choose_lambda(sweep, validate::LambdaRule::one_standard_error, "t");
  EXPECT_EQ(one_se.least_lambda, 1.0);
  EXPECT_NEAR(one_se.least_error, 7.49 / 3.0, 1e-12);
  EXPECT_GT(one_se.standard_error, 0.5);
  EXPECT_EQ(one_se.lambda, 10.0);
  const validate::LambdaChoice least = validate::choose_lambda(sweep, validate::LambdaRule::minimum, "t");
  EXPECT_EQ(least.lambda, 1.0);
  EXPECT_EQ(least.threshold, least.least_error);
}

TEST(LambdaChoice, ClearMinimumIsKept) {
  // Folds that agree (standard error 0.01 mm) and a minimum 1 mm below its neighbours: no larger λ is within reach.
  const std::vector<validate::LambdaScore> sweep{
      {0.1, {3.0, 3.02}}, {1.0, {2.0, 2.02}}, {10.0, {3.0, 3.02}}, {100.0, {kNaN, kNaN}}};
  const validate::LambdaChoice c = validate::choose_lambda(sweep, validate::LambdaRule::one_standard_error, "t");
  EXPECT_EQ(c.lambda, 1.0);
  EXPECT_NEAR(c.standard_error, 0.01, 1e-12);
  EXPECT_NEAR(c.threshold, 2.02, 1e-12);
  EXPECT_TRUE(std::isnan(c.mean_errors[3]));
}

TEST(LambdaChoice, OneFoldFallsBackToTheLeastError) {
  const std::vector<validate::LambdaScore> sweep{{0.01, {1.0}}, {1.0, {1.001}}};
  EXPECT_EQ(validate::choose_lambda(sweep, validate::LambdaRule::one_standard_error, "t").lambda, 0.01);
}

TEST(LambdaChoice, NoFiniteErrorFailsNamingTheSweep) {
  const std::vector<validate::LambdaScore> sweep{{0.01, {kNaN}}, {1.0, {}}};
  try {
    validate::choose_lambda(sweep, validate::LambdaRule::minimum, "validate: regularizer ours");
    FAIL() << "no error";
  } catch (const sflsh::Error& e) {
    EXPECT_NE(std::string(e.what()).find("regularizer ours"), std::string::npos) << e.what();
  }
}

// The automatic grid (shapefit --lambdas auto, validate --lambda-extensions) grows by half a decade at the end where
// the error is least, stops once the least error is inside, at its bounds, or for a one-λ grid.
TEST(LambdaChoice, AGridGrowsAtTheEndWhereTheErrorIsLeast) {
  const std::vector<validate::LambdaScore> falling{{0.1, {3.0, 3.2}}, {1.0, {2.0, 2.2}}, {10.0, {1.0, 1.2}}};
  ASSERT_TRUE(validate::lambda_beyond_grid(falling).has_value());
  EXPECT_NEAR(*validate::lambda_beyond_grid(falling), 10.0 * std::sqrt(10.0), 1e-12);
  EXPECT_FALSE(validate::lambda_sweep_bracketed(falling));
  const std::vector<validate::LambdaScore> rising{{0.1, {1.0}}, {1.0, {2.0}}, {10.0, {3.0}}};
  EXPECT_NEAR(*validate::lambda_beyond_grid(rising), 0.1 / std::sqrt(10.0), 1e-15);
  const std::vector<validate::LambdaScore> bracketed{{0.1, {2.0}}, {1.0, {1.0}}, {10.0, {3.0}}};
  EXPECT_FALSE(validate::lambda_beyond_grid(bracketed).has_value());
  EXPECT_TRUE(validate::lambda_sweep_bracketed(bracketed));
  // A missing fold is left out of its λ's mean; a λ without any never is the least.
  const std::vector<validate::LambdaScore> gap{{0.1, {kNaN}}, {1.0, {1.0}}, {10.0, {3.0}}};
  EXPECT_TRUE(validate::lambda_sweep_bracketed(gap));
  EXPECT_FALSE(validate::lambda_beyond_grid({{1.0, {1.0}}}).has_value());        // one λ: a choice, not a sweep
  EXPECT_FALSE(validate::lambda_beyond_grid(rising, 0.1).has_value());           // already at the floor
  EXPECT_FALSE(validate::lambda_beyond_grid(falling, 1e-12, 10.0).has_value());  // … or the ceiling
}

TEST(LambdaChoice, RuleNamesParseAndRoundTrip) {
  EXPECT_EQ(validate::parse_lambda_rule("one-se", "x"), validate::LambdaRule::one_standard_error);
  EXPECT_EQ(validate::parse_lambda_rule("one-standard-error", "x"), validate::LambdaRule::one_standard_error);
  EXPECT_EQ(validate::parse_lambda_rule("minimum", "x"), validate::LambdaRule::minimum);
  EXPECT_EQ(validate::lambda_rule_name(validate::parse_lambda_rule("min", "x")), "min");
  EXPECT_THROW(validate::parse_lambda_rule("best", "--lambda-rule"), sflsh::Error);
}
