#include <sflsh/core/error.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/material/fung_strain.hpp>
#include <sflsh/material/orthotropic_fung.hpp>
#include <sflsh/model/terms.hpp>
#include <sflsh/reduced/cubature_guard.hpp>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace sflsh::reduced {

namespace {

using model::kInfinity;

Cubature unguarded_tets(const model::Problem& problem, const Cubature& cubature) {
  std::vector<char> weighted(static_cast<std::size_t>(problem.num_tets()), 0);
  for (std::size_t k = 0; k < cubature.tets.size(); ++k)
    if (cubature.weights[k] > 0.0) weighted[static_cast<std::size_t>(cubature.tets[k])] = 1;
  Cubature out;
  for (int e = 0; e < problem.num_tets(); ++e)
    if (!weighted[static_cast<std::size_t>(e)]) {
      out.tets.push_back(e);
      out.weights.push_back(1.0);
    }
  out.method = "guard";
  return out;
}

}  // namespace

CubatureGuard::CubatureGuard(const model::Problem& problem, const Subspace& subspace, const Cubature& cubature,
                             double exponent_limit, double energy_limit)
    : problem_(problem),
      tets_(problem, subspace, unguarded_tets(problem, cubature)),
      limit_(exponent_limit),
      energy_limit_(energy_limit) {
  require(exponent_limit > 0.0 && exponent_limit <= material::kFungExponentCap,
          "reduced: the guard's exponent limit {} must be in (0, {}]", exponent_limit, material::kFungExponentCap);
  require(energy_limit > 0.0, "reduced: the guard's energy limit {} J must be positive", energy_limit);
  const int n = tets_.num_points();
  guarded_ = n;
  active_.assign(static_cast<std::size_t>(n), 1);
  spectral_.resize(static_cast<std::size_t>(n));
  allowed_.resize(static_cast<std::size_t>(n));
  point_limit_.resize(static_cast<std::size_t>(n));
  offset_.assign(1, 0);
  point_of_tet_.assign(static_cast<std::size_t>(problem.num_tets()), -1);
  for (int p = 0; p < n; ++p) {
    const auto k = static_cast<std::size_t>(p);
    const int e = tets_.point_tet(p);
    point_of_tet_[static_cast<std::size_t>(e)] = p;
    offset_.push_back(offset_.back() + static_cast<int>(tets_.point_functions(p).size()));
    const material::OrthotropicFung& m = problem.tet_material[static_cast<std::size_t>(e)];
    const double p_norm = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m.scaling, Eigen::EigenvaluesOnly)
                              .eigenvalues()
                              .cwiseAbs()
                              .maxCoeff();
    spectral_[k] = p_norm * p_norm;
    // The tet's Fung energy (c/2)(eˣ − 1) V (docs/physics.md §1.2) reaches the energy limit at x_E.
    const double volume = problem.tet_rest[static_cast<std::size_t>(e)].volume;
    const double x_energy = m.inv_c == 0.0 ? kInfinity : std::log1p(2.0 * energy_limit_ / (m.c * volume));
    point_limit_[k] = std::min(limit_, std::isnan(x_energy) ? limit_ : x_energy);
    // x = 2Ψ₀/c ≤ (2/c)(μ₀ + 3/2 λ₀⁺)‖Ê‖² ≤ limit  ⇐  ‖Ê‖ ≤ √(limit c / (2(μ₀ + 3/2 λ₀⁺)))
    const double modulus = m.mu0 + 1.5 * std::max(m.lambda0, 0.0);
    allowed_[k] = m.inv_c == 0.0 || modulus <= 0.0 ? kInfinity : std::sqrt(point_limit_[k] * m.c / (2.0 * modulus));
  }
  scaled_.assign(static_cast<std::size_t>(offset_.back()), kInfinity);
  moved_.assign(static_cast<std::size_t>(subspace.num_functions()), 0.0);
  budget_.assign(static_cast<std::size_t>(subspace.num_functions()), 0.0);
  // The guarded points touching each function (CSR).
  function_offset_.assign(static_cast<std::size_t>(subspace.num_functions()) + 1, 0);
  for (int p = 0; p < n; ++p)
    for (int f : tets_.point_functions(p)) ++function_offset_[static_cast<std::size_t>(f) + 1];
  for (std::size_t f = 0; f + 1 < function_offset_.size(); ++f) function_offset_[f + 1] += function_offset_[f];
  function_points_.resize(static_cast<std::size_t>(function_offset_.back()));
  std::vector<int> fill(function_offset_.begin(), function_offset_.end() - 1);
  for (int p = 0; p < n; ++p)
    for (int f : tets_.point_functions(p))
      function_points_[static_cast<std::size_t>(fill[static_cast<std::size_t>(f)]++)] = p;
  visited_.assign(static_cast<std::size_t>(n), 0);
}

