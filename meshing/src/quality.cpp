// Element quality of linear tets: signed volume, dihedral angles, radius–edge ratio.
//
// For a tet x0..x3 with edge vectors a = x1 − x0, b = x2 − x0, c = x3 − x0:
//   volume   V = a·(b × c) / 6                              (positive for the orientation we store)
//   circumcentre offset from x0 (Shewchuk, "Lecture notes on geometric robustness", §4):
//            o = (|a|² b×c + |b|² c×a + |c|² a×b) / (2 a·(b × c)),   R = |o|
//   dihedral angle at the edge shared by the faces opposite vertices k and l, with n_k the area
//   normals of the faces all taken outward (or all inward):  cos θ_kl = −n_k·n_l / (|n_k| |n_l|).
// A regular tet has θ = acos(1/3) = 70.53° at every edge and R / edge = √6/4 = 0.612.
#include <sflsh/meshing/quality.hpp>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace sflsh::meshing {
namespace {

constexpr double kDegenerateVolume = 1e-12;  // relative to (mean edge)³
constexpr double kDegenerateDihedralDeg = 0.1;

struct TetMeasures {
  double volume = 0.0;
  double mean_edge = 0.0;
  double radius_edge = 0.0;
  std::array<double, 6> dihedral_deg{};
};

TetMeasures measure_tet(const RowMatrixX3d& nodes, const RowMatrixX4i& tets, Eigen::Index e) {
  std::array<Eigen::Vector3d, 4> x;
  for (int k = 0; k < 4; ++k) x[static_cast<std::size_t>(k)] = nodes.row(tets(e, k)).transpose();
  const Eigen::Vector3d a = x[1] - x[0], b = x[2] - x[0], c = x[3] - x[0];
  const double triple = a.dot(b.cross(c));

  TetMeasures m;
  m.volume = triple / 6.0;

  // Edges: shortest and mean.
  double shortest = std::numeric_limits<double>::infinity(), sum = 0.0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) {
      const double length = (x[static_cast<std::size_t>(j)] - x[static_cast<std::size_t>(i)]).norm();
      shortest = std::min(shortest, length);
      sum += length;
    }
  m.mean_edge = sum / 6.0;

  // Circumradius over shortest edge; infinite for flat tets or coincident nodes.
  const Eigen::Vector3d numerator =
      a.squaredNorm() * b.cross(c) + b.squaredNorm() * c.cross(a) + c.squaredNorm() * a.cross(b);
  const double radius =
      triple != 0.0 ? numerator.norm() / (2.0 * std::abs(triple)) : std::numeric_limits<double>::infinity();
  m.radius_edge = shortest > 0.0 ? radius / shortest : std::numeric_limits<double>::infinity();

  // Area normals of the faces opposite each vertex, consistently oriented (outward for V > 0).
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::array<Eigen::Vector3d, 4> normal;
  for (int k = 0; k < 4; ++k) {
    const auto& p = x[static_cast<std::size_t>(kFace[k][0])];
    normal[static_cast<std::size_t>(k)] =
        (x[static_cast<std::size_t>(kFace[k][1])] - p).cross(x[static_cast<std::size_t>(kFace[k][2])] - p);
  }
  int slot = 0;
  for (int k = 0; k < 4; ++k)
    for (int l = k + 1; l < 4; ++l) {
      const auto& nk = normal[static_cast<std::size_t>(k)];
      const auto& nl = normal[static_cast<std::size_t>(l)];
      const double scale = nk.norm() * nl.norm();
      // A face of zero area makes the angle undefined; report 0° so the tet counts as degenerate.
      const double cosine = scale > 0.0 ? std::clamp(-nk.dot(nl) / scale, -1.0, 1.0) : 1.0;
      m.dihedral_deg[static_cast<std::size_t>(slot++)] = std::acos(cosine) * 180.0 / std::numbers::pi;
    }
  return m;
}

bool is_degenerate(const TetMeasures& m) {
  const double min_dihedral = *std::min_element(m.dihedral_deg.begin(), m.dihedral_deg.end());
  return std::abs(m.volume) < kDegenerateVolume * m.mean_edge * m.mean_edge * m.mean_edge ||
         min_dihedral < kDegenerateDihedralDeg;
}

}  // namespace

TetQuality tet_quality(const RowMatrixX3d& nodes, const RowMatrixX4i& tets) {
  const Eigen::Index count = tets.rows();
  TetQuality quality;
  quality.volume.resize(count);
  quality.min_dihedral_deg.resize(count);
  quality.radius_edge.resize(count);
  quality.degenerate.resize(static_cast<std::size_t>(count));
  for (Eigen::Index e = 0; e < count; ++e) {
    const TetMeasures m = measure_tet(nodes, tets, e);
    quality.degenerate[static_cast<std::size_t>(e)] = is_degenerate(m) ? 1 : 0;
    quality.volume(e) = m.volume;
    quality.min_dihedral_deg(e) = *std::min_element(m.dihedral_deg.begin(), m.dihedral_deg.end());
    quality.radius_edge(e) = m.radius_edge;
  }
  return quality;
}

