#pragma once
// A parametric body in SMPL's array layout (Loper et al. 2015; docs/physics.md §3.1).
// Units: metres, Y up, the body faces +Z, its left side is +X (as SMPL).
#include <sflsh/core/eigen_types.hpp>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <array>
#include <string>
#include <vector>

namespace sflsh::body {

inline constexpr int kNumJoints = 24;
inline constexpr int kNumBetas = 10;
inline constexpr int kNumPoseFeatures = 207;  // 23 joints × 9 entries of (R − I)

/// SMPL's joint names in index order.
extern const std::array<const char*, kNumJoints> kJointNames;
/// SMPL's parents (kintree_table row 0); -1 for the root (pelvis).
extern const std::array<int, kNumJoints> kJointParents;

/// Index of a joint by SMPL name; throws sflsh::Error for an unknown name.
int joint_index(const std::string& name);

using sflsh::RowMatrixX3d;  // core/eigen_types.hpp
using sflsh::RowMatrixX3i;

/// The arrays of a body model. n = vertex count, m = face count.
struct BodyModel {
  std::string name;         ///< e.g. "sflsh-open-body" or the file stem of a SMPL file
  RowMatrixX3d v_template;  ///< n×3 rest template [m]
  RowMatrixX3i faces;       ///< m×3 vertex indices, counter-clockwise seen from outside
  /// shapedirs (n×3×B): stored as a (3n)×B matrix, row 3v+c = shapedirs[v, c, :]. B ≥ 10; only
  /// the first kNumBetas columns are used.
  Eigen::MatrixXd shapedirs;
  /// posedirs (n×3×207) as (3n)×207, row 3v+c; empty when the model has no pose correctives.
  Eigen::MatrixXd posedirs;
  Eigen::SparseMatrix<double, Eigen::RowMajor> joint_regressor;  ///< 24×n
  Eigen::MatrixXd weights;                                       ///< n×24 skinning weights, rows sum to 1
  std::array<int, kNumJoints> parents = kJointParents;           ///< kintree_table row 0 (-1 = root)

  Eigen::Index num_vertices() const { return v_template.rows(); }
  Eigen::Index num_faces() const { return faces.rows(); }
  bool has_pose_correctives() const { return posedirs.size() > 0; }

  /// Checks sizes, index ranges, finiteness and the kinematic tree; throws sflsh::Error
  /// "<name>: <array>: found, expected".
  void validate() const;
  /// The same checks, the message starting with `source` (e.g. the file the model was read from).
  void validate(const std::string& source) const;
};

}  // namespace sflsh::body