double CubatureGuard::smallest_tet_limit() const {
  double smallest = kInfinity;
  for (std::size_t k = 0; k < point_limit_.size(); ++k)
    if (active_[k]) smallest = std::min(smallest, point_limit_[k]);
  return smallest;
}

void CubatureGuard::set_prescribed_state(const Eigen::VectorXd& x_prescribed) {
  tets_.set_prescribed_state(x_prescribed);
  valid_ = false;
}

void CubatureGuard::release(int tet) {
  require(tet >= 0 && tet < static_cast<int>(point_of_tet_.size()), "reduced: guard release of tet {} out of range",
          tet);
  const int p = point_of_tet_[static_cast<std::size_t>(tet)];
  if (p < 0 || !active_[static_cast<std::size_t>(p)]) return;
  active_[static_cast<std::size_t>(p)] = 0;
  --guarded_;
}

double CubatureGuard::exponent(int p, const Eigen::VectorXd& q, double* radius) const {
  const auto k = static_cast<std::size_t>(p);
  const Eigen::Matrix3d F = tets_.point_deformation_gradient(p, q);
  if (!F.allFinite()) return kInfinity;
  const material::OrthotropicFung& m = problem_.tet_material[static_cast<std::size_t>(tets_.point_tet(p))];
  material::FungStrain strain;
  try {
    strain = material::fung_strain(F, m);  // x = 2Ψ₀/c and ‖Ê‖ (the material's own definitions)
  } catch (const Error&) {
    return kInfinity;  // the StVK energy overflows: far outside the range
  }
  const double x = strain.exponent;
  if (radius) {
    // The radius r in F with ‖Ê_ref‖ + ‖P_Y‖²(‖F_ref‖₂ r + r²/2) ≤ allowed (‖F_refᵀΔ‖_F ≤ ‖F_ref‖₂‖Δ‖_F).
    const double e_hat = strain.scaled_strain;
    const double d = (allowed_[k] - e_hat) / spectral_[k];
    const double f = std::sqrt(F.cwiseAbs().colwise().sum().maxCoeff() *
                               F.cwiseAbs().rowwise().sum().maxCoeff());  // ‖F‖₂ ≤ √(‖F‖₁‖F‖∞)
    *radius = !std::isfinite(allowed_[k]) ? kInfinity : d > 0.0 ? -f + std::sqrt(f * f + 2.0 * d) : 0.0;
  }
  return std::isfinite(x) ? x : kInfinity;
}

