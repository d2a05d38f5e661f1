// The fit's cheap simulation set-up (SFLSH §5): a problem built from a shape prepared once per subject, checked by
// the light pass, is the problem of the full retarget bit for bit.
#include <sflsh/body/body_io.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/reduced/dynamics_case.hpp>
#include <sflsh/reduced/elasticity_fit.hpp>

#include <gtest/gtest.h>

namespace sflsh {

using namespace sflsh::reduced;

TEST(FitSetup, PreparedShapeGivesTheSameProblemBitForBit) {
  const body::BodyModel model = body::load_body(std::filesystem::path(SFLSH_DATA_DIR) / "open_body.npz");
  model::BodyLayerOptions options;
  options.size = meshing::SizePreset::coarse;
  options.cache_dir = SFLSH_TEST_CACHE;
  const body::Betas beta = body::find_subject(body::default_subjects(), "OPEN_TRAIN_2").beta;
  const DynamicsCase c(model, "S", beta, body::make_procedural_motion("one_leg_jump", 60.0, 4), options);
  ParameterizationCache parameterizations(c.layer());
  const LayerParameterization& parameterization = parameterizations.get(4);
  material::KappaMatrix kappa(4, 3);
  kappa << 0.5, 9000.0, 3000.0, 0.3, 6000.0, 2500.0, 0.45, 12000.0, 4000.0, 0.55, 7000.0, 2000.0;
  const meshing::ShapedLayer shaped = parameterization.retargeter().shape(beta);
  meshing::RowMatrixX3d skin_full, skin_light;
  const model::Problem full = parameterization.problem(c.layer(), kappa, c.layer_options(), &skin_full);
  const model::Problem light = parameterization.problem(c.layer(), kappa, c.layer_options(), &skin_light, &shaped);
  EXPECT_EQ(light.rest, full.rest);
  EXPECT_EQ(light.mass, full.mass);
  EXPECT_EQ(skin_light, skin_full);
  ASSERT_EQ(light.tet_rest.size(), full.tet_rest.size());
  ASSERT_EQ(light.tet_material.size(), full.tet_material.size());
  for (std::size_t e = 0; e < full.tet_rest.size(); ++e) {
    ASSERT_EQ(light.tet_rest[e].dm_inv, full.tet_rest[e].dm_inv) << "tet " << e;
    ASSERT_EQ(light.tet_rest[e].volume, full.tet_rest[e].volume) << "tet " << e;
    ASSERT_EQ(light.tet_material[e].scaling, full.tet_material[e].scaling) << "tet " << e;
    ASSERT_EQ(light.tet_material[e].normal, full.tet_material[e].normal) << "tet " << e;
  }
  // A shape prepared for another subject is refused.
  const meshing::ShapedLayer other = parameterization.retargeter().shape(body::Betas::Zero());
  EXPECT_THROW(parameterization.problem(c.layer(), kappa, c.layer_options(), nullptr, &other), Error);
}

}  // namespace sflsh
