#include <sflsh/core/error.hpp>
#include <sflsh/model/mass.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <vector>

namespace sflsh::model {

MassKind parse_mass_kind(std::string_view text, std::string_view where) {
  if (text == "lumped") return MassKind::lumped;
  if (text == "consistent") return MassKind::consistent;
  throw_error("{}: mass '{}' is not one of lumped, consistent", where, text);
}

std::string_view to_string(MassKind kind) { return kind == MassKind::lumped ? "lumped" : "consistent"; }

Eigen::VectorXd tet_masses(const meshing::RowMatrixX3d& rest, const meshing::RowMatrixX4i& tets, double density) {
  require(std::isfinite(density) && density >= 0.0, "density must be finite and non-negative, got {}", density);
  Eigen::VectorXd mass(tets.rows());
  for (Eigen::Index e = 0; e < tets.rows(); ++e) {
    const Eigen::Vector3d a = rest.row(tets(e, 0)), b = rest.row(tets(e, 1)), c = rest.row(tets(e, 2)),
                          d = rest.row(tets(e, 3));
    mass[e] = density * std::abs((b - a).dot((c - a).cross(d - a))) / 6.0;
  }
  return mass;
}

Eigen::SparseMatrix<double, Eigen::RowMajor> consistent_mass_matrix(const meshing::RowMatrixX4i& tets,
                                                                    const Eigen::VectorXd& tet_mass, int num_nodes) {
  require(tet_mass.size() == tets.rows(), "consistent mass: {} tet masses for {} tets", tet_mass.size(), tets.rows());
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<std::size_t>(16 * tets.rows()));
  for (Eigen::Index e = 0; e < tets.rows(); ++e) {
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b)
        entries.emplace_back(tets(e, a), tets(e, b), tet_mass[e] * consistent_mass_factor(a, b));
    }
  }
  Eigen::SparseMatrix<double, Eigen::RowMajor> M(num_nodes, num_nodes);
  M.setFromTriplets(entries.begin(), entries.end());
  return M;
}

}  // namespace sflsh::model
