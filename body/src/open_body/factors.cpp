#include "factors.hpp"

#include <sflsh/core/error.hpp>

#include <Eigen/Cholesky>

#include <cmath>
#include <numbers>
#include <random>

namespace sflsh::body {

const std::array<const char*, kNumAnthroFactors> kAnthroFactorNames = {
    "stature", "girth",    "shoulder_width", "hip_width", "chest",
    "belly",   "buttocks", "thigh_girth",    "arm_girth", "torso_length"};

}  // namespace sflsh::body

namespace sflsh::body::detail {

FactorMatrix factor_correlation() {
  FactorMatrix c = FactorMatrix::Identity();
  const auto couple = [&c](Factor i, Factor j, double r) { c(i, j) = c(j, i) = r; };
  couple(kGirth, kBelly, 0.5);
  couple(kGirth, kThighGirth, 0.35);
  couple(kGirth, kArmGirth, 0.35);
  couple(kGirth, kChest, 0.3);
  couple(kGirth, kButtocks, 0.3);
  couple(kStature, kShoulderWidth, 0.3);
  couple(kHipWidth, kButtocks, 0.3);
  couple(kHipWidth, kThighGirth, 0.2);
  return c;
}

std::vector<AnthroFactors> sample_population(int count, unsigned seed) {
  require(count >= 0, "open body: negative population size {}", count);
  const Eigen::LLT<FactorMatrix> llt(factor_correlation());
  require(llt.info() == Eigen::Success, "open body: factor correlation matrix is not positive definite");
  const FactorMatrix lower = llt.matrixL();

  std::mt19937 engine(seed);
  // Uniform in (0, 1) from one 32-bit draw; Box–Muller turns two of them into two normals.
  const auto uniform = [&engine]() { return (static_cast<double>(engine()) + 0.5) / 4294967296.0; };
  std::vector<AnthroFactors> population(static_cast<std::size_t>(count));
  for (auto& z : population) {
    AnthroFactors white;
    for (int i = 0; i < kNumAnthroFactors; i += 2) {
      const double radius = std::sqrt(-2.0 * std::log(uniform()));
      const double angle = 2.0 * std::numbers::pi * uniform();
      white(i) = radius * std::cos(angle);
      if (i + 1 < kNumAnthroFactors) white(i + 1) = radius * std::sin(angle);
    }
    z = lower * white;
  }
  return population;
}

}  // namespace sflsh::body::detail
