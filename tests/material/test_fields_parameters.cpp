// κ = (h, Y_t, Y_n): bounds, validation, normalization by the maxima, and the field κ(s) = Σ φ_i κ_i.
#include "error_of.hpp"
#include "test_fields_meshes.hpp"

#include <sflsh/material/biharmonic_basis.hpp>
#include <sflsh/material/control_points.hpp>
#include <sflsh/material/parameters.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

namespace sflsh {

using namespace sflsh::material;
using sflsh::testing::error_of;
using ::testing::HasSubstr;

TEST(FieldParameters, DefaultBoundsAndNormalization) {
  const ParameterBounds bounds;
  EXPECT_NO_THROW(validate(bounds));
  EXPECT_EQ(bounds.maximum(), Eigen::RowVector3d(0.9, 50000.0, 50000.0));
  KappaMatrix kappa(2, 3);
  kappa << 0.9, 50000.0, 500.0, 0.45, 5000.0, 25000.0;
  const KappaMatrix normalized = normalize(kappa, bounds);
  EXPECT_DOUBLE_EQ(normalized(0, kThickness), 1.0);  // the maxima map to 1
  EXPECT_DOUBLE_EQ(normalized(0, kYoungTangent), 1.0);
  EXPECT_DOUBLE_EQ(normalized(0, kYoungNormal), 0.01);
  EXPECT_DOUBLE_EQ(normalized(1, kThickness), 0.5);
  // One division and one multiplication by the same number: within 1 ulp (≈ 2.2e-16 relative).
  EXPECT_LT(((denormalize(normalized, bounds) - kappa).array() / kappa.array()).abs().maxCoeff(), 4.5e-16);
  const ParameterBounds unit = normalized_bounds(bounds);
  EXPECT_DOUBLE_EQ(unit.young_tangent.min, 0.01);
  EXPECT_DOUBLE_EQ(unit.thickness.max, 1.0);
  const Kappa start = initial_kappa();
  EXPECT_NO_THROW(validate(start, bounds, "initial"));
  EXPECT_DOUBLE_EQ(start.young_tangent, 5000.0);  // √(500 · 50000)
  EXPECT_EQ(from_matrix(to_matrix({start})).front().young_normal, start.young_normal);
}

TEST(FieldParameters, ValidationNamesTheField) {
  const ParameterBounds bounds;
  EXPECT_THAT(error_of([&] {
                validate(Kappa{0.05, 1000.0, 1000.0}, bounds, "point 3");
              }),
              HasSubstr("point 3: thickness = 0.05 is outside [0.1, 0.9]"));
  EXPECT_THAT(error_of([&] {
                validate(Kappa{0.5, 1000.0, 6e4}, bounds, "p");
              }),
              HasSubstr("young_normal = 60000 is outside [500, 50000] Pa"));
  EXPECT_THAT(error_of([&] { validate(Kappa{0.5, std::nan(""), 1000.0}, bounds, "p"); }), HasSubstr("young_tangent"));
  KappaMatrix rows(2, 3);
  rows << 0.5, 1000.0, 1000.0, 0.5, 100.0, 1000.0;
  EXPECT_THAT(error_of([&] { validate(rows, bounds, "control point"); }),
              HasSubstr("control point 1: young_tangent = 100"));
  ParameterBounds bad;
  bad.young_tangent = {5000.0, 500.0};
  EXPECT_THAT(error_of([&] { validate(bad); }), HasSubstr("young_tangent = [5000, 500]"));
  bad = {};
  bad.thickness.max = 1.2;
  EXPECT_THAT(error_of([&] { validate(bad); }), HasSubstr("thickness max 1.2 exceeds 1"));
}

TEST(FieldParameters, FieldStaysWithinTheBoundsAndInterpolates) {
  // κ(s) = Σ φ_i κ_i with φ ≥ 0 and Σφ = 1 is a convex combination: every vertex lies in the bounds when the
  // κ_i do, including 100× stiffness contrasts between neighbours (docs/architecture.md §8). Round-off: Σφ = 1 to
  // ~1e-15, so the field can exceed a bound by that relative amount; 1e-12 relative is the tolerance.
  const auto mesh = sflsh::testing::body_region();
  const std::vector<int> s = place_control_points(mesh.V, mesh.F, 24);
  const BiharmonicBasis basis = biharmonic_basis(mesh.V, mesh.F, s);
  const ParameterBounds bounds;
  std::mt19937 rng(11);
  KappaMatrix kappa(24, 3);
  for (int i = 0; i < 24; ++i) {
    const bool extreme = i % 2 == 0;  // alternate the range ends: the largest contrast the bounds allow
    kappa.row(i) << (extreme ? bounds.thickness.min : bounds.thickness.max),
        (extreme ? bounds.young_tangent.min : bounds.young_tangent.max),
        std::uniform_real_distribution<double>(bounds.young_normal.min, bounds.young_normal.max)(rng);
  }
  for (const bool normalized : {false, true}) {
    const KappaMatrix values = normalized ? normalize(kappa, bounds) : kappa;
    const ParameterBounds b = normalized ? normalized_bounds(bounds) : bounds;
    const KappaMatrix field = evaluate_field(basis.phi, values);
    ASSERT_EQ(field.rows(), mesh.V.rows());
    for (int c = 0; c < kNumKappa; ++c) {
      EXPECT_GE(field.col(c).minCoeff(), b[c].min * (1.0 - 1e-12)) << kKappaNames[static_cast<std::size_t>(c)];
      EXPECT_LE(field.col(c).maxCoeff(), b[c].max * (1.0 + 1e-12)) << kKappaNames[static_cast<std::size_t>(c)];
    }
    for (int i = 0; i < 24; ++i)
      EXPECT_EQ(field.row(s[static_cast<std::size_t>(i)]), values.row(i));  // φ_j(s_i) = δ_ij
  }
  // And the field varies: it is not a constant mean (the test could not fail on a constant).
  const KappaMatrix field = evaluate_field(basis.phi, kappa);
  EXPECT_GT(field.col(kYoungTangent).maxCoeff() / field.col(kYoungTangent).minCoeff(), 10.0);
  EXPECT_THAT(error_of([&] { evaluate_field(basis.phi, kappa.topRows(12)); }),
              HasSubstr("basis has 24 functions but 12 control values"));
}

}  // namespace sflsh
