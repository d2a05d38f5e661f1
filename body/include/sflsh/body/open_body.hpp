#pragma once
// The project's own open parametric body: generated from skeleton-attached smooth implicit
// primitives, with shape directions from PCA over a sampled anthropometric population.
// No third-party body data is involved; `sflsh body generate` reproduces data/open_body.npz.
#include <sflsh/body/body_model.hpp>
#include <sflsh/body/skinning.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace sflsh::body {

/// Anthropometric factors of the population generator, each a standard-normal variate.
inline constexpr int kNumAnthroFactors = 10;
extern const std::array<const char*, kNumAnthroFactors> kAnthroFactorNames;
// stature, girth, shoulder_width, hip_width, chest, belly, buttocks, thigh_girth, arm_girth, torso_length

using AnthroFactors = Eigen::Matrix<double, kNumAnthroFactors, 1>;

struct OpenBodyOptions {
  int population = 300;        ///< sampled bodies for the shape PCA
  unsigned seed = 20231212;    ///< population sampling seed (deterministic output)
  int target_vertices = 7000;  ///< approximate vertex count of the template surface
};

/// A named subject of the open body, defined in anthropometric-factor space.
struct OpenBodySubject {
  std::string name;
  std::string split;  ///< "train" or "test"
  std::string description;
  AnthroFactors factors;
  Betas beta;  ///< its β in the generated model's PCA basis
};

struct OpenBodyResult {
  BodyModel model;
  std::vector<OpenBodySubject> subjects;
  Eigen::VectorXd explained_variance;  ///< fraction of population variance per kept component
};

/// Generates the open body (deterministic for fixed options).
OpenBodyResult generate_open_body(const OpenBodyOptions& options = {});

}  // namespace sflsh::body
