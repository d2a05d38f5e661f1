// The fit's fast retarget (a shape prepared once, the light validity check) against the full one, and the exact
// derivative of the nodes in the thickness field.
#include "error_of.hpp"
#include "layer_fixture.hpp"

#include <sflsh/body/subjects.hpp>
#include <sflsh/meshing/quality.hpp>
#include <sflsh/meshing/retarget.hpp>

#include <gmock/gmock.h>

namespace sflsh {

using sflsh::testing::coarse_layer;
using sflsh::testing::error_of;
using sflsh::testing::open_body;
using ::testing::HasSubstr;

namespace {

/// h varying smoothly with height between `low` and `high`.
Eigen::VectorXd height_thickness(const meshing::LayerMesh& mesh, double low, double high) {
  const auto& region = mesh.region_surface;
  const Eigen::VectorXd y = open_body().v_template(region.vertices, 1);
  Eigen::VectorXd h(region.num_vertices());
  for (int v = 0; v < h.size(); ++v) h(v) = low + (high - low) * (y(v) - y.minCoeff()) / (y.maxCoeff() - y.minCoeff());
  return h;
}

}  // namespace

TEST(RetargetShaped, GivesTheFullRetargetBitForBit) {
  const auto& mesh = coarse_layer(meshing::Mesher::layered);
  const meshing::Retargeter retargeter(open_body(), mesh);
  const auto subjects = body::default_subjects();
  for (const std::string name : {"OPEN_TRAIN_2", "OPEN_TEST_1"}) {
    SCOPED_TRACE(name);
    const body::Betas beta = body::find_subject(subjects, name).beta;
    const meshing::ShapedLayer shaped = retargeter.shape(beta);
    for (const Eigen::VectorXd& h :
         {height_thickness(mesh, 0.2, 0.55), Eigen::VectorXd(height_thickness(mesh, 0.5, 0.3))}) {
      const meshing::RetargetedLayer full = retargeter.retarget(beta, h);
      const meshing::RetargetedLayer light = retargeter.retarget(shaped, h, meshing::RetargetCheck::light);
      // The same arithmetic in the same order (the harmonic solve is column by column): exactly equal.
      EXPECT_EQ((light.nodes - full.nodes).cwiseAbs().maxCoeff(), 0.0);
      EXPECT_EQ(light.geometry.skin, full.geometry.skin);
      EXPECT_EQ(light.geometry.skeleton, full.geometry.skeleton);
      EXPECT_TRUE(full.quality.valid());
      EXPECT_EQ(light.quality.inverted + light.quality.degenerate, 0);
      EXPECT_EQ(light.quality.tets, full.quality.tets);
    }
  }
}

TEST(RetargetShaped, LightCheckFailsLoudlyLikeTheFullOne) {
  const auto& mesh = coarse_layer(meshing::Mesher::layered);
  const meshing::Retargeter retargeter(open_body(), mesh);
  const meshing::ShapedLayer shaped = retargeter.shape(body::Betas::Zero());
  Eigen::VectorXd h(mesh.region_surface.num_vertices());
  for (int v = 0; v < h.size(); ++v) h(v) = (v % 2) ? 0.98 : 0.02;  // folds the inner surface (test_retarget.cpp)
  const std::string full = error_of([&] { retargeter.retarget(body::Betas::Zero(), h); });
  const std::string light = error_of([&] { retargeter.retarget(shaped, h, meshing::RetargetCheck::light); });
  EXPECT_THAT(light, HasSubstr("inverts"));
  EXPECT_EQ(light, full);
  EXPECT_THAT(error_of([&] { retargeter.retarget(shaped, Eigen::VectorXd::Constant(h.size(), 1.2)); }),
              HasSubstr("expected 0 < h < 1"));
}

TEST(RetargetShaped, TetsValidAgreesWithTheQualityReport) {
  const auto& mesh = coarse_layer(meshing::Mesher::layered);
  EXPECT_TRUE(meshing::tets_valid(mesh.nodes, mesh.tets));
  EXPECT_TRUE(meshing::quality_report(mesh.nodes, mesh.tets).valid());
  const int a = mesh.tets(0, 0), b = mesh.tets(0, 1), c = mesh.tets(0, 2), d = mesh.tets(0, 3);
  // Node d on the plane of a, b, c: tet 0 flat (volume 0 up to round-off: inverted or degenerate).
  meshing::RowMatrixX3d flat = mesh.nodes;
  flat.row(d) = (mesh.nodes.row(a) + mesh.nodes.row(b) + mesh.nodes.row(c)) / 3.0;
  EXPECT_FALSE(meshing::quality_report(flat, mesh.tets).valid());
  EXPECT_FALSE(meshing::tets_valid(flat, mesh.tets));
  // Node d mirrored through that plane: tet 0 inverted.
  meshing::RowMatrixX3d inverted = mesh.nodes;
  inverted.row(d) = 2.0 * flat.row(d) - mesh.nodes.row(d);
  EXPECT_GT(meshing::quality_report(inverted, mesh.tets).inverted, 0);
  EXPECT_FALSE(meshing::tets_valid(inverted, mesh.tets));
  // A sliver: d just off the plane of a, b, c (0.01 % of an edge): positive volume, dihedral angles near 0 or 180°.
  meshing::RowMatrixX3d sliver = mesh.nodes;
  sliver.row(d) = flat.row(d) + 1e-4 * (mesh.nodes.row(d) - flat.row(d));
  EXPECT_EQ(meshing::quality_report(sliver, mesh.tets).valid(), meshing::tets_valid(sliver, mesh.tets));
  EXPECT_FALSE(meshing::tets_valid(sliver, mesh.tets));
}

TEST(RetargetShaped, NodeDerivativeIsTheExactChangeOfTheNodes) {
  const auto& mesh = coarse_layer(meshing::Mesher::layered);
  const meshing::Retargeter retargeter(open_body(), mesh);
  const body::Betas beta = body::find_subject(body::default_subjects(), "OPEN_TRAIN_3").beta;
  const meshing::ShapedLayer shaped = retargeter.shape(beta);
  const Eigen::VectorXd h = height_thickness(mesh, 0.25, 0.5);
  // A smooth change of h: 0.1 at the knees to 0 at the shoulders.
  const Eigen::VectorXd dh = height_thickness(mesh, 0.1, 0.0);
  const meshing::RowMatrixX3d derivative = retargeter.node_derivative(shaped, dh);
  const meshing::RetargetedLayer base = retargeter.retarget(shaped, h, meshing::RetargetCheck::light);
  ASSERT_EQ(base.untangled_nodes, 0);
  for (double step : {1e-3, 0.5}) {
    const meshing::RetargetedLayer moved = retargeter.retarget(shaped, h + step * dh, meshing::RetargetCheck::light);
    ASSERT_EQ(moved.untangled_nodes, 0);
    // The nodes are affine in h, so even the large step agrees; what is left is round-off of positions of ~1 m
    // (1e-15 m) divided by the step, and of the harmonic solve (1e-12 relative): 1e-9 m per unit h is far below
    // the derivative's size (~0.1 m per unit h) and far above that round-off.
    const double error = ((moved.nodes - base.nodes) / step - derivative).cwiseAbs().maxCoeff();
    EXPECT_LT(error, 1e-9) << "step " << step;
  }
  EXPECT_GT(derivative.cwiseAbs().maxCoeff(), 1e-3);  // not trivially zero
}

TEST(RetargetShaped, HarmonicExtensionIsColumnByColumn) {
  // shape() extends S alone and retarget() C alone where the retarget used to extend (S, C) in one solve: equal
  // bit for bit only if the solve treats each column on its own (it does: sparse triangular solves per column).
  const auto& mesh = coarse_layer(meshing::Mesher::layered);
  const meshing::Retargeter retargeter(open_body(), mesh);
  const Eigen::MatrixXd values = Eigen::MatrixXd::Random(mesh.num_nodes(), 6);
  const Eigen::MatrixXd both = retargeter.interpolator().extend(values);
  EXPECT_EQ(both.leftCols<3>(), retargeter.interpolator().extend(values.leftCols<3>()));
  EXPECT_EQ(both.rightCols<3>(), retargeter.interpolator().extend(values.rightCols<3>()));
}

}  // namespace sflsh
