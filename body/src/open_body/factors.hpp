#pragma once
// The anthropometric factor space of the open body's population (each factor a standard-normal
// variate; see kAnthroFactorNames for the order).
#include <sflsh/body/open_body.hpp>

#include <Eigen/Core>

#include <vector>

namespace sflsh::body::detail {

/// Indices into AnthroFactors, in kAnthroFactorNames order.
enum Factor : int {
  kStature = 0,
  kGirth,
  kShoulderWidth,
  kHipWidth,
  kChest,
  kBelly,
  kButtocks,
  kThighGirth,
  kArmGirth,
  kTorsoLength,
};

using FactorMatrix = Eigen::Matrix<double, kNumAnthroFactors, kNumAnthroFactors>;

/// Correlation matrix of the factors in the population (unit diagonal, mild positive couplings such
/// as girth with belly, thigh and arm girth).
FactorMatrix factor_correlation();

/// Draws `count` factor vectors z ~ N(0, C), C = factor_correlation(), from std::mt19937(seed) through
/// Box–Muller (so the stream is the same with every standard library).
std::vector<AnthroFactors> sample_population(int count, unsigned seed);

}  // namespace sflsh::body::detail
