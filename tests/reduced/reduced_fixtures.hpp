#pragma once
// Small problems for the reduced-model tests: a structured box with a homogeneous material, its bottom face
// attached (every component), and a handful of interior point handles.
#include <sflsh/fullspace/msh_reader.hpp>
#include <sflsh/material/skin_material.hpp>
#include <sflsh/model/problem.hpp>
#include <sflsh/reduced/subspace.hpp>
#include <sflsh/reduced/weights.hpp>

#include <algorithm>
#include <cmath>
#include <random>

namespace sflsh::reduced::testing {

inline material::SkinMaterial skin(double young_tangent = 5000.0, double young_normal = 2000.0) {
  material::SkinMaterial m;
  m.young_tangent = young_tangent;
  m.young_normal = young_normal;
  return m;
}

struct BoxCase {
  fullspace::MshMesh mesh;
  model::Problem problem;
  std::vector<int> attached;       ///< the zmin face
  std::vector<int> point_handles;  ///< interior nodes
};

/// z(t) = amplitude · sin(2π · frequency · t) [m] and its rate, for a driven face.
inline model::ScalarDrive shake(double amplitude, double frequency) {
  const double w = 2.0 * M_PI * frequency;
  return {[=](double t) { return amplitude * std::sin(w * t); },
          [=](double t) { return amplitude * w * std::cos(w * t); }};
}

/// A box of size (0.12, 0.1, 0.06) m with `cells`, density ρ, zmin attached (zero displacement, or driven
/// in z by `drive` when given), point handles at the interior nodes nearest to a few fixed sites.
inline BoxCase box_case(std::array<int, 3> cells = {4, 4, 3}, double density = 1000.0,
                        const model::ScalarDrive* drive = nullptr) {
  BoxCase c;
  const Eigen::Vector3d size(0.12, 0.1, 0.06);
  c.mesh = fullspace::box_tet_mesh(size, cells);
  model::Problem& p = c.problem;
  p.rest = c.mesh.nodes;
  p.tets = c.mesh.tets;
  p.tet_material.assign(static_cast<std::size_t>(p.num_tets()),
                        material::make_orthotropic_fung(skin(), Eigen::Vector3d::UnitZ()));
  p.mass = model::lumped_masses(p.rest, p.tets, density);
  p.density = density;
  c.attached = c.mesh.node_groups.at("zmin");
  int drive_index = -1;
  if (drive) {
    p.dirichlet.drives.push_back(*drive);
    drive_index = 0;
  }
  for (int v : c.attached) {
    p.dirichlet.add(v, 0b011u);
    p.dirichlet.add(v, 0b100u, drive_index);
  }
  p.validate();
  const std::vector<char> fixed = p.dirichlet.mask(p.num_nodes());
  const std::vector<Eigen::Vector3d> sites{{0.03, 0.025, 0.04}, {0.09, 0.025, 0.04}, {0.03, 0.075, 0.04},
                                           {0.09, 0.075, 0.04}, {0.06, 0.05, 0.06},  {0.06, 0.05, 0.02}};
  for (const Eigen::Vector3d& s : sites) {
    int best = -1;
    double best_d = 1e30;
    for (int i = 0; i < p.num_nodes(); ++i) {
      if (fixed[static_cast<std::size_t>(3 * i)] ||
          std::find(c.point_handles.begin(), c.point_handles.end(), i) != c.point_handles.end())
        continue;
      const double d = (p.rest.row(i).transpose() - s).norm();
      if (d < best_d) {
        best_d = d;
        best = i;
      }
    }
    c.point_handles.push_back(best);
  }
  return c;
}

/// Point handles first (one node each), the attached face as one bone handle.
inline HandleSets box_handle_sets(const BoxCase& c) {
  HandleSets sets;
  for (int v : c.point_handles) sets.handle_nodes.push_back({v});
  sets.handle_nodes.push_back(c.attached);
  return sets;
}

inline std::vector<char> attached_flags(const BoxCase& c) {
  std::vector<char> flags(static_cast<std::size_t>(c.problem.num_nodes()), 0);
  for (int v : c.attached) flags[static_cast<std::size_t>(v)] = 1;
  return flags;
}

/// The handle subspace of the box (translational point handles, no truncation).
inline Subspace box_subspace(const BoxCase& c, bool affine = false) {
  const Eigen::MatrixXd W =
      handle_weights(c.problem.rest, c.problem.tets, box_handle_sets(c), static_cast<int>(c.point_handles.size()));
  BasisOptions options;
  options.drop_below = 0.0;
  options.max_influences = 1000;
  options.affine = affine;
  return point_handle_subspace(W, attached_flags(c), c.problem.rest, c.point_handles, options);
}

/// B = identity on every free node: the subspace is the whole free space.
inline Subspace full_basis(const model::Problem& p) {
  const std::vector<char> fixed = p.dirichlet.mask(p.num_nodes());
  std::vector<Eigen::Triplet<double>> entries;
  int s = 0;
  for (int i = 0; i < p.num_nodes(); ++i)
    if (!fixed[static_cast<std::size_t>(3 * i)]) entries.emplace_back(i, s++, 1.0);
  Subspace sub;
  sub.basis.resize(p.num_nodes(), s);
  sub.basis.setFromTriplets(entries.begin(), entries.end());
  return sub;
}

/// Reduced coordinates with i.i.d. N(0, amplitude²) entries [m], reproducible from the seed.
inline Eigen::VectorXd random_q(int n, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, amplitude);
  Eigen::VectorXd q(n);
  for (int k = 0; k < n; ++k) q[k] = normal(rng);
  return q;
}

// A box with a two-control material: Y of tet e = (1 − ξ_e) Y_0 + ξ_e Y_1, ξ_e its centroid's x / length.
inline Eigen::MatrixXd box_young_map(const model::Problem& p, const std::vector<int>& tets) {
  Eigen::MatrixXd W(static_cast<Eigen::Index>(tets.size()), 2);
  for (std::size_t k = 0; k < tets.size(); ++k) {
    double x = 0.0;
    for (int c = 0; c < 4; ++c) x += 0.25 * p.rest(p.tets(tets[k], c), 0);
    const double xi = x / 0.12;
    W(static_cast<Eigen::Index>(k), 0) = 1.0 - xi;
    W(static_cast<Eigen::Index>(k), 1) = xi;
  }
  return W;
}

inline std::vector<int> all_tets(const model::Problem& p) {
  std::vector<int> tets(static_cast<std::size_t>(p.num_tets()));
  for (int e = 0; e < p.num_tets(); ++e) tets[static_cast<std::size_t>(e)] = e;
  return tets;
}

/// young: controls × (Y_t, Y_n) [Pa].
inline void set_box_young(model::Problem& p, const Eigen::MatrixX2d& young) {
  const Eigen::MatrixXd W = box_young_map(p, all_tets(p));
  const Eigen::MatrixX2d tet = W * young;
  for (int e = 0; e < p.num_tets(); ++e)
    p.tet_material[static_cast<std::size_t>(e)] =
        material::make_orthotropic_fung(testing::skin(tet(e, 0), tet(e, 1)), Eigen::Vector3d::UnitZ());
}

}  // namespace sflsh::reduced::testing