std::vector<GuardViolation> CubatureGuard::check(const Eigen::VectorXd& q) {
  ++checks_;
  if (guarded_ == 0) return {};
  if (!valid_ || q_reference_.size() != q.size()) return renew(q);
  // Functions within their budget β_s cannot push a tet over its radius; only the tets touching one that moved
  // further need their own bound Σ_s ‖Δt_s‖ ‖c_s‖ ≤ r_e, and those failing it are evaluated exactly. Too many
  // suspects renew the reference.
  std::vector<int> beyond;
  for (std::size_t s = 0; s < moved_.size(); ++s) {
    moved_[s] =
        (q.segment<3>(3 * static_cast<Eigen::Index>(s)) - q_reference_.segment<3>(3 * static_cast<Eigen::Index>(s)))
            .norm();
    if (moved_[s] > budget_[s]) beyond.push_back(static_cast<int>(s));
  }
  if (beyond.empty()) return {};
  ++tet_passes_;
  const auto pass_start = std::chrono::steady_clock::now();
  struct PassTimer {  // the pass alone: a renewal it ends in counts as a renewal
    std::chrono::steady_clock::time_point start;
    double* seconds;
    const double* renewals;
    double renewals_before;
    ~PassTimer() { *seconds += seconds_since(start) - (*renewals - renewals_before); }
  } pass_timer{pass_start, &pass_seconds_, &renew_seconds_, renew_seconds_};
  ++generation_;
  std::vector<int> suspects;
  const auto budget = static_cast<std::size_t>(renew_fraction_ * guarded_) + 1;
  for (int s : beyond) {
    for (int k = function_offset_[static_cast<std::size_t>(s)]; k < function_offset_[static_cast<std::size_t>(s) + 1];
         ++k) {
      const int p = function_points_[static_cast<std::size_t>(k)];
      const auto pk = static_cast<std::size_t>(p);
      if (visited_[pk] == generation_ || !active_[pk]) continue;
      visited_[pk] = generation_;
      const std::span<const int> functions = tets_.point_functions(p);
      const double* scaled = scaled_.data() + offset_[pk];
      double bound = 0.0;
      for (std::size_t j = 0; j < functions.size(); ++j)
        bound += moved_[static_cast<std::size_t>(functions[j])] * scaled[j];
      if (bound > 1.0) {
        suspects.push_back(p);
        if (suspects.size() > budget) return renew(q);
      }
    }
  }
  std::vector<GuardViolation> over;
  for (int p : suspects) {
    ++exact_;
    const double x = exponent(p, q, nullptr);
    if (!(x <= point_limit_[static_cast<std::size_t>(p)])) over.push_back({tets_.point_tet(p), x});
  }
  return over;
}

std::vector<GuardViolation> CubatureGuard::renew(const Eigen::VectorXd& q) {
  ++full_checks_;
  const auto renew_start = std::chrono::steady_clock::now();
  std::vector<GuardViolation> over;
  last_max_ = 0.0;
  for (int p = 0; p < tets_.num_points(); ++p) {
    const auto k = static_cast<std::size_t>(p);
    if (!active_[k]) continue;
    ++exact_;
    double radius = 0.0;
    const double x = exponent(p, q, &radius);
    last_max_ = std::max(last_max_, x);
    if (!(x <= point_limit_[k])) over.push_back({tets_.point_tet(p), x});
    const std::span<const Eigen::Vector3d> vectors = tets_.point_vectors(p);
    double* scaled = scaled_.data() + offset_[k];
    for (std::size_t j = 0; j < vectors.size(); ++j) scaled[j] = radius > 0.0 ? vectors[j].norm() / radius : kInfinity;
  }
  // β_s = min over the tets touching s of r_e / L_e: while every ‖Δt_s‖ ≤ β_s, Σ_s ‖Δt_s‖ ‖c_s‖ ≤ r_e for every tet.
  std::fill(budget_.begin(), budget_.end(), kInfinity);
  for (int p = 0; p < tets_.num_points(); ++p) {
    const auto k = static_cast<std::size_t>(p);
    if (!active_[k]) continue;
    const std::span<const int> functions = tets_.point_functions(p);
    const double* scaled = scaled_.data() + offset_[k];
    double sum = 0.0;  // L_e / r_e
    for (std::size_t j = 0; j < functions.size(); ++j) sum += scaled[j];
    for (int s : functions)
      budget_[static_cast<std::size_t>(s)] = std::min(budget_[static_cast<std::size_t>(s)], 1.0 / sum);
  }
  q_reference_ = q;
  valid_ = true;
  renew_seconds_ += seconds_since(renew_start);
  return over;
}

}  // namespace sflsh::reduced
