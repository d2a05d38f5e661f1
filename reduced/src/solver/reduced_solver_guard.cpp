// The reduced solver's cubature enlargement (cubature_guard.hpp, docs/reduced.md "Robust cubature"): a tet the guard
// caught leaving the material's range joins the cubature with ω = 1 (its own V Ψ), and the cubature point nearest to
// it (by centroid) among those whose weight covers it gives up its volume, ω_p V_p −= V_e, so Σ ω V stays the
// layer's volume.
#include <sflsh/core/log.hpp>
#include <sflsh/material/orthotropic_fung.hpp>
#include <sflsh/reduced/reduced_solver.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <limits>

namespace sflsh::reduced {

namespace {

Eigen::Vector3d centroid(const model::Problem& problem, int e) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int a = 0; a < 4; ++a) c += problem.rest.row(problem.tets(e, a)).transpose();
  return 0.25 * c;
}

}  // namespace

void ReducedSolver::enlarge_cubature(const std::vector<GuardViolation>& over, double t) {
  std::string named;
  for (const GuardViolation& v : over) {
    const int e = v.tet;
    const double volume = problem_.tet_rest[static_cast<std::size_t>(e)].volume;
    const Eigen::Vector3d at = centroid(problem_, e);
    // The donor: the nearest point whose ω V covers V_e.
    int donor = -1;
    double best = std::numeric_limits<double>::infinity();
    for (int p = 0; p < cubature_.size(); ++p) {
      const int tet = cubature_.tets[static_cast<std::size_t>(p)];
      if (tet == e ||
          cubature_.weights[static_cast<std::size_t>(p)] * problem_.tet_rest[static_cast<std::size_t>(tet)].volume <
              volume)
        continue;
      const double d = (centroid(problem_, tet) - at).squaredNorm();
      if (d < best) {
        best = d;
        donor = p;
      }
    }
    if (donor >= 0) {
      const int tet = cubature_.tets[static_cast<std::size_t>(donor)];
      double& w = cubature_.weights[static_cast<std::size_t>(donor)];
      w = std::max(0.0, w - volume / problem_.tet_rest[static_cast<std::size_t>(tet)].volume);
      elastic_.set_point_weight(donor, w);
    }
    // A tet already in the set with ω = 0 gets its weight; any other is appended (point index = cubature index).
    const auto existing = std::find(cubature_.tets.begin(), cubature_.tets.end(), e);
    if (existing != cubature_.tets.end()) {
      const auto p = static_cast<int>(existing - cubature_.tets.begin());
      cubature_.weights[static_cast<std::size_t>(p)] = 1.0;
      elastic_.set_point_weight(p, 1.0);
    } else {
      cubature_.tets.push_back(e);
      cubature_.weights.push_back(1.0);
      elastic_.add_point(e, 1.0);
    }
    guard_->release(e);
    ++added_;
    if (named.size() < 200) named += fmt::format("{}{} (x = {:.3g})", named.empty() ? "" : ", ", e, v.exponent);
  }
  logger()->warn(
      "reduced: t = {:.6g} s: tet(s) {} outside the cubature passed the guard's limit (Fung exponent {} or {} J of "
      "elastic energy; the material's cap is x = {}); added to the cubature, now {} tets, and the substep solved again",
      t, named, options_.guard_exponent, options_.guard_energy, material::kFungExponentCap, cubature_.size());
}

}  // namespace sflsh::reduced
