#include <sflsh/core/error.hpp>
#include <sflsh/reduced/joint_pair_mass.hpp>

#include <map>

namespace sflsh::reduced {

JointPairMass JointPairMass::lumped(const model::SkinnedTrajectory& skinned, const Subspace& subspace,
                                    const std::vector<int>& active, const std::vector<double>& mass) {
  require(mass.size() == active.size(), "joint-pair mass: {} masses for {} active nodes", mass.size(), active.size());
  // T_kl(s, r) for k ≤ l, accumulated densely per joint pair (S × S, upper triangle), then compressed.
  const int S = subspace.num_functions();
  std::map<std::pair<int, int>, Eigen::MatrixXd> accumulate;
  for (std::size_t a = 0; a < active.size(); ++a) {
    const int i = active[a];
    const auto& weights = skinned.node_weights(i);
    for (const auto& [k, wk] : weights) {
      for (const auto& [l, wl] : weights) {
        if (l < k) continue;
        auto [it, inserted] = accumulate.try_emplace({k, l});
        if (inserted) it->second = Eigen::MatrixXd::Zero(S, S);
        Eigen::MatrixXd& term = it->second;
        const double scale = mass[a] * wk * wl;
        for (SparseRowMatrix::InnerIterator si(subspace.basis, i); si; ++si)
          for (SparseRowMatrix::InnerIterator ri(subspace.basis, i); ri; ++ri)
            if (ri.col() >= si.col()) term(si.col(), ri.col()) += scale * si.value() * ri.value();
      }
    }
  }
  JointPairMass out;
  for (const auto& [kl, term] : accumulate) {
    PairTerm pair;
    pair.k = kl.first;
    pair.l = kl.second;
    for (int s = 0; s < S; ++s)
      for (int r = s; r < S; ++r)
        if (term(s, r) != 0.0) {
          pair.s.push_back(s);
          pair.r.push_back(r);
          pair.value.push_back(term(s, r));
        }
    out.pairs_.push_back(std::move(pair));
  }
  return out;
}

JointPairMass JointPairMass::consistent(const model::SkinnedTrajectory& skinned, const Subspace& subspace,
                                        const std::vector<int>& active,
                                        const Eigen::SparseMatrix<double, Eigen::RowMajor>& mass) {
  const auto n = static_cast<Eigen::Index>(active.size());
  require(mass.rows() == n && mass.cols() == n, "joint-pair mass: M is {}×{} for {} active nodes", mass.rows(),
          mass.cols(), n);
  const int S = subspace.num_functions();
  // W_k (active × S): entry (a, s) = w_ik b_is, i = active[a]; then T_kl = W_kᵀ M W_l.
  std::map<int, std::vector<Eigen::Triplet<double>>> entries;
  for (Eigen::Index a = 0; a < n; ++a) {
    const int i = active[static_cast<std::size_t>(a)];
    for (const auto& [k, wk] : skinned.node_weights(i))
      for (SparseRowMatrix::InnerIterator it(subspace.basis, i); it; ++it)
        entries[k].emplace_back(a, it.col(), wk * it.value());
  }
  using Sparse = Eigen::SparseMatrix<double>;
  std::map<int, Sparse> weighted, mass_weighted;  // W_k and M W_k per joint with weight on an active node
  const Sparse M(mass);
  for (const auto& [k, list] : entries) {
    Sparse W(n, S);
    W.setFromTriplets(list.begin(), list.end());
    mass_weighted.emplace(k, Sparse(M * W));
    weighted.emplace(k, std::move(W));
  }
  std::map<std::pair<int, int>, Eigen::MatrixXd> ordered;  // T_kl for every ordered pair that is not zero
  for (const auto& [k, Wk] : weighted) {
    const Sparse Wk_t = Wk.transpose();
    for (const auto& [l, MWl] : mass_weighted) {
      const Sparse T = Wk_t * MWl;
      if (T.nonZeros() == 0) continue;
      ordered.emplace(std::make_pair(k, l), Eigen::MatrixXd(T));
    }
  }
  JointPairMass out;
  const Eigen::MatrixXd zero = Eigen::MatrixXd::Zero(S, S);
  for (const auto& [kl, T] : ordered) {
    const auto [k, l] = kl;
    if (l < k) {
      if (ordered.count({l, k}) == 0)
        throw_error("joint-pair mass: T_{}{} without T_{}{} (M is not symmetric)", k, l, l, k);
      continue;  // stored with (l, k)
    }
    const auto swapped = ordered.find({l, k});
    const Eigen::MatrixXd& T_swapped = k == l ? T : (swapped == ordered.end() ? zero : swapped->second);
    PairTerm pair;
    pair.k = k;
    pair.l = l;
    for (int s = 0; s < S; ++s)
      for (int r = s; r < S; ++r)
        if (T(s, r) != 0.0 || T_swapped(s, r) != 0.0) {
          pair.s.push_back(s);
          pair.r.push_back(r);
          pair.value.push_back(T(s, r));
          if (k != l) pair.value_swapped.push_back(T_swapped(s, r));
        }
    out.pairs_.push_back(std::move(pair));
  }
  return out;
}

void JointPairMass::add(const model::JointTransforms& at, const model::JointTransforms& other, double scale,
                        Eigen::MatrixXd& M) const {
  for (const PairTerm& pair : pairs_) {
    const Eigen::Matrix3d Rk = at[static_cast<std::size_t>(pair.k)].leftCols<3>();
    const Eigen::Matrix3d Rl = at[static_cast<std::size_t>(pair.l)].leftCols<3>();
    const Eigen::Matrix3d Rk_other = other[static_cast<std::size_t>(pair.k)].leftCols<3>();
    const Eigen::Matrix3d Rl_other = other[static_cast<std::size_t>(pair.l)].leftCols<3>();
    if (pair.value_swapped.empty()) {
      // Lumped (or k = l): T symmetric in (s, r), so the (s, r) and (r, s) blocks are equal (not transposed: b_is b_ir
      // is symmetric, the 3×3 factor need not be).
      const Eigen::Matrix3d G =
          scale * (pair.k == pair.l ? Eigen::Matrix3d(Rk.transpose() * Rk_other)
                                    : Eigen::Matrix3d(Rk.transpose() * Rl_other + Rl.transpose() * Rk_other));
      for (std::size_t e = 0; e < pair.value.size(); ++e) {
        const int s = pair.s[e], r = pair.r[e];
        M.block<3, 3>(3 * s, 3 * r) += pair.value[e] * G;
        if (r != s) M.block<3, 3>(3 * r, 3 * s) += pair.value[e] * G;
      }
      continue;
    }
    // Consistent, k < l: block(s, r) = a G + b G', block(r, s) = b G + a G' with G = R_kᵀR'_l, G' = R_lᵀR'_k.
    const Eigen::Matrix3d G = scale * (Rk.transpose() * Rl_other);
    const Eigen::Matrix3d G_swapped = scale * (Rl.transpose() * Rk_other);
    for (std::size_t e = 0; e < pair.value.size(); ++e) {
      const int s = pair.s[e], r = pair.r[e];
      const double a = pair.value[e], b = pair.value_swapped[e];
      M.block<3, 3>(3 * s, 3 * r) += a * G + b * G_swapped;
      if (r != s) M.block<3, 3>(3 * r, 3 * s) += b * G + a * G_swapped;
    }
  }
}

std::size_t JointPairMass::num_entries() const {
  std::size_t total = 0;
  for (const PairTerm& pair : pairs_) total += pair.value.size();
  return total;
}

}  // namespace sflsh::reduced
