#pragma once
// Surfaces for the material-field tests, built here from plain arrays:
//  - a planar grid patch on [−1, 1] × [0, 1] whose diagonals are mirrored across x = 0 (open, one
//    boundary loop), with its exact mirror map;
//  - an icosphere (optionally deformed into an x-symmetric "blob"), closed, with its exact mirror map;
//  - the shipped open body's skin, and a soft-layer-like region of it (torso, upper arms, thighs by
//    dominant skinning joint; open, several boundary loops) with part ids and a nearest-vertex mirror map.
#include <sflsh/body/body_io.hpp>
#include <sflsh/material/surface_operators.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <tuple>
#include <vector>

namespace sflsh::testing {

struct FieldMesh {
  material::RowMatrixX3d V;
  material::RowMatrixX3i F;
  std::vector<int> mirror;  ///< exact or nearest-vertex mirror across x = 0
  std::vector<int> part;    ///< body region only: 0 torso, 1/2 left/right upper arm, 3/4 left/right thigh
};

/// (K+1)×(L+1) vertices; K even so that the column i = K/2 lies on the mirror plane x = 0.
inline FieldMesh grid_patch(int K = 40, int L = 20) {
  FieldMesh m;
  const auto id = [L](int i, int j) { return i * (L + 1) + j; };
  m.V.resize((K + 1) * (L + 1), 3);
  m.mirror.resize(static_cast<std::size_t>(m.V.rows()));
  for (int i = 0; i <= K; ++i)
    for (int j = 0; j <= L; ++j) {
      m.V.row(id(i, j)) << -1.0 + 2.0 * i / K, static_cast<double>(j) / L, 0.0;
      m.mirror[static_cast<std::size_t>(id(i, j))] = id(K - i, j);
    }
  m.F.resize(2 * K * L, 3);
  int f = 0;
  for (int i = 0; i < K; ++i)
    for (int j = 0; j < L; ++j) {
      const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      if (2 * i < K) {  // left half: diagonal a–c; right half: the mirrored diagonal b–d
        m.F.row(f++) << a, b, c;
        m.F.row(f++) << a, c, d;
      } else {
        m.F.row(f++) << a, b, d;
        m.F.row(f++) << b, c, d;
      }
    }
  return m;
}

/// Icosphere with 10·4^level + 2 vertices. `blob` deforms it by a map that commutes with x → −x.
inline FieldMesh icosphere(int level, bool blob = false) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p.normalize();
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> midpoint;
    const auto mid = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      if (const auto it = midpoint.find(key); it != midpoint.end()) return it->second;
      v.push_back((0.5 * (v[static_cast<std::size_t>(a)] + v[static_cast<std::size_t>(b)])).normalized());
      return midpoint[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> next;
    for (const auto& [a, b, c] : f) {
      const int ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      next.insert(next.end(), {{a, ab, ca}, {b, bc, ab}, {c, ca, bc}, {ab, bc, ca}});
    }
    f = std::move(next);
  }
  FieldMesh m;
  m.V.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) m.V.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  m.F.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i) m.F.row(static_cast<Eigen::Index>(i)) << f[i][0], f[i][1], f[i][2];
  // Exact mirror map: reflected positions are bit-identical (midpoint and normalization commute with x → −x).
  std::map<std::tuple<double, double, double>, int> index;
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) index[{m.V(i, 0), m.V(i, 1), m.V(i, 2)}] = static_cast<int>(i);
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) {
    const double mx = m.V(i, 0) == 0.0 ? 0.0 : -m.V(i, 0);  // no −0.0 keys
    m.mirror.push_back(index.at({mx, m.V(i, 1), m.V(i, 2)}));
  }
  if (blob) {
    for (Eigen::Index i = 0; i < m.V.rows(); ++i) {
      const double x = m.V(i, 0), y = m.V(i, 1), z = m.V(i, 2);
      m.V.row(i) << 1.4 * x * (1.0 + 0.3 * y), y + 0.4 * y * y + 0.2 * x * x, 0.7 * z * (1.0 + 0.2 * y);
    }
  }
  return m;
}

inline const body::BodyModel& open_body() {
  static const body::BodyModel model = body::load_body(body::default_body_path());
  return model;
}

