// The structured box of tetrahedra with named face groups (msh_reader.hpp: box_tet_mesh), for verify
// problems and tests.
#include <sflsh/core/error.hpp>
#include <sflsh/fullspace/msh_reader.hpp>

#include <array>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace sflsh::fullspace {

MshMesh box_tet_mesh(const Eigen::Vector3d& size, std::array<int, 3> cells) {
  require(size.allFinite() && size.minCoeff() > 0.0, "box_tet_mesh: size ({}, {}, {}) must be positive", size[0],
          size[1], size[2]);
  require(cells[0] >= 1 && cells[1] >= 1 && cells[2] >= 1, "box_tet_mesh: cells ({}, {}, {}) must be >= 1", cells[0],
          cells[1], cells[2]);
  const int nx = cells[0] + 1, ny = cells[1] + 1, nz = cells[2] + 1;
  auto index = [&](int i, int j, int k) { return i + nx * (j + ny * k); };
  MshMesh mesh;
  mesh.nodes.resize(nx * ny * nz, 3);
  std::map<std::string, std::vector<int>>& g = mesh.node_groups;
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        const int v = index(i, j, k);
        mesh.nodes.row(v) << size[0] * i / cells[0], size[1] * j / cells[1], size[2] * k / cells[2];
        g["all"].push_back(v);
        if (i == 0) g["xmin"].push_back(v);
        if (i == cells[0]) g["xmax"].push_back(v);
        if (j == 0) g["ymin"].push_back(v);
        if (j == cells[1]) g["ymax"].push_back(v);
        if (k == 0) g["zmin"].push_back(v);
        if (k == cells[2]) g["zmax"].push_back(v);
      }
    }
  }
  for (const auto& [name, nodes] : g) mesh.group_dimension[name] = name == "all" ? 3 : 2;
  // Kuhn split: one tet per axis order (a, b, c), the path (0,0,0) → +e_a → +e_b → +e_c = (1,1,1).
  // Its orientation is the sign of the permutation; odd ones swap two vertices.
  constexpr int orders[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};
  mesh.tets.resize(6 * cells[0] * cells[1] * cells[2], 4);
  int e = 0;
  for (int k = 0; k < cells[2]; ++k) {
    for (int j = 0; j < cells[1]; ++j) {
      for (int i = 0; i < cells[0]; ++i) {
        for (int p = 0; p < 6; ++p) {
          std::array<int, 3> at{i, j, k};
          std::array<int, 4> tet{};
          tet[0] = index(at[0], at[1], at[2]);
          for (int s = 0; s < 3; ++s) {
            ++at[static_cast<std::size_t>(orders[p][s])];
            tet[static_cast<std::size_t>(s) + 1] = index(at[0], at[1], at[2]);
          }
          if (p >= 3) std::swap(tet[2], tet[3]);
          mesh.tets.row(e++) << tet[0], tet[1], tet[2], tet[3];
        }
      }
    }
  }
  return mesh;
}

}  // namespace sflsh::fullspace
