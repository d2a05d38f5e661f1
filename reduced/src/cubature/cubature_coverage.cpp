#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/reduced/cubature_coverage.hpp>

#include <algorithm>
#include <map>

namespace sflsh::reduced {

namespace {

/// V_e |∇b_s|²_e for every function s that is non-zero on tet e, with ∇b = [b₁ − b₀, b₂ − b₀, b₃ − b₀] D_m⁻¹.
std::map<int, double> tet_function_energies(const model::Problem& problem, const Subspace& subspace, int e) {
  std::map<int, Eigen::Vector4d> values;
  for (int a = 0; a < 4; ++a)
    for (SparseRowMatrix::InnerIterator it(subspace.basis, problem.tets(e, a)); it; ++it) {
      auto [entry, fresh] = values.try_emplace(static_cast<int>(it.col()), Eigen::Vector4d::Zero());
      entry->second[a] = it.value();
    }
  const material::TetRest& rest = problem.tet_rest[static_cast<std::size_t>(e)];
  std::map<int, double> out;
  for (const auto& [s, b] : values) {
    const Eigen::RowVector3d difference(b[1] - b[0], b[2] - b[0], b[3] - b[0]);
    out[s] = rest.volume * (difference * rest.dm_inv).squaredNorm();
  }
  return out;
}

struct Energies {
  Eigen::VectorXd exact, cubature;
  std::vector<int> richest_tet;  ///< per function: the tet with the largest V_e |∇b_s|²_e
  std::vector<double> richest;   ///< that value
};

Energies function_energies(const model::Problem& problem, const Subspace& subspace, const Cubature& cubature) {
  require(problem.tet_rest.size() == static_cast<std::size_t>(problem.num_tets()),
          "cubature coverage: the problem is not validated");
  require(subspace.num_nodes() == problem.num_nodes(), "cubature coverage: basis has {} rows for {} nodes",
          subspace.num_nodes(), problem.num_nodes());
  const int functions = subspace.num_functions();
  Energies out{Eigen::VectorXd::Zero(functions), Eigen::VectorXd::Zero(functions),
               std::vector<int>(static_cast<std::size_t>(functions), -1),
               std::vector<double>(static_cast<std::size_t>(functions), 0.0)};
  for (int e = 0; e < problem.num_tets(); ++e)
    for (const auto& [s, energy] : tet_function_energies(problem, subspace, e)) {
      out.exact[s] += energy;
      if (energy > out.richest[static_cast<std::size_t>(s)]) {
        out.richest[static_cast<std::size_t>(s)] = energy;
        out.richest_tet[static_cast<std::size_t>(s)] = e;
      }
    }
  for (int c = 0; c < cubature.size(); ++c)
    for (const auto& [s, energy] : tet_function_energies(problem, subspace, cubature.tets[static_cast<std::size_t>(c)]))
      out.cubature[s] += cubature.weights[static_cast<std::size_t>(c)] * energy;
  return out;
}

}  // namespace

Eigen::VectorXd cubature_coverage(const model::Problem& problem, const Subspace& subspace, const Cubature& cubature) {
  const Energies energies = function_energies(problem, subspace, cubature);
  Eigen::VectorXd share = Eigen::VectorXd::Ones(subspace.num_functions());
  for (int s = 0; s < subspace.num_functions(); ++s)
    if (energies.exact[s] > 0.0) share[s] = energies.cubature[s] / energies.exact[s];
  return share;
}

int cover_every_function(const model::Problem& problem, const Subspace& subspace, Cubature& cubature, double fraction) {
  require(fraction > 0.0 && fraction <= 1.0, "cubature coverage: fraction {} must be in (0, 1]", fraction);
  Energies energies = function_energies(problem, subspace, cubature);
  int raised = 0;
  for (int s = 0; s < subspace.num_functions(); ++s) {
    const double wanted = fraction * energies.exact[s];
    if (!(energies.exact[s] > 0.0) || energies.cubature[s] >= wanted) continue;
    const int e = energies.richest_tet[static_cast<std::size_t>(s)];
    const auto found = std::find(cubature.tets.begin(), cubature.tets.end(), e);
    const auto c = static_cast<std::size_t>(found - cubature.tets.begin());
    if (found == cubature.tets.end()) {
      cubature.tets.push_back(e);
      cubature.weights.push_back(0.0);
    }
    // Δω = (α D_s − C_s) / (V_e |∇b_s|²_e); every function on tet e gains Δω V_e |∇b|²_e.
    const double added = (wanted - energies.cubature[s]) / energies.richest[static_cast<std::size_t>(s)];
    cubature.weights[c] += added;
    for (const auto& [r, energy] : tet_function_energies(problem, subspace, e)) energies.cubature[r] += added * energy;
    ++raised;
  }
  if (raised > 0)
    logger()->info(
        "cubature: {} of {} basis functions had less than {:.0f}% of their elastic energy in the cubature; "
        "raised on their richest tet ({} tets now)",
        raised, subspace.num_functions(), 100.0 * fraction, cubature.size());
  return raised;
}

}  // namespace sflsh::reduced