bool tets_valid(const RowMatrixX3d& nodes, const RowMatrixX4i& tets) {
  if (tets.rows() == 0) return false;
  // θ < 0.1° ⇔ cos θ > cos 0.1° (cos θ_kl = −n_k·n_l / (|n_k| |n_l|), as in measure_tet).
  const double cos_min = std::cos(kDegenerateDihedralDeg * std::numbers::pi / 180.0);
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  for (Eigen::Index e = 0; e < tets.rows(); ++e) {
    std::array<Eigen::Vector3d, 4> x;
    for (int k = 0; k < 4; ++k) x[static_cast<std::size_t>(k)] = nodes.row(tets(e, k)).transpose();
    const Eigen::Vector3d a = x[1] - x[0], b = x[2] - x[0], c = x[3] - x[0];
    const double volume = a.dot(b.cross(c)) / 6.0;
    if (!(volume > 0.0)) return false;
    double sum = 0.0;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) sum += (x[static_cast<std::size_t>(j)] - x[static_cast<std::size_t>(i)]).norm();
    const double mean_edge = sum / 6.0;
    if (volume < kDegenerateVolume * mean_edge * mean_edge * mean_edge) return false;
    std::array<Eigen::Vector3d, 4> normal;
    for (int k = 0; k < 4; ++k) {
      const auto& p = x[static_cast<std::size_t>(kFace[k][0])];
      normal[static_cast<std::size_t>(k)] =
          (x[static_cast<std::size_t>(kFace[k][1])] - p).cross(x[static_cast<std::size_t>(kFace[k][2])] - p);
    }
    for (int k = 0; k < 4; ++k)
      for (int l = k + 1; l < 4; ++l) {
        const auto& nk = normal[static_cast<std::size_t>(k)];
        const auto& nl = normal[static_cast<std::size_t>(l)];
        const double scale = nk.norm() * nl.norm();
        if (!(scale > 0.0) || -nk.dot(nl) > cos_min * scale) return false;
      }
  }
  return true;
}

QualityReport quality_report(const RowMatrixX3d& nodes, const RowMatrixX4i& tets) {
  QualityReport report;
  report.tets = static_cast<long>(tets.rows());
  report.nodes = static_cast<long>(nodes.rows());
  if (tets.rows() == 0) return report;

  std::vector<double> dihedrals;
  dihedrals.reserve(static_cast<std::size_t>(6 * tets.rows()));
  report.min_dihedral_deg = 180.0;
  report.max_dihedral_deg = 0.0;
  report.min_volume = std::numeric_limits<double>::infinity();
  for (Eigen::Index e = 0; e < tets.rows(); ++e) {
    const TetMeasures m = measure_tet(nodes, tets, e);
    for (double angle : m.dihedral_deg) {
      dihedrals.push_back(angle);
      report.min_dihedral_deg = std::min(report.min_dihedral_deg, angle);
      report.max_dihedral_deg = std::max(report.max_dihedral_deg, angle);
    }
    report.max_radius_edge = std::max(report.max_radius_edge, m.radius_edge);
    report.min_volume = std::min(report.min_volume, m.volume);
    report.total_volume += m.volume;
    if (m.volume <= 0.0) ++report.inverted;
    if (is_degenerate(m)) ++report.degenerate;
  }
  const auto middle = dihedrals.begin() + static_cast<std::ptrdiff_t>(dihedrals.size() / 2);
  std::nth_element(dihedrals.begin(), middle, dihedrals.end());
  report.median_dihedral_deg = *middle;
  return report;
}

void to_json(nlohmann::json& json, const QualityReport& report) {
  // Non-finite values (the radius–edge ratio of a flat tet) are written as null by nlohmann::json.
  json = nlohmann::json{{"tets", report.tets},
                        {"nodes", report.nodes},
                        {"min_dihedral_deg", report.min_dihedral_deg},
                        {"median_dihedral_deg", report.median_dihedral_deg},
                        {"max_dihedral_deg", report.max_dihedral_deg},
                        {"max_radius_edge", report.max_radius_edge},
                        {"min_volume_m3", report.min_volume},
                        {"total_volume_m3", report.total_volume},
                        {"inverted", report.inverted},
                        {"degenerate", report.degenerate},
                        {"thickness_min_m", report.thickness_min},
                        {"thickness_median_m", report.thickness_median},
                        {"thickness_max_m", report.thickness_max},
                        {"valid", report.valid()}};
}

}  // namespace sflsh::meshing
