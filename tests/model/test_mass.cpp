// Mass matrices (model/mass.hpp): the consistent matrix's row sums are the lumped masses, and on a clamped
// column the natural frequencies from the two bracket the analytical ones and converge to them.
#include "model_fixtures.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/model/mass.hpp>
#include <sflsh/model/terms.hpp>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <numbers>

namespace sflsh::model {
namespace {

using testing::DenseHessian;

TEST(Mass, ConsistentRowSumsAreTheLumpedMasses) {
  Problem p =
      testing::box_problem({0.1, 0.05, 0.03}, {3, 2, 2}, 1100.0, MassKind::consistent, testing::box_material(5e3, 2e3));
  p.validate();
  const Eigen::SparseMatrix<double, Eigen::RowMajor> M = p.mass_matrix();
  const Eigen::VectorXd row_sums = M * Eigen::VectorXd::Ones(p.num_nodes());
  EXPECT_LE((row_sums - p.mass).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_NEAR(p.mass.sum(), 1100.0 * 0.1 * 0.05 * 0.03, 1e-12);
  EXPECT_LE((Eigen::MatrixXd(M) - Eigen::MatrixXd(M).transpose()).cwiseAbs().maxCoeff(), 0.0);
  p.mass_kind = MassKind::lumped;
  EXPECT_LE((Eigen::VectorXd(p.mass_matrix().diagonal()) - p.mass).cwiseAbs().maxCoeff(), 0.0);
}

TEST(Mass, ValidateRejectsMassesThatAreNotTheRowSums) {
  Problem p =
      testing::box_problem({0.1, 0.05, 0.03}, {2, 1, 1}, 1000.0, MassKind::consistent, testing::box_material(5e3, 2e3));
  p.density = 900.0;  // the lumped masses came from 1000
  EXPECT_THROW(p.validate(), Error);
}

/// The two lowest axial angular frequencies [rad/s] of a column L × a × a clamped at z = 0 with its lateral
/// components held (rollers), ν = 0, by a dense generalized eigensolve K v = ω² M v on the free z components.
std::array<double, 2> axial_frequencies(int layers, MassKind kind, double length, double side, double young,
                                        double density) {
  Problem p = testing::box_problem({side, side, length}, {2, 2, layers}, density, kind,
                                   testing::box_material(young, young, 0.0));
  for (int i = 0; i < p.num_nodes(); ++i) p.dirichlet.add(i, p.rest(i, 2) < 1e-12 ? 7u : 3u);
  p.validate();
  DenseHessian sink(p);
  ElasticTerm(p, TermSubset::whole(p))
      .add_hessian(Eigen::Map<const Eigen::VectorXd>(p.rest.data(), p.num_dofs()), sink);
  const Eigen::MatrixXd M_nodes(p.mass_matrix());
  const std::vector<char> constrained = p.dirichlet.mask(p.num_nodes());
  std::vector<int> free;
  for (int d = 0; d < p.num_dofs(); ++d)
    if (!constrained[static_cast<std::size_t>(d)]) free.push_back(d);
  const auto n = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd K(n, n), M = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index r = 0; r < n; ++r)
    for (Eigen::Index c = 0; c < n; ++c) {
      K(r, c) = sink.H(free[static_cast<std::size_t>(r)], free[static_cast<std::size_t>(c)]);
      if (free[static_cast<std::size_t>(r)] % 3 == free[static_cast<std::size_t>(c)] % 3)
        M(r, c) = M_nodes(free[static_cast<std::size_t>(r)] / 3, free[static_cast<std::size_t>(c)] / 3);
    }
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> solver(K, M);
  const Eigen::VectorXd omega2 = solver.eigenvalues();  // ascending
  return {std::sqrt(omega2[0]), std::sqrt(omega2[1])};
}

TEST(Mass, ClampedColumnFrequenciesAreBracketedAndConverge) {
  // Axial modes of a clamped–free bar with ν = 0: ω_n = (2n − 1)π/(2L) √(Y/ρ) (σ_zz alone satisfies equilibrium and
  // the traction-free sides). With the sides on rollers, shear modes across the 2 cm section lie far above, so the
  // two lowest discrete modes are the axial ones. Consistent masses are a Ritz discretization: their frequencies are
  // upper bounds; lumped masses lower them below the exact ones (−(kh)²/24 against +(kh)²/24 for linear elements).
  const double length = 0.2, side = 0.02, young = 5e3, density = 1000.0;
  const double c = std::sqrt(young / density);
  const std::array<double, 2> exact = {std::numbers::pi / (2.0 * length) * c,
                                       3.0 * std::numbers::pi / (2.0 * length) * c};
  std::array<double, 2> previous_error = {1.0, 1.0};
  for (int layers : {8, 16, 32}) {
    const auto consistent = axial_frequencies(layers, MassKind::consistent, length, side, young, density);
    const auto lumped = axial_frequencies(layers, MassKind::lumped, length, side, young, density);
    for (std::size_t n = 0; n < 2; ++n) {
      EXPECT_GT(consistent[n], exact[n]) << layers << " layers, mode " << n + 1;
      EXPECT_LT(lumped[n], exact[n]) << layers << " layers, mode " << n + 1;
      const double error = (consistent[n] - exact[n]) / exact[n];
      EXPECT_LT(error, previous_error[n] / 3.0) << layers << " layers, mode " << n + 1;  // second order: ÷4 per halving
      previous_error[n] = error;
    }
  }
  EXPECT_LT(previous_error[0], 1e-3);  // 32 layers: (πh/2L)²/24 ≈ 1e-4 for the first mode
}

}  // namespace
}  // namespace sflsh::model
