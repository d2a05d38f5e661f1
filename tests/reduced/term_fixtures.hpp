#pragma once
// The finite-difference harness of the reduced incremental potential's terms and the box fixtures the term tests
// share (test_reduced_terms.cpp, test_skeleton_deviation.cpp).
#include "integrator_fixtures.hpp"
#include "reduced_fixtures.hpp"

#include <sflsh/reduced/coupled_term.hpp>
#include <sflsh/reduced/reduced_history.hpp>
#include <sflsh/reduced/reduced_terms.hpp>
#include <sflsh/reduced/root_tracking.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace sflsh::reduced::testing_terms {

/// Gradient and Hessian of `term` at q against central differences of its value and gradient. The step is 1e-7 m
/// against coordinates of up to 1e-2 m on a 0.1 m box: truncation (h²|f'''|/6) and rounding (ε|f|/h) are both
/// ≲ 1e-8 relative here, so 1e-6 separates a correct derivative from a wrong one (a missing factor, block or
/// neighbour shows as O(1)).
inline void check_derivatives(const ReducedTerm& term, const Eigen::VectorXd& q, bool exact_hessian = true) {
  const Eigen::Index n = q.size();
  constexpr double h = 1e-7;
  constexpr double kTolerance = 1e-6;
  Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
  EXPECT_TRUE(term.add_gradient(q, g)) << term.name() << ": gradient refused";
  Eigen::VectorXd g_fd(n);
  Eigen::MatrixXd H_fd(n, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    Eigen::VectorXd qp = q, qm = q;
    qp[k] += h;
    qm[k] -= h;
    g_fd[k] = (term.value(qp) - term.value(qm)) / (2.0 * h);
    Eigen::VectorXd gp = Eigen::VectorXd::Zero(n), gm = Eigen::VectorXd::Zero(n);
    term.add_gradient(qp, gp);
    term.add_gradient(qm, gm);
    H_fd.col(k) = (gp - gm) / (2.0 * h);
  }
  const double g_scale = std::max(g.cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LE((g - g_fd).cwiseAbs().maxCoeff() / g_scale, kTolerance) << term.name() << ": gradient";
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  EXPECT_TRUE(term.add_hessian(q, H)) << term.name() << ": Hessian refused";
  if (exact_hessian) {
    const double H_scale = std::max(H_fd.cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LE((H - H_fd).cwiseAbs().maxCoeff() / H_scale, kTolerance) << term.name() << ": Hessian";
  }
  EXPECT_LE((H - H.transpose()).cwiseAbs().maxCoeff(), 1e-12 * std::max(1.0, H.cwiseAbs().maxCoeff()))
      << term.name() << ": Hessian not symmetric";
}

/// A smooth penalty below the plane z = level on every listed node: u = k/3 (level − p_z)³ where p_z < level.
class CubicFloor final : public model::NodePotential {
 public:
  CubicFloor(std::vector<int> nodes, double level, double stiffness)
      : nodes_(std::move(nodes)), level_(level), k_(stiffness) {
    for (std::size_t c = 0; c < nodes_.size(); ++c) candidates_.push_back(static_cast<int>(c));
  }
  const std::vector<int>& nodes() const override { return nodes_; }
  bool begin_substep(double, double, const meshing::RowMatrixX3d&, const meshing::RowMatrixX3d&) override {
    return true;
  }
  const std::vector<int>& candidates() const override { return candidates_; }
  double evaluate(int, const Eigen::Vector3d& p, Eigen::Vector3d* gradient, Eigen::Matrix3d* hessian) const override {
    const double depth = std::max(0.0, level_ - p.z());
    if (gradient) *gradient = -k_ * depth * depth * Eigen::Vector3d::UnitZ();
    if (hessian) *hessian = 2.0 * k_ * depth * Eigen::Vector3d::UnitZ() * Eigen::Vector3d::UnitZ().transpose();
    return k_ / 3.0 * depth * depth * depth;
  }
  bool accept_substep(const meshing::RowMatrixX3d&) override { return true; }

 private:
  std::vector<int> nodes_, candidates_;
  double level_, k_;
};

// 0.1 mm (linear regime), 1 mm, 4 mm (several % strain on 2 cm cells, where the Fung factor bites).
constexpr double kAmplitudes[] = {1e-4, 1e-3, 4e-3};

struct ReducedTermsFixture : ::testing::Test {
  testing::BoxCase box = testing::box_case({4, 4, 3});
  Subspace subspace;
  Cubature cubature;
  Eigen::VectorXd x_prescribed;
  const double t = 0.13;

  void SetUp() override {
    model::Problem& p = box.problem;
    p.gravity = Eigen::Vector3d(0.3, -1.0, -9.81);
    p.trajectory = std::make_shared<testing::SwingTrajectory>(p.num_nodes(), Eigen::Vector3d(0.06, 0.05, 0.0),
                                                              Eigen::Vector3d(1.0, 0.3, 0.2), 0.5, 2.0,
                                                              Eigen::Vector3d(0.01, -0.02, 0.015), 5.0);
    p.validate();
    subspace = testing::box_subspace(box, true);  // affine handles: signed basis entries
    // Every third tet with uneven weights (the cubature's ω enters as a factor per point).
    for (int e = 0; e < p.num_tets(); e += 3) {
      cubature.tets.push_back(e);
      cubature.weights.push_back(1.0 + 0.37 * (e % 7));
    }
    cubature.method = "test";
    x_prescribed = Eigen::Map<const Eigen::VectorXd>(p.rest.data(), p.num_dofs());
  }
  Eigen::VectorXd q(double amplitude, unsigned seed) const {
    return testing::random_q(subspace.num_dofs(), amplitude, seed);
  }
};

struct RootTermsFixture : ReducedTermsFixture {
  std::vector<int> carried;  ///< the attached nodes: only the root moves them
  std::vector<double> carried_mass;
  meshing::RowMatrixX3d carried_posed;
  Eigen::VectorXd carried_tilde;
  const Eigen::Vector3d pivot{0.06, 0.05, 0.01};
  Eigen::Index offset = 0;

  void SetUp() override {
    ReducedTermsFixture::SetUp();
    const model::Problem& p = box.problem;
    carried = box.attached;
    std::sort(carried.begin(), carried.end());
    model::NodeFrame frame;
    p.frame(t, frame);
    const model::RowMatrixX3d skinned = model::posed_positions(frame, x_prescribed);
    carried_posed.resize(static_cast<Eigen::Index>(carried.size()), 3);
    for (std::size_t k = 0; k < carried.size(); ++k) {
      carried_posed.row(static_cast<Eigen::Index>(k)) = skinned.row(carried[k]);
      carried_mass.push_back(p.mass[carried[k]]);
    }
    carried_tilde = Eigen::Map<const Eigen::VectorXd>(carried_posed.data(), carried_posed.size()) +
                    testing::random_q(static_cast<int>(carried_posed.size()), 0.02, 3);
    offset = subspace.num_dofs();
  }
  /// Inertia targets p̃ on the inertia nodes: the skinned positions at t, perturbed by 2 cm.
  Eigen::VectorXd inertia_targets(const ReducedInertia& inertia) const {
    const model::Problem& p = box.problem;
    model::NodeFrame frame;
    p.frame(t, frame);
    const model::RowMatrixX3d skinned = model::posed_positions(frame, x_prescribed);
    const Eigen::VectorXd all =
        Eigen::Map<const Eigen::VectorXd>(skinned.data(), skinned.size()) + testing::random_q(p.num_dofs(), 0.02, 7);
    return gather_nodes(all, inertia.inertia_nodes());
  }
  /// x = [q; θ; τ] with q of `amplitude` [m], θ up to 10·amplitude [rad] (0.001–0.04 rad), τ of `amplitude`.
  Eigen::VectorXd x(double amplitude, unsigned seed) const {
    Eigen::VectorXd v(offset + 6);
    v << q(amplitude, seed), testing::random_q(3, 10.0 * amplitude, seed + 100),
        testing::random_q(3, amplitude, seed + 200);
    return v;
  }
};

// ---------------------------------------------------------------------------------------------------------
// A coupled system (coupled_term.hpp): x = [q; y] and, with a tracking root, [q; θ; τ; y].

/// Springs with a rest length from every listed node to a free point y (3 coordinates):
/// u = k/4 (|d|² − ℓ²)², d = p − y − a_c, so the node, node × y and y blocks are all non-trivial.
class SpringsToAPoint final : public CoupledSystem {
 public:
  SpringsToAPoint(std::vector<int> nodes, double stiffness, double rest)
      : nodes_(std::move(nodes)), k_(stiffness), l_(rest) {
    for (std::size_t c = 0; c < nodes_.size(); ++c) {
      candidates_.push_back(static_cast<int>(c));
      offsets_.push_back(Eigen::Vector3d(0.01 * (c % 3), -0.02 * (c % 5), 0.015 * (c % 2)));
    }
  }
  Eigen::Index size() const override { return 3; }
  const std::vector<int>& nodes() const override { return nodes_; }
  void begin_substep(double, double, const meshing::RowMatrixX3d&, const meshing::RowMatrixX3d&) override {}
  const std::vector<int>& candidates() const override { return candidates_; }
  double evaluate(const meshing::RowMatrixX3d& P, const Eigen::VectorXd& y, CoupledDerivatives* d,
                  bool with_hessian) const override {
    if (d) d->reset(P.rows(), 3, with_hessian);
    double value = 0.0;
    for (Eigen::Index c = 0; c < P.rows(); ++c) {
      const Eigen::Vector3d r = P.row(c).transpose() - y - offsets_[static_cast<std::size_t>(c)] - origin_;
      const double e = r.squaredNorm() - l_ * l_;
      value += 0.25 * k_ * e * e;
      if (!d) continue;
      const Eigen::Vector3d g = k_ * e * r;  // ∂u/∂p = −∂u/∂y
      d->node_gradient.row(c) += g.transpose();
      d->gradient -= g;
      if (!with_hessian) continue;
      const Eigen::Matrix3d H = k_ * (e * Eigen::Matrix3d::Identity() + 2.0 * r * r.transpose());
      d->node_hessian[static_cast<std::size_t>(c)] += H;
      d->node_mixed.middleRows<3>(3 * c) -= H;
      d->hessian += H;
    }
    return value;
  }
  bool accept_substep(const meshing::RowMatrixX3d&, const Eigen::VectorXd&) override { return true; }
  void commit_substep(const meshing::RowMatrixX3d&, const Eigen::VectorXd&) override {}
  void save() override {}
  void restore() override {}
  Eigen::Vector3d origin_ = Eigen::Vector3d(0.05, 0.04, 0.02);

 private:
  std::vector<int> nodes_, candidates_;
  std::vector<Eigen::Vector3d> offsets_;
  double k_, l_;
};

}  // namespace sflsh::reduced::testing_terms
