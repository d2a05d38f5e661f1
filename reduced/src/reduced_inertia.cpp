#include <sflsh/reduced/reduced_inertia.hpp>

#include <sflsh/core/error.hpp>

#include <map>

namespace sflsh::reduced {

ReducedInertia::ReducedInertia(const model::Problem& problem, const Subspace& subspace)
    : problem_(problem), subspace_(subspace), active_(subspace.active_nodes()) {
  for (int i : active_) mass_.push_back(problem.mass.size() ? problem.mass[i] : 0.0);
  skinned_ = dynamic_cast<const model::SkinnedTrajectory*>(problem.trajectory.get());
  if (skinned_) build_pairs(*skinned_);
  z_.resize(static_cast<Eigen::Index>(active_.size()), 3);
}

void ReducedInertia::build_pairs(const model::SkinnedTrajectory& skinned) {
  // T_kl(s, r) for k ≤ l, accumulated densely per joint pair (S × S, upper triangle), then compressed.
  const int S = subspace_.num_functions();
  std::map<std::pair<int, int>, Eigen::MatrixXd> accumulate;
  for (std::size_t a = 0; a < active_.size(); ++a) {
    const int i = active_[a];
    const auto& weights = skinned.node_weights(i);
    for (const auto& [k, wk] : weights) {
      for (const auto& [l, wl] : weights) {
        if (l < k) continue;
        auto [it, inserted] = accumulate.try_emplace({k, l});
        if (inserted) it->second = Eigen::MatrixXd::Zero(S, S);
        Eigen::MatrixXd& term = it->second;
        const double scale = mass_[a] * wk * wl;
        for (SparseRowMatrix::InnerIterator si(subspace_.basis, i); si; ++si)
          for (SparseRowMatrix::InnerIterator ri(subspace_.basis, i); ri; ++ri)
            if (ri.col() >= si.col()) term(si.col(), ri.col()) += scale * si.value() * ri.value();
      }
    }
  }
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
    pairs_.push_back(std::move(pair));
  }
}

void ReducedInertia::set_time(double t, const Eigen::VectorXd& x_prescribed) {
  if (problem_.trajectory) {
    problem_.trajectory->evaluate_nodes(t, active_, frame_);
  } else {
    frame_.A.assign(active_.size(), Eigen::Matrix3d::Identity());
    frame_.d = meshing::RowMatrixX3d::Zero(static_cast<Eigen::Index>(active_.size()), 3);
  }
  for (std::size_t a = 0; a < active_.size(); ++a)
    z_.row(static_cast<Eigen::Index>(a)) =
        (frame_.A[a] * x_prescribed.segment<3>(3 * active_[a])).transpose() + frame_.d.row(static_cast<Eigen::Index>(a));
  if (skinned_) skinned_->curve().transforms(t, joints_);
}

Eigen::VectorXd ReducedInertia::linear_term(const meshing::RowMatrixX3d& p_tilde, double h, bool inertia) const {
  Eigen::VectorXd c = Eigen::VectorXd::Zero(subspace_.num_dofs());
  const double inv_h2 = inertia ? 1.0 / (h * h) : 0.0;
  for (std::size_t a = 0; a < active_.size(); ++a) {
    if (mass_[a] == 0.0) continue;
    const auto row = static_cast<Eigen::Index>(a);
    Eigen::Vector3d target = -problem_.gravity;
    if (inertia) target += inv_h2 * (z_.row(row) - p_tilde.row(row)).transpose();
    const Eigen::Vector3d r = mass_[a] * (frame_.A[a].transpose() * target);
    for (SparseRowMatrix::InnerIterator it(subspace_.basis, active_[a]); it; ++it) c.segment<3>(3 * it.col()) += it.value() * r;
  }
  return c;
}

