// Heterogeneous material on the layer mesh: control points, basis, κ per vertex/node/tet, normals.
#include "error_of.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/material/layer_material.hpp>
#include <sflsh/material/through_thickness.hpp>
#include <sflsh/meshing/layer_mesh.hpp>

#include <gmock/gmock.h>

#include <random>

namespace sflsh {

using sflsh::testing::error_of;
using ::testing::HasSubstr;

namespace {

struct Layer {
  body::BodyModel model = body::load_body(std::filesystem::path(SFLSH_DATA_DIR) / "open_body.npz");
  meshing::LayerMesh mesh;
  Layer() {
    meshing::LayerMeshOptions options;
    options.mesher = meshing::Mesher::layered;  // extruded: built in a fraction of a second
    options.size = meshing::SizePreset::medium;
    mesh = meshing::build_layer_mesh(model, options);
  }
};

const Layer& layer() {
  static const Layer instance;
  return instance;
}

}  // namespace

TEST(LayerMaterial, ControlPointsAreOnTheRegionNestedAndDenserOnTheTorso) {
  const auto& l = layer();
  const auto twelve = material::layer_control_points(l.model, l.mesh, 12);
  const auto eightyfour = material::layer_control_points(l.model, l.mesh, 84);
  ASSERT_EQ(eightyfour.size(), 84u);
  EXPECT_TRUE(std::equal(twelve.begin(), twelve.end(), eightyfour.begin()));  // nested: a fit can grow N
  int torso = 0;
  for (int v : eightyfour) {
    const int local = l.mesh.region_surface.local_of[static_cast<std::size_t>(v)];
    ASSERT_GE(local, 0);
    torso += l.mesh.region_surface.part[static_cast<std::size_t>(local)] == meshing::Part::torso;
  }
  // The torso holds about half the region's skin; with 1.5× density it gets clearly more than half the points.
  EXPECT_GT(torso, 84 / 2);
  Eigen::Index top = 0;  // the top of the head is not part of the layer
  l.model.v_template.col(1).maxCoeff(&top);
  EXPECT_THAT(error_of([&] { material::layer_basis(l.model, l.mesh, {static_cast<int>(top)}); }),
              HasSubstr("not on the layer's region"));
}

TEST(LayerMaterial, FieldsInterpolateControlValuesAndStayInTheirRange) {
  const auto& l = layer();
  const auto vertices = material::layer_control_points(l.model, l.mesh, 12);
  const auto basis = material::layer_basis(l.model, l.mesh, vertices);
  // Random control values inside the bounds, with a 10× stiffness contrast.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> h(0.3, 0.7), y(1000.0, 10000.0);
  material::KappaMatrix kappa(12, 3);
  for (int i = 0; i < 12; ++i) kappa.row(i) << h(rng), y(rng), y(rng);
  const meshing::Retargeter retargeter(l.model, l.mesh);
  const auto retargeted = retargeter.retarget(body::Betas::Zero(), material::evaluate_field(basis.phi, kappa).col(0));
  const auto fields = material::layer_material_fields(retargeter, basis.phi, kappa, retargeted.nodes);
  // φ_i(s_j) = δ_ij: the field equals κ_i at control vertex i (1e-9: the bounded solve's tolerance).
  for (int i = 0; i < 12; ++i) {
    const int local = l.mesh.region_surface.local_of[static_cast<std::size_t>(vertices[static_cast<std::size_t>(i)])];
    EXPECT_LT((fields.vertex.row(local) - kappa.row(i)).cwiseAbs().maxCoeff(),
              1e-9 * kappa.row(i).cwiseAbs().maxCoeff());
  }
  // Convex combinations and harmonic extension: every node and tet stays within the control range.
  for (int k = 0; k < 3; ++k) {
    const double lo = kappa.col(k).minCoeff(), hi = kappa.col(k).maxCoeff(), slack = 1e-9 * hi;
    EXPECT_GE(fields.node.col(k).minCoeff(), lo - slack);
    EXPECT_LE(fields.node.col(k).maxCoeff(), hi + slack);
    EXPECT_GE(fields.tet.col(k).minCoeff(), lo - slack);
    EXPECT_LE(fields.tet.col(k).maxCoeff(), hi + slack);
  }
}

TEST(LayerMaterial, NormalsAreUnitAndPointFromTheBoneToTheSkin) {
  const auto& l = layer();
  const meshing::Retargeter retargeter(l.model, l.mesh);
  const auto normals = material::through_thickness_normals(l.mesh.nodes, l.mesh.tets, retargeter.depth_field());
  EXPECT_LT((normals.rowwise().norm().array() - 1.0).abs().maxCoeff(), 1e-12);
  // The normal follows the layer's columns: it points along skin − skeleton of the tet's skin vertices.
  // 95% of tets within 45° (the columns are oblique to the skin where bones meet, e.g. the shoulders).
  const auto geometry = meshing::layer_geometry(l.model, l.mesh.region_surface, l.mesh.correspondence,
                                                body::Betas::Zero(), l.mesh.template_thickness_field());
  int aligned = 0;
  for (int e = 0; e < l.mesh.num_tets(); ++e) {
    Eigen::RowVector3d column = Eigen::RowVector3d::Zero();
    for (int c = 0; c < 4; ++c) {
      const int v = l.mesh.anchor[static_cast<std::size_t>(l.mesh.tets(e, c))].vertex[0];
      column += geometry.skin.row(v) - geometry.skeleton.row(v);
    }
    aligned += normals.row(e).dot(column.normalized()) > std::cos(M_PI / 4);
  }
  EXPECT_GT(aligned, 0.95 * l.mesh.num_tets());
}

TEST(ThroughThickness, LinearDepthGivesTheExactNormal) {
  // One tet with depth d = −x: the normal is +x exactly.
  meshing::RowMatrixX3d nodes(4, 3);
  nodes << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  meshing::RowMatrixX4i tets(1, 4);
  tets << 0, 1, 2, 3;
  Eigen::VectorXd depth(4);
  depth << 0.0, -1.0, 0.0, 0.0;
  const auto n = material::through_thickness_normals(nodes, tets, depth);
  EXPECT_LT((n.row(0) - Eigen::RowVector3d(1, 0, 0)).norm(), 1e-14);
  EXPECT_THAT(error_of([&] { material::through_thickness_normals(nodes, tets, Eigen::VectorXd::Zero(4)); }),
              HasSubstr("no depth gradient"));
}

}  // namespace sflsh
