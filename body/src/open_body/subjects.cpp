#include "subjects.hpp"

#include "factors.hpp"

#include <initializer_list>
#include <utility>

namespace sflsh::body::detail {
namespace {

OpenBodySubject subject(const char* name, const char* split, const char* description,
                        std::initializer_list<std::pair<Factor, double>> factors) {
  OpenBodySubject s;
  s.name = name;
  s.split = split;
  s.description = description;
  s.factors.setZero();
  for (const auto& [factor, value] : factors) s.factors(factor) = value;
  s.beta.setZero();
  return s;
}

}  // namespace

std::vector<OpenBodySubject> open_body_subject_definitions() {
  // Train subjects probe the features of the paper's Table 1 (average, pear, large chest, tall and
  // thin, heavy); test subjects 1–5 vary them so that none coincides with a train subject (extrapolation),
  // 6 and 7 keep one train subject's body part (locality).
  return {
      subject("OPEN_TRAIN_1", "train", "average body (all factors zero)", {}),
      subject("OPEN_TRAIN_2", "train", "pear shape: wide hips, heavy thighs and buttocks, narrow shoulders",
              {{kHipWidth, 2.0}, {kThighGirth, 1.5}, {kButtocks, 1.5}, {kShoulderWidth, -1.5}, {kChest, -0.5}}),
      subject("OPEN_TRAIN_3", "train", "large chest", {{kChest, 2.5}, {kGirth, 0.5}}),
      subject("OPEN_TRAIN_4", "train", "tall and thin",
              {{kStature, 2.0}, {kGirth, -1.5}, {kTorsoLength, 1.0}, {kThighGirth, -1.0}, {kArmGirth, -1.0}}),
      subject("OPEN_TRAIN_5", "train", "heavy with a large belly",
              {{kGirth, 2.0}, {kBelly, 2.5}, {kThighGirth, 1.0}, {kArmGirth, 1.0}, {kChest, 0.5}}),
      subject("OPEN_TEST_1", "test", "slightly short, slightly heavy, otherwise average",
              {{kStature, -1.0}, {kGirth, 0.5}, {kBelly, 0.5}}),
      subject("OPEN_TEST_2", "test", "short pear shape: wide hips, large buttocks",
              {{kStature, -1.0}, {kHipWidth, 1.5}, {kButtocks, 2.0}, {kThighGirth, 1.0}}),
      subject("OPEN_TEST_3", "test", "large chest and broad shoulders", {{kChest, 2.0}, {kShoulderWidth, 1.5}}),
      subject("OPEN_TEST_4", "test", "short and thin", {{kStature, -2.0}, {kGirth, -1.5}, {kBelly, -1.0}}),
      subject("OPEN_TEST_5", "test", "heavy with large buttocks and belly",
              {{kGirth, 1.5}, {kBelly, 1.5}, {kButtocks, 2.0}, {kThighGirth, 0.5}}),
      // Locality probes (the paper's TEST 1 has the upper body of DYNA 1): one body part as a train subject's,
      // the rest of the body different enough that β differs by ≥ 2 in norm (tests/body/test_open_body.cpp).
      subject("OPEN_TEST_6", "test", "the large chest of OPEN_TRAIN_3 on a pear-shaped lower body",
              {{kChest, 2.5}, {kGirth, 0.5}, {kHipWidth, 2.0}, {kThighGirth, 1.5}, {kButtocks, 1.5}}),
      subject("OPEN_TEST_7", "test", "the hips, thighs and buttocks of OPEN_TRAIN_2 under a heavy upper body",
              {{kHipWidth, 2.0},
               {kThighGirth, 1.5},
               {kButtocks, 1.5},
               {kShoulderWidth, 1.0},
               {kChest, 1.5},
               {kBelly, 1.5}}),
  };
}

}  // namespace sflsh::body::detail