void ReducedInertia::mass_hessian(double h, Eigen::MatrixXd& H) const {
  const int n = subspace_.num_dofs();
  H.setZero(n, n);
  const double inv_h2 = 1.0 / (h * h);
  if (skinned_) {
    for (const PairTerm& pair : pairs_) {
      const Eigen::Matrix3d Rk = joints_[static_cast<std::size_t>(pair.k)].leftCols<3>();
      const Eigen::Matrix3d Rl = joints_[static_cast<std::size_t>(pair.l)].leftCols<3>();
      const Eigen::Matrix3d G =
          inv_h2 * (pair.k == pair.l ? Eigen::Matrix3d(Rk.transpose() * Rk) : Eigen::Matrix3d(Rk.transpose() * Rl + Rl.transpose() * Rk));
      for (std::size_t e = 0; e < pair.value.size(); ++e) {
        const int s = pair.s[e], r = pair.r[e];
        H.block<3, 3>(3 * s, 3 * r) += pair.value[e] * G;
        if (r != s) H.block<3, 3>(3 * r, 3 * s) += pair.value[e] * G;   // G is symmetric
      }
    }
    return;
  }
  for (std::size_t a = 0; a < active_.size(); ++a) {
    if (mass_[a] == 0.0) continue;
    const Eigen::Matrix3d G = inv_h2 * mass_[a] * (frame_.A[a].transpose() * frame_.A[a]);
    for (SparseRowMatrix::InnerIterator si(subspace_.basis, active_[a]); si; ++si)
      for (SparseRowMatrix::InnerIterator ri(subspace_.basis, active_[a]); ri; ++ri)
        H.block<3, 3>(3 * si.col(), 3 * ri.col()) += (si.value() * ri.value()) * G;
  }
}

void ReducedInertia::cross_mass(double t_other, Eigen::MatrixXd& M) const {
  const int n = subspace_.num_dofs();
  M.setZero(n, n);
  if (skinned_) {
    // A_i(t)ᵀA_i(t') = Σ_{k,l} w_ik w_il R_k(t)ᵀ R_l(t'); T_kl is symmetric in (k, l) and in (s, r), and the
    // (s, r) and (r, s) blocks are equal (not transposed: b_is b_ir is symmetric, the 3×3 factor is not).
    model::JointTransforms other;
    skinned_->curve().transforms(t_other, other);
    for (const PairTerm& pair : pairs_) {
      const Eigen::Matrix3d Rk = joints_[static_cast<std::size_t>(pair.k)].leftCols<3>();
      const Eigen::Matrix3d Rl = joints_[static_cast<std::size_t>(pair.l)].leftCols<3>();
      const Eigen::Matrix3d Rk_other = other[static_cast<std::size_t>(pair.k)].leftCols<3>();
      const Eigen::Matrix3d Rl_other = other[static_cast<std::size_t>(pair.l)].leftCols<3>();
      const Eigen::Matrix3d G = pair.k == pair.l ? Eigen::Matrix3d(Rk.transpose() * Rk_other)
                                                 : Eigen::Matrix3d(Rk.transpose() * Rl_other + Rl.transpose() * Rk_other);
      for (std::size_t e = 0; e < pair.value.size(); ++e) {
        const int s = pair.s[e], r = pair.r[e];
        M.block<3, 3>(3 * s, 3 * r) += pair.value[e] * G;
        if (r != s) M.block<3, 3>(3 * r, 3 * s) += pair.value[e] * G;
      }
    }
    return;
  }
  model::NodeFrame other;
  if (problem_.trajectory) {
    problem_.trajectory->evaluate_nodes(t_other, active_, other);
  } else {
    other.A.assign(active_.size(), Eigen::Matrix3d::Identity());
  }
  for (std::size_t a = 0; a < active_.size(); ++a) {
    if (mass_[a] == 0.0) continue;
    const Eigen::Matrix3d G = mass_[a] * (frame_.A[a].transpose() * other.A[a]);
    for (SparseRowMatrix::InnerIterator si(subspace_.basis, active_[a]); si; ++si)
      for (SparseRowMatrix::InnerIterator ri(subspace_.basis, active_[a]); ri; ++ri)
        M.block<3, 3>(3 * si.col(), 3 * ri.col()) += (si.value() * ri.value()) * G;
  }
}

void ReducedInertia::displacement(const Eigen::VectorXd& q, meshing::RowMatrixX3d& u) const {
  u.resize(static_cast<Eigen::Index>(active_.size()), 3);
  for (std::size_t a = 0; a < active_.size(); ++a) {
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    for (SparseRowMatrix::InnerIterator it(subspace_.basis, active_[a]); it; ++it) v += it.value() * q.segment<3>(3 * it.col());
    u.row(static_cast<Eigen::Index>(a)) = v.transpose();
  }
}

void ReducedInertia::posed(const Eigen::VectorXd& q, meshing::RowMatrixX3d& p) const {
  displacement(q, p);
  for (std::size_t a = 0; a < active_.size(); ++a) {
    const auto row = static_cast<Eigen::Index>(a);
    p.row(row) = (frame_.A[a] * p.row(row).transpose()).transpose() + z_.row(row);
  }
}

}  // namespace sflsh::reduced
