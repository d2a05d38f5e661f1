#pragma once
// Element quality of a tet mesh: the report every mesh carries (issue: quality report).
#include <sflsh/meshing/types.hpp>

#include <Eigen/Dense>
#include <nlohmann/json_fwd.hpp>

#include <vector>

namespace sflsh::meshing {

struct QualityReport {
  long tets = 0;
  long nodes = 0;
  double min_dihedral_deg = 0.0;
  double median_dihedral_deg = 0.0;
  double max_dihedral_deg = 0.0;
  double max_radius_edge = 0.0;  ///< circumradius / shortest edge (regular tet: 0.612)
  double min_volume = 0.0;       ///< signed [m³]
  double total_volume = 0.0;     ///< [m³]
  long inverted = 0;             ///< signed volume ≤ 0
  long degenerate = 0;           ///< |volume| below 1e-12 · (mean edge)³ or min dihedral < 0.1°
  /// Layer thickness h·|c − s| over the region's skin vertices [m] (zeros when not a layer mesh).
  double thickness_min = 0.0;
  double thickness_median = 0.0;
  double thickness_max = 0.0;

  bool valid() const { return tets > 0 && inverted == 0 && degenerate == 0; }
};

/// Per-tet quality measures (for VTK cell data).
struct TetQuality {
  Eigen::VectorXd volume;  ///< signed
  Eigen::VectorXd min_dihedral_deg;
  Eigen::VectorXd radius_edge;
  std::vector<char> degenerate;  ///< per tet, by QualityReport's degenerate criterion
};

/// Signed volume of tet e [m³]: det[x1 − x0, x2 − x0, x3 − x0] / 6, positive for the meshers' orientation.
inline double signed_volume(const RowMatrixX3d& nodes, const RowMatrixX4i& tets, Eigen::Index e) {
  Eigen::Matrix3d edges;
  for (int k = 0; k < 3; ++k) edges.col(k) = (nodes.row(tets(e, k + 1)) - nodes.row(tets(e, 0))).transpose();
  return edges.determinant() / 6.0;
}

TetQuality tet_quality(const RowMatrixX3d& nodes, const RowMatrixX4i& tets);
QualityReport quality_report(const RowMatrixX3d& nodes, const RowMatrixX4i& tets);
/// quality_report(nodes, tets).valid() in one cheap pass: no tet inverted or degenerate (the same volume and
/// dihedral thresholds, the angle compared through its cosine, without acos or circumradii).
bool tets_valid(const RowMatrixX3d& nodes, const RowMatrixX4i& tets);
void to_json(nlohmann::json& json, const QualityReport& report);

}  // namespace sflsh::meshing