/// Nearest vertex of each vertex's reflection across x = 0 (brute force; fine for ~7k vertices).
inline std::vector<int> nearest_mirror(const material::RowMatrixX3d& V) {
  std::vector<int> mirror(static_cast<std::size_t>(V.rows()));
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    const Eigen::RowVector3d r(-V(i, 0), V(i, 1), V(i, 2));
    Eigen::Index best = 0;
    (V.rowwise() - r).rowwise().squaredNorm().minCoeff(&best);
    mirror[static_cast<std::size_t>(i)] = static_cast<int>(best);
  }
  return mirror;
}

/// The open body's torso, upper arms and thighs: faces whose three vertices' dominant skinning joint is
/// one of those parts' joints, largest connected component, re-indexed. Parts follow SMPL joint names.
inline FieldMesh body_region() {
  const body::BodyModel& model = open_body();
  const auto part_of_joint = [](int joint) {
    switch (joint) {
      case 0:
      case 3:
      case 6:
      case 9:
      case 13:
      case 14:
        return 0;  // pelvis, spine1–3, collars: torso
      case 16:
        return 1;  // left_shoulder: left upper arm
      case 17:
        return 2;  // right_shoulder: right upper arm
      case 1:
        return 3;  // left_hip: left thigh
      case 2:
        return 4;  // right_hip: right thigh
      default:
        return -1;
    }
  };
  const Eigen::Index n = model.num_vertices();
  std::vector<int> part(static_cast<std::size_t>(n));
  for (Eigen::Index v = 0; v < n; ++v) {
    Eigen::Index joint = 0;
    model.weights.row(v).maxCoeff(&joint);
    part[static_cast<std::size_t>(v)] = part_of_joint(static_cast<int>(joint));
  }
  std::vector<Eigen::Index> faces;
  for (Eigen::Index f = 0; f < model.num_faces(); ++f)
    if (part[static_cast<std::size_t>(model.faces(f, 0))] >= 0 &&
        part[static_cast<std::size_t>(model.faces(f, 1))] >= 0 &&
        part[static_cast<std::size_t>(model.faces(f, 2))] >= 0)
      faces.push_back(f);
  // Largest component of the selected faces (over body vertex indices).
  material::RowMatrixX3i selected(static_cast<Eigen::Index>(faces.size()), 3);
  for (std::size_t k = 0; k < faces.size(); ++k) selected.row(static_cast<Eigen::Index>(k)) = model.faces.row(faces[k]);
  const std::vector<int> component =
      material::connected_components(material::vertex_adjacency(selected, static_cast<int>(n)));
  std::map<int, int> size;
  for (Eigen::Index k = 0; k < selected.size(); ++k) ++size[component[static_cast<std::size_t>(selected.data()[k])]];
  const int largest =
      std::max_element(size.begin(), size.end(), [](auto& a, auto& b) { return a.second < b.second; })->first;
  std::vector<int> local(static_cast<std::size_t>(n), -1), global;
  FieldMesh m;
  std::vector<std::array<int, 3>> kept;
  for (Eigen::Index k = 0; k < selected.rows(); ++k) {
    if (component[static_cast<std::size_t>(selected(k, 0))] != largest) continue;
    std::array<int, 3> tri{};
    for (int c = 0; c < 3; ++c) {
      int& l = local[static_cast<std::size_t>(selected(k, c))];
      if (l < 0) l = static_cast<int>(global.size()), global.push_back(selected(k, c));
      tri[static_cast<std::size_t>(c)] = l;
    }
    kept.push_back(tri);
  }
  m.F.resize(static_cast<Eigen::Index>(kept.size()), 3);
  for (std::size_t k = 0; k < kept.size(); ++k)
    m.F.row(static_cast<Eigen::Index>(k)) << kept[k][0], kept[k][1], kept[k][2];
  m.V.resize(static_cast<Eigen::Index>(global.size()), 3);
  for (std::size_t i = 0; i < global.size(); ++i) {
    m.V.row(static_cast<Eigen::Index>(i)) = model.v_template.row(global[i]);
    m.part.push_back(part[static_cast<std::size_t>(global[i])]);
  }
  m.mirror = nearest_mirror(m.V);
  return m;
}

/// The whole skin of the open body (closed surface).
inline FieldMesh body_skin() {
  FieldMesh m;
  m.V = open_body().v_template;
  m.F = open_body().faces;
  m.mirror = nearest_mirror(m.V);
  return m;
}

}  // namespace sflsh::testing
