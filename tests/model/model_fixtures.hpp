#pragma once
// Small problems for the model tests: a box of Kuhn-split cubes (six positively oriented tets per cell) with
// a homogeneous material, and random node maps (invertible, near rotations).
#include "dense_hessian.hpp"

#include <sflsh/material/orthotropic_fung.hpp>
#include <sflsh/model/problem.hpp>
#include <sflsh/model/terms.hpp>

#include <Eigen/Geometry>

#include <array>
#include <random>

namespace sflsh::testing {

/// A box [0, size] split into cells, six tets per cell, nodes in x-fastest order.
inline void kuhn_box(const Eigen::Vector3d& size, std::array<int, 3> cells, model::RowMatrixX3d& nodes,
                     model::RowMatrixX4i& tets) {
  const int nx = cells[0] + 1, ny = cells[1] + 1, nz = cells[2] + 1;
  nodes.resize(nx * ny * nz, 3);
  auto id = [&](int i, int j, int k) { return i + nx * (j + ny * k); };
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        nodes.row(id(i, j, k)) << size[0] * i / cells[0], size[1] * j / cells[1], size[2] * k / cells[2];
  // The six paths from corner 0 to corner 7 of a cube (Kuhn / Freudenthal split).
  const std::array<std::array<int, 3>, 6> orders = {{{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  std::vector<std::array<int, 4>> list;
  for (int k = 0; k < cells[2]; ++k)
    for (int j = 0; j < cells[1]; ++j)
      for (int i = 0; i < cells[0]; ++i)
        for (const auto& order : orders) {
          std::array<int, 3> c = {i, j, k};
          std::array<int, 4> tet{};
          tet[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[static_cast<std::size_t>(order[static_cast<std::size_t>(s)])];
            tet[static_cast<std::size_t>(s) + 1] = id(c[0], c[1], c[2]);
          }
          const Eigen::Vector3d a = nodes.row(tet[0]), b = nodes.row(tet[1]), cc = nodes.row(tet[2]),
                                d = nodes.row(tet[3]);
          if ((b - a).dot((cc - a).cross(d - a)) < 0.0) std::swap(tet[2], tet[3]);
          list.push_back(tet);
        }
  tets.resize(static_cast<Eigen::Index>(list.size()), 4);
  for (std::size_t e = 0; e < list.size(); ++e)
    for (int a = 0; a < 4; ++a) tets(static_cast<Eigen::Index>(e), a) = list[e][static_cast<std::size_t>(a)];
}

/// An isotropic-in-plane skin material (Y_t, Y_n) [Pa] with Poisson ratio ν and normal +z.
inline material::OrthotropicFung box_material(double young_tangent, double young_normal, double poisson = 0.2) {
  material::SkinMaterial skin;
  skin.young_tangent = young_tangent;
  skin.young_normal = young_normal;
  skin.poisson = poisson;
  return material::make_orthotropic_fung(skin, Eigen::Vector3d::UnitZ());
}

/// A validated box problem: density ρ, the material on every tet, no attachment (add Dirichlet before validate
/// for a dynamic problem that must not drift).
inline model::Problem box_problem(const Eigen::Vector3d& size, std::array<int, 3> cells, double density,
                                  model::MassKind mass, const material::OrthotropicFung& material) {
  model::Problem p;
  kuhn_box(size, cells, p.rest, p.tets);
  p.tet_material.assign(static_cast<std::size_t>(p.tets.rows()), material);
  p.density = density;
  p.mass = model::lumped_masses(p.rest, p.tets, density);
  p.mass_kind = mass;
  return p;
}

/// Random maps: A_i = s R (rotation R, scale s ∈ [0.8, 1.2]) and offsets of a few centimetres.
inline model::NodeFrame random_frame(int nodes, std::mt19937& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> scale(0.8, 1.2);
  model::NodeFrame frame;
  frame.d.resize(nodes, 3);
  for (int i = 0; i < nodes; ++i) {
    Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
    frame.A.push_back(scale(rng) * q.normalized().toRotationMatrix());
    frame.d.row(i) << 0.03 * normal(rng), 0.03 * normal(rng), 0.03 * normal(rng);
  }
  return frame;
}

}  // namespace sflsh::testing
