#include <sflsh/body/body_model.hpp>
#include <sflsh/core/error.hpp>

#include <algorithm>
#include <cmath>

namespace sflsh::body {

const std::array<const char*, kNumJoints> kJointNames = {
    "pelvis",     "left_hip",    "right_hip",    "spine1",      "left_knee",     "right_knee",
    "spine2",     "left_ankle",  "right_ankle",  "spine3",      "left_foot",     "right_foot",
    "neck",       "left_collar", "right_collar", "head",        "left_shoulder", "right_shoulder",
    "left_elbow", "right_elbow", "left_wrist",   "right_wrist", "left_hand",     "right_hand"};

const std::array<int, kNumJoints> kJointParents = {-1, 0, 0, 0,  1,  2,  3,  4,  5,  6,  7,  8,
                                                   9,  9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21};

int joint_index(const std::string& name) {
  for (int k = 0; k < kNumJoints; ++k)
    if (name == kJointNames[static_cast<std::size_t>(k)]) return k;
  throw_error("unknown joint '{}' (expected one of SMPL's 24 joint names, e.g. 'left_hip')", name);
}

void BodyModel::validate() const { validate(name.empty() ? std::string("body model") : name); }

void BodyModel::validate(const std::string& who) const {
  const Eigen::Index n = num_vertices();
  require(n >= 4, "{}: v_template: {} rows, expected (n, 3) with n >= 4", who, n);
  require(v_template.allFinite(), "{}: v_template: non-finite values, expected finite positions [m]", who);
  require(faces.rows() >= 4, "{}: f: {} rows, expected (m, 3) with m >= 4", who, faces.rows());
  require(faces.minCoeff() >= 0 && faces.maxCoeff() < n, "{}: f: vertex indices {}..{}, expected 0..{}", who,
          faces.minCoeff(), faces.maxCoeff(), n - 1);
  require(shapedirs.rows() == 3 * n && shapedirs.cols() >= kNumBetas,
          "{}: shapedirs: ({}, 3, {}), expected ({}, 3, >= {})", who, shapedirs.rows() / 3, shapedirs.cols(), n,
          kNumBetas);
  require(shapedirs.allFinite(), "{}: shapedirs: non-finite values, expected finite displacements [m]", who);
  if (posedirs.size() > 0) {
    require(posedirs.rows() == 3 * n && posedirs.cols() == kNumPoseFeatures,
            "{}: posedirs: ({}, 3, {}), expected ({}, 3, {})", who, posedirs.rows() / 3, posedirs.cols(), n,
            kNumPoseFeatures);
    require(posedirs.allFinite(), "{}: posedirs: non-finite values, expected finite displacements [m]", who);
  }
  require(joint_regressor.rows() == kNumJoints && joint_regressor.cols() == n,
          "{}: J_regressor: ({}, {}), expected ({}, {})", who, joint_regressor.rows(), joint_regressor.cols(),
          kNumJoints, n);
  for (int k = 0; k < kNumJoints; ++k) {
    double sum = 0.0;
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(joint_regressor, k); it; ++it) {
      require(std::isfinite(it.value()),
              "{}: J_regressor: row {} ({}) holds a non-finite value, expected finite weights", who, k,
              kJointNames[static_cast<std::size_t>(k)]);
      sum += it.value();
    }
    require(std::abs(sum - 1.0) < 1e-3, "{}: J_regressor: row {} ({}) sums to {:.6f}, expected 1", who, k,
            kJointNames[static_cast<std::size_t>(k)], sum);
  }
  require(weights.rows() == n && weights.cols() == kNumJoints, "{}: weights: ({}, {}), expected ({}, {})", who,
          weights.rows(), weights.cols(), n, kNumJoints);
  require(weights.allFinite(), "{}: weights: non-finite values, expected finite skinning weights", who);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double sum = weights.row(i).sum();
    require(std::abs(sum - 1.0) < 1e-3, "{}: weights: row {} sums to {:.6f}, expected 1", who, i, sum);
  }
  require(parents[0] == -1, "{}: kintree_table[0, 0]: {}, expected the root marker (-1 or 4294967295)", who,
          parents[0]);
  for (int k = 1; k < kNumJoints; ++k) {
    const int p = parents[static_cast<std::size_t>(k)];
    require(p >= 0 && p < k, "{}: kintree_table[0, {}]: parent {}, expected a parent index in 0..{}", who, k, p, k - 1);
  }
}

}  // namespace sflsh::body
