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
#include <cstdint>
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
  point_of_tet_.assign(static_cast<std::size_t>(problem.num_tets()), -1);
  for (int p = 0; p < n; ++p) {
    const auto k = static_cast<std::size_t>(p);
    const int e = tets_.point_tet(p);
    point_of_tet_[static_cast<std::size_t>(e)] = p;
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
  build_terms(subspace.num_functions());
  visited_.assign(static_cast<std::size_t>(n), 0);
}

void CubatureGuard::build_terms(int num_functions) {
  ground_ = num_functions;
  const int n = tets_.num_points();
  const int clusters = num_functions + 1;
  // Per point: its anchor (the entry of largest ‖c‖ among its functions and g) and its terms keyed (a, s).
  std::vector<int> anchor(static_cast<std::size_t>(n));
  std::vector<std::int64_t> term_key;
  offset_.assign(1, 0);
  std::vector<std::pair<int, double>> entries;  // (function or g, ‖c‖) of one point
  for (int p = 0; p < n; ++p) {
    const std::span<const int> functions = tets_.point_functions(p);
    const std::span<const Eigen::Vector3d> vectors = tets_.point_vectors(p);
    entries.clear();
    Eigen::Vector3d ground = Eigen::Vector3d::Zero();  // c_g = −Σ_s c_s
    for (std::size_t j = 0; j < functions.size(); ++j) {
      entries.emplace_back(functions[j], vectors[j].norm());
      ground -= vectors[j];
    }
    entries.emplace_back(ground_, ground.norm());
    const int a = std::max_element(entries.begin(), entries.end(), [](const auto& x, const auto& y) {
                    return x.second < y.second;
                  })->first;
    anchor[static_cast<std::size_t>(p)] = a;
    for (std::size_t j = 0; j < entries.size(); ++j) {
      const auto [f, norm] = entries[j];
      if (f == a || norm == 0.0) continue;
      term_key.push_back(static_cast<std::int64_t>(a) * clusters + f);
      term_norm_.push_back(norm);
      term_vector_.push_back(j < functions.size() ? vectors[j] : ground);
    }
    offset_.push_back(static_cast<int>(term_key.size()));
  }
  // Edges numbered by (anchor, function): cluster by cluster.
  std::vector<std::int64_t> edge_key = term_key;
  std::sort(edge_key.begin(), edge_key.end());
  edge_key.erase(std::unique(edge_key.begin(), edge_key.end()), edge_key.end());
  term_edge_.resize(term_key.size());
  for (std::size_t j = 0; j < term_key.size(); ++j)
    term_edge_[j] =
        static_cast<int>(std::lower_bound(edge_key.begin(), edge_key.end(), term_key[j]) - edge_key.begin());
  const std::size_t edges = edge_key.size();
  cluster_edge_offset_.assign(static_cast<std::size_t>(clusters) + 1, 0);
  for (const std::int64_t key : edge_key) {
    edge_anchor_.push_back(static_cast<int>(key / clusters));
    edge_function_.push_back(static_cast<int>(key % clusters));
    ++cluster_edge_offset_[static_cast<std::size_t>(edge_anchor_.back()) + 1];
  }
  for (std::size_t c = 0; c + 1 < cluster_edge_offset_.size(); ++c)
    cluster_edge_offset_[c + 1] += cluster_edge_offset_[c];
  scaled_.assign(term_edge_.size(), kInfinity);
  moved_.assign(edges, 0.0);
  budget_.assign(edges, 0.0);
  edge_reference_ = Eigen::VectorXd::Zero(3 * static_cast<Eigen::Index>(edges));
  edge_moved_ = Eigen::VectorXd::Zero(3 * static_cast<Eigen::Index>(edges));
  radius_.assign(static_cast<std::size_t>(n), 0.0);
  point_budget_.assign(static_cast<std::size_t>(n), 0.0);
  cluster_max_.assign(static_cast<std::size_t>(clusters), 0.0);
  const auto csr = [](std::size_t rows, const std::vector<std::pair<int, int>>& pairs, std::vector<int>& offset,
                      std::vector<int>& column) {  // (row, column) pairs in row order
    offset.assign(rows + 1, 0);
    for (const auto& [row, col] : pairs) ++offset[static_cast<std::size_t>(row) + 1];
    for (std::size_t r = 0; r < rows; ++r) offset[r + 1] += offset[r];
    column.resize(pairs.size());
    std::vector<int> fill(offset.begin(), offset.end() - 1);
    for (const auto& [row, col] : pairs) column[static_cast<std::size_t>(fill[static_cast<std::size_t>(row)]++)] = col;
  };
  std::vector<std::pair<int, int>> pairs;
  for (int p = 0; p < n; ++p) pairs.emplace_back(anchor[static_cast<std::size_t>(p)], p);
  csr(static_cast<std::size_t>(clusters), pairs, cluster_offset_, cluster_points_);
  pairs.clear();
  for (int p = 0; p < n; ++p)
    for (int j = offset_[static_cast<std::size_t>(p)]; j < offset_[static_cast<std::size_t>(p) + 1]; ++j)
      pairs.emplace_back(term_edge_[static_cast<std::size_t>(j)], p);
  csr(edges, pairs, edge_offset_, edge_points_);
  edge_point_budget_.assign(edge_points_.size(), 0.0);
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

double CubatureGuard::last_max_exponent() const {
  return cluster_max_.empty() ? 0.0 : *std::max_element(cluster_max_.begin(), cluster_max_.end());
}

std::vector<GuardViolation> CubatureGuard::check(const Eigen::VectorXd& q) {
  ++checks_;
  if (guarded_ == 0) return {};
  // t: the coordinates per function, and 0 for the fixed skeleton g.
  Eigen::VectorXd t = Eigen::VectorXd::Zero(3 * (static_cast<Eigen::Index>(ground_) + 1));
  t.head(3 * ground_) = q.head(3 * ground_);
  std::vector<GuardViolation> over;
  if (!valid_ || q_size_ != q.size()) {
    ++full_checks_;
    for (int c = 0; c < num_clusters(); ++c) renew_cluster(c, q, t, over);
    valid_ = true;
    q_size_ = q.size();
    return over;
  }
  // Pairs within their budget β cannot push a tet over its radius; only the tets using a pair that moved further
  // need their own bound Σ ‖d_s − d_s,ref‖ ‖c_s‖ ≤ r_e, cluster by cluster.
  std::vector<int> beyond;  // in cluster order (edges are numbered so)
  for (std::size_t k = 0; k < moved_.size(); ++k) {
    const auto edge = static_cast<Eigen::Index>(k);
    edge_moved_.segment<3>(3 * edge) = t.segment<3>(3 * static_cast<Eigen::Index>(edge_function_[k])) -
                                       t.segment<3>(3 * static_cast<Eigen::Index>(edge_anchor_[k])) -
                                       edge_reference_.segment<3>(3 * edge);
    moved_[k] = edge_moved_.segment<3>(3 * edge).norm();
    if (moved_[k] > budget_[k]) beyond.push_back(static_cast<int>(k));
  }
  if (beyond.empty()) return over;
  ++tet_passes_;
  const auto pass_start = std::chrono::steady_clock::now();
  const double renewals_before = renew_seconds_;
  ++generation_;
  for (std::size_t first = 0; first < beyond.size();) {
    const int cluster = edge_anchor_[static_cast<std::size_t>(beyond[first])];
    std::size_t last = first;
    while (last < beyond.size() && edge_anchor_[static_cast<std::size_t>(beyond[last])] == cluster) ++last;
    pass_cluster(cluster, std::span<const int>(beyond.data() + first, last - first), q, t, over);
    first = last;
  }
  pass_seconds_ += seconds_since(pass_start) - (renew_seconds_ - renewals_before);  // a renewal counts as one
  return over;
}

void CubatureGuard::pass_cluster(int cluster, std::span<const int> edges, const Eigen::VectorXd& q,
                                 const Eigen::VectorXd& t, std::vector<GuardViolation>& over) {
  const auto c = static_cast<std::size_t>(cluster);
  const auto budget = static_cast<std::size_t>(renew_fraction_ * (cluster_offset_[c + 1] - cluster_offset_[c])) + 1;
  std::vector<int> suspects;  // ‖ΔF‖ past r_e: evaluated exactly
  for (int edge : edges) {
    const auto k_edge = static_cast<std::size_t>(edge);
    // Only the tets whose own budget r_e / L_e this pair's move passes (the edge's tets are sorted by it): a tet
    // whose every pair moved less than its budget is within its radius.
    for (int k = edge_offset_[k_edge]; k < edge_offset_[k_edge + 1]; ++k) {
      if (edge_point_budget_[static_cast<std::size_t>(k)] >= moved_[k_edge]) break;
      const int p = edge_points_[static_cast<std::size_t>(k)];
      const auto pk = static_cast<std::size_t>(p);
      if (visited_[pk] == generation_ || !active_[pk]) continue;
      visited_[pk] = generation_;
      // The bound first (one product per term), then ‖ΔF‖ itself (one outer product per term) where it fails.
      double bound = 0.0;
      for (int j = offset_[pk]; j < offset_[pk + 1]; ++j)
        bound += moved_[static_cast<std::size_t>(term_edge_[static_cast<std::size_t>(j)])] *
                 scaled_[static_cast<std::size_t>(j)];
      if (bound <= 1.0 || change_norm(p) <= radius_[pk]) continue;
      suspects.push_back(p);
      if (suspects.size() > budget) {  // the reference is stale for this cluster: move it to q
        renew_cluster(cluster, q, t, over);
        return;
      }
    }
  }
  for (int p : suspects) {
    ++exact_;
    const double x = exponent(p, q, nullptr);
    if (!(x <= point_limit_[static_cast<std::size_t>(p)])) over.push_back({tets_.point_tet(p), x});
  }
}

double CubatureGuard::change_norm(int p) const {
  const auto k = static_cast<std::size_t>(p);
  Eigen::Matrix3d change = Eigen::Matrix3d::Zero();  // ΔF = Σ_{s ≠ a} (d_s − d_s,ref) c_sᵀ
  for (int j = offset_[k]; j < offset_[k + 1]; ++j)
    change.noalias() += edge_moved_.segment<3>(3 * static_cast<Eigen::Index>(term_edge_[static_cast<std::size_t>(j)])) *
                        term_vector_[static_cast<std::size_t>(j)].transpose();
  return change.norm();
}

void CubatureGuard::renew_cluster(int cluster, const Eigen::VectorXd& q, const Eigen::VectorXd& t,
                                  std::vector<GuardViolation>& over) {
  ++cluster_renewals_;
  const auto renew_start = std::chrono::steady_clock::now();
  const auto c = static_cast<std::size_t>(cluster);
  double largest = 0.0;
  for (int m = cluster_offset_[c]; m < cluster_offset_[c + 1]; ++m) {
    const int p = cluster_points_[static_cast<std::size_t>(m)];
    const auto k = static_cast<std::size_t>(p);
    if (!active_[k]) continue;
    ++exact_;
    double radius = 0.0;
    const double x = exponent(p, q, &radius);
    radius_[k] = radius;
    largest = std::max(largest, x);
    if (!(x <= point_limit_[k])) over.push_back({tets_.point_tet(p), x});
  }
  cluster_max_[c] = largest;
  // The pairs' references move to q; β of a pair = min over the cluster's tets using it of r_e / L_e: while every
  // pair keeps within its β, Σ ‖d_s − d_s,ref‖ ‖c_s‖ ≤ r_e for every tet of the cluster.
  for (int k = cluster_edge_offset_[c]; k < cluster_edge_offset_[c + 1]; ++k) {
    const auto edge = static_cast<std::size_t>(k);
    budget_[edge] = kInfinity;
    edge_reference_.segment<3>(3 * static_cast<Eigen::Index>(k)) =
        t.segment<3>(3 * static_cast<Eigen::Index>(edge_function_[edge])) -
        t.segment<3>(3 * static_cast<Eigen::Index>(edge_anchor_[edge]));
  }
  for (int m = cluster_offset_[c]; m < cluster_offset_[c + 1]; ++m) {
    const auto k = static_cast<std::size_t>(cluster_points_[static_cast<std::size_t>(m)]);
    if (!active_[k]) continue;
    double sum = 0.0;  // L_e / r_e
    for (int j = offset_[k]; j < offset_[k + 1]; ++j) {
      double& scaled = scaled_[static_cast<std::size_t>(j)];
      scaled = radius_[k] > 0.0 ? term_norm_[static_cast<std::size_t>(j)] / radius_[k] : kInfinity;
      sum += scaled;
    }
    point_budget_[k] = 1.0 / sum;
    for (int j = offset_[k]; j < offset_[k + 1]; ++j) {
      double& b = budget_[static_cast<std::size_t>(term_edge_[static_cast<std::size_t>(j)])];
      b = std::min(b, point_budget_[k]);
    }
  }
  // Each pair's tets by their own budget, ascending (released tets count as +∞).
  for (int k = cluster_edge_offset_[c]; k < cluster_edge_offset_[c + 1]; ++k) {
    const auto first = edge_points_.begin() + edge_offset_[static_cast<std::size_t>(k)];
    const auto last = edge_points_.begin() + edge_offset_[static_cast<std::size_t>(k) + 1];
    const auto budget_of = [this](int p) {
      return active_[static_cast<std::size_t>(p)] ? point_budget_[static_cast<std::size_t>(p)] : kInfinity;
    };
    std::sort(first, last, [&](int a, int b) { return budget_of(a) < budget_of(b); });
    for (auto it = first; it != last; ++it)
      edge_point_budget_[static_cast<std::size_t>(it - edge_points_.begin())] = budget_of(*it);
  }
  renew_seconds_ += seconds_since(renew_start);
}

}  // namespace sflsh::reduced
