#pragma once
// A small random body model in SMPL layout, built by the tests themselves (no data files):
// SMPL's 24-joint tree with plausible rest joints, vertices scattered around the bones, random
// normalized skinning weights over nearby joints, random shape and pose blend shapes.
#include <sflsh/body/body_model.hpp>

#include <random>

namespace sflsh::testing {

inline body::BodyModel synthetic_body(int vertices_per_joint = 6, bool with_posedirs = true, unsigned seed = 7) {
  using namespace sflsh::body;
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  // Rest joints of a T-posed person [m] (x = body's left).
  const double joints[kNumJoints][3] = {
      {0, 0, 0},         {0.09, -0.08, 0},   {-0.09, -0.08, 0},   {0, 0.1, 0},          {0.1, -0.48, 0},
      {-0.1, -0.48, 0},  {0, 0.23, 0},       {0.1, -0.88, -0.02}, {-0.1, -0.88, -0.02}, {0, 0.29, 0.02},
      {0.1, -0.94, 0.1}, {-0.1, -0.94, 0.1}, {0, 0.5, 0},         {0.07, 0.4, 0},       {-0.07, 0.4, 0},
      {0, 0.6, 0.03},    {0.18, 0.42, 0},    {-0.18, 0.42, 0},    {0.45, 0.42, 0},      {-0.45, 0.42, 0},
      {0.7, 0.42, 0},    {-0.7, 0.42, 0},    {0.78, 0.42, 0},     {-0.78, 0.42, 0}};
  BodyModel model;
  model.name = "synthetic";
  const int n = kNumJoints * vertices_per_joint;
  model.v_template.resize(n, 3);
  model.weights = Eigen::MatrixXd::Zero(n, kNumJoints);
  std::vector<Eigen::Triplet<double>> regressor;
  for (int k = 0; k < kNumJoints; ++k) {
    for (int j = 0; j < vertices_per_joint; ++j) {
      const int v = k * vertices_per_joint + j;
      for (int c = 0; c < 3; ++c) model.v_template(v, c) = joints[k][c] + 0.04 * normal(rng);
      const int parent = kJointParents[static_cast<std::size_t>(k)];
      const double a = 0.4 + 0.6 * uniform(rng);
      model.weights(v, k) = a;
      model.weights(v, parent >= 0 ? parent : 3) += 1.0 - a;
      regressor.emplace_back(k, v, 1.0 / vertices_per_joint);
    }
  }
  // Make the regressor hit the listed joints exactly at β = 0 by shifting each vertex group.
  for (int k = 0; k < kNumJoints; ++k) {
    const auto block = model.v_template.middleRows(k * vertices_per_joint, vertices_per_joint);
    const Eigen::RowVector3d mean = block.colwise().mean();
    const Eigen::RowVector3d target(joints[k][0], joints[k][1], joints[k][2]);
    model.v_template.middleRows(k * vertices_per_joint, vertices_per_joint).rowwise() += target - mean;
  }
  model.joint_regressor.resize(kNumJoints, n);
  model.joint_regressor.setFromTriplets(regressor.begin(), regressor.end());
  // Faces only need valid indices for the layout checks here.
  model.faces.resize(n - 2, 3);
  for (int f = 0; f < n - 2; ++f) model.faces.row(f) << f, f + 1, f + 2;
  model.shapedirs.resize(3 * n, kNumBetas);
  for (Eigen::Index i = 0; i < model.shapedirs.size(); ++i) model.shapedirs.data()[i] = 0.01 * normal(rng);
  if (with_posedirs) {
    model.posedirs.resize(3 * n, kNumPoseFeatures);
    for (Eigen::Index i = 0; i < model.posedirs.size(); ++i) model.posedirs.data()[i] = 0.002 * normal(rng);
  }
  return model;
}

}  // namespace sflsh::testing
