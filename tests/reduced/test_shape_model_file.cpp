// Shape-model files (save → load round trip, file:line errors) and the material of a subject of shape β
// (material_for_beta): constant models, clamping, the checks of material files, and build_body_layer.
#include "error_of.hpp"
#include "scratch_dir.hpp"
#include "synthetic_body.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/motion.hpp>
#include <sflsh/model/body_layer.hpp>
#include <sflsh/reduced/shape_model_file.hpp>

#include <gtest/gtest.h>

#include <fstream>
#include <random>

namespace sflsh::reduced {
namespace {

using sflsh::testing::error_of;

/// A model on vertices 3, 10, 17 of `body` with random A (|A| ≤ 0.05) and b inside the normalized bounds.
ShapeModelFile random_model(const body::BodyModel& body, unsigned seed = 3) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ShapeElasticity s;
  s.b.resize(3, material::kNumKappa);
  for (int i = 0; i < 3; ++i) {
    ShapeMatrix a;
    for (Eigen::Index k = 0; k < a.size(); ++k) a.data()[k] = 0.05 * u(rng);
    s.A.push_back(a);
    s.b.row(i) << 0.5 + 0.2 * u(rng), 0.3 + 0.2 * u(rng), 0.2 + 0.1 * u(rng);
  }
  ShapeModelFile file = make_shape_model_file(s, body, {3, 10, 17}, material::ParameterBounds{}, 0.25, 3.5);
  file.region = "thighs+torso";
  file.mesh = "coarse";
  file.fit = ShapeModelFit{Regularizer::local, 0.1, {"A", "B"}, {"shake_hips"}};
  return file;
}

body::Betas random_beta(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.5);
  body::Betas beta;
  for (int k = 0; k < body::kNumBetas; ++k) beta[k] = n(rng);
  return beta;
}

TEST(ShapeModelFile, RoundTripGivesIdenticalKappaOfEveryBeta) {
  const body::BodyModel body = sflsh::testing::synthetic_body();
  const ShapeModelFile model = random_model(body);
  const auto path = sflsh::testing::scratch_dir() / "model.toml";
  save_shape_model_file(path, model, "a header\nof two lines");
  const ShapeModelFile loaded = load_shape_model_file(path);
  EXPECT_EQ(loaded.body, body.name);
  EXPECT_EQ(loaded.poisson, 0.25);
  EXPECT_EQ(loaded.saturation, 3.5);
  EXPECT_EQ(loaded.region, "thighs+torso");
  EXPECT_EQ(loaded.mesh, "coarse");
  ASSERT_TRUE(loaded.fit.has_value());
  EXPECT_EQ(loaded.fit->regularizer, Regularizer::local);
  EXPECT_EQ(loaded.fit->lambda, 0.1);
  EXPECT_EQ(loaded.fit->subjects, (std::vector<std::string>{"A", "B"}));
  EXPECT_EQ(loaded.fit->motions, std::vector<std::string>{"shake_hips"});
  EXPECT_EQ(loaded.vertices(), model.vertices());
  for (int i = 0; i < model.num_controls(); ++i)
    EXPECT_EQ(*loaded.control_points[i].position, *model.control_points[i].position);
  // Shortest round-trip decimals: bit-identical coefficients, hence bit-identical κ̂(β).
  for (unsigned seed = 0; seed < 5; ++seed) {
    const body::Betas beta = random_beta(seed);
    EXPECT_EQ(loaded.elasticity().kappa_normalized(beta), model.elasticity().kappa_normalized(beta)) << seed;
  }
  std::ifstream in(path);
  std::string first;
  std::getline(in, first);
  EXPECT_EQ(first, "# a header");
}

TEST(ShapeModelFile, BadFilesAreRejectedWithFileAndLine) {
  const body::BodyModel body = sflsh::testing::synthetic_body();
  const auto dir = sflsh::testing::scratch_dir();
  const auto good = dir / "good.toml";
  save_shape_model_file(good, random_model(body));
  std::ifstream in(good);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  auto line_of = [&](const std::string& prefix, int nth = 0) {
    for (std::size_t i = 0; i < lines.size(); ++i)
      if (lines[i].rfind(prefix, 0) == 0 && nth-- == 0) return static_cast<int>(i);
    ADD_FAILURE() << "no line " << prefix;
    return 0;
  };
  // Each case replaces one line (0-based index) and expects "<file>:<line>:" plus a phrase.
  struct Case {
    std::string name;
    int index;
    std::string text, phrase;
  };
  const int b1 = line_of("b = ", 1);
  const std::vector<Case> cases = {
      {"unknown_key", line_of("saturation"), "stiffness = 2.0\nsaturation = 4.0", "unknown key 'stiffness'"},
      {"nan_b", b1, "b = [0.5, nan, 0.2]", "'b' in control_point #1 is not finite"},
      {"short_b", b1, "b = [0.5, 0.2]", "'b' in control_point #1 must be an array of 3 numbers"},
      {"short_A_row", b1 + 3, "  [0.1, 0.2],", "must be an array of 3 numbers"},
      {"inf_A", b1 + 4, "  [0.1, inf, 0.0],", "is not finite"},
      {"repeated_vertex", line_of("vertex = ", 1), "vertex = 3", "repeats vertex 3"},
      {"basis_kind", line_of("kind = "), "kind = 'radial'", "the only basis is 'bounded_biharmonic'"},
      {"regularizer", line_of("regularizer = "), "regularizer = 'l1'", "expected l2, local or none"},
      {"negative_lambda", line_of("lambda = "), "lambda = -1.0", "must be >= 0"},
      {"version", line_of("version = "), "version = 2", "'version' must be the integer 1"},
      {"syntax", line_of("poisson = "), "poisson = = 0.2", ""},
  };
  for (const Case& c : cases) {
    std::vector<std::string> edited = lines;
    edited[static_cast<std::size_t>(c.index)] = c.text;
    const auto path = dir / (c.name + ".toml");
    std::ofstream out(path);
    for (const std::string& l : edited) out << l << "\n";
    out.close();
    const std::string msg = error_of([&] { load_shape_model_file(path); });
    EXPECT_NE(msg.find(fmt::format("{}:{}:", path.string(), c.index + 1)), std::string::npos) << c.name << ": " << msg;
    EXPECT_NE(msg.find(c.phrase), std::string::npos) << c.name << ": " << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << c.name;
  }
  EXPECT_NE(error_of([&] { load_shape_model_file(dir / "missing.toml"); }).find("not found"), std::string::npos);
}

TEST(MaterialForBeta, ConstantModelGivesTheConstantMaterial) {
  const body::BodyModel body = sflsh::testing::synthetic_body();
  material::KappaMatrix kappa(2, 3);
  kappa << 0.4, 5000.0, 2000.0, 0.7, 20000.0, 800.0;
  const material::ParameterBounds bounds;
  const ShapeModelFile model =
      make_shape_model_file(ShapeElasticity::constant(material::normalize(kappa, bounds)), body, {5, 40}, bounds);
  for (const body::Betas& beta : {body::Betas(body::Betas::Zero()), random_beta(1)}) {
    const material::MaterialFile m = material_for_beta(model, body, beta, "S");
    EXPECT_EQ(m.subject, "S");
    EXPECT_EQ(m.vertices(), (std::vector<int>{5, 40}));
    // κ / κ_max · κ_max: exact up to two roundings.
    EXPECT_LT((m.kappa() - kappa).cwiseQuotient(kappa).cwiseAbs().maxCoeff(), 4e-16);
  }
}

TEST(MaterialForBeta, ClampsIntoTheBoundsAndPassesTheMaterialChecks) {
  const body::BodyModel body = sflsh::testing::synthetic_body();
  ShapeModelFile model = random_model(body);
  for (ShapeModelControlPoint& p : model.control_points) p.A *= 10.0;  // |A| up to 0.5: far outside for β ~ 3
  const material::MaterialFile m = material_for_beta(model, body, 3.0 * random_beta(2));
  EXPECT_EQ(m.subject, "beta");
  EXPECT_EQ(m.poisson, 0.25);
  EXPECT_NO_THROW(material::validate(m));
  EXPECT_NO_THROW(material::check_against_body(m, body.v_template));
  const material::KappaMatrix k = m.kappa();
  EXPECT_TRUE(((k.rowwise() - m.bounds.minimum()).array() == 0.0).any() ||
              ((k.rowwise() - m.bounds.maximum()).array() == 0.0).any());  // some entry was clamped
  body::BodyModel other = body;
  other.name = "other";
  EXPECT_NE(error_of([&] { material_for_beta(model, other, body::Betas::Zero()); }).find("the run uses body 'other'"),
            std::string::npos);
  other = body;
  other.v_template.row(10).x() += 0.01;  // control point #1 sits elsewhere on this body
  EXPECT_NE(error_of([&] { material_for_beta(model, other, body::Betas::Zero()); }).find("control_point #1"),
            std::string::npos);
}

TEST(MaterialForBeta, BuildBodyLayerAcceptsTheMaterial) {
  const body::BodyModel body = body::load_body(body::default_body_path());
  model::BodyLayerOptions options;
  options.size = meshing::SizePreset::coarse;
  options.cache_dir = SFLSH_TEST_CACHE;
  const body::Motion motion = body::make_procedural_motion("dance", 30.0, 2);
  const model::BodyLayer base = model::build_body_layer(body, body::Betas::Zero(), motion, nullptr, 4, options);
  material::ParameterBounds bounds;
  bounds.thickness.max = 0.6;  // what the coarse mesh retargets validly (validate's default)
  ShapeElasticity s = ShapeElasticity::constant(material::normalize(base.material.kappa(), bounds));
  for (ShapeMatrix& a : s.A) a(0, 0) = 0.02;  // thickness grows a little with β_1
  const ShapeModelFile model = make_shape_model_file(s, body, base.material.vertices(), bounds);
  body::Betas beta = body::Betas::Zero();
  beta[0] = 1.5;
  const material::MaterialFile m = material_for_beta(model, body, beta, "crowd_0");
  const model::BodyLayer layer = model::build_body_layer(body, beta, motion, &m, 0, options);
  EXPECT_EQ(layer.material.kappa(), m.kappa());
  EXPECT_NEAR(m.kappa()(0, material::kThickness), base.material.kappa()(0, material::kThickness) + 0.02 * 1.5 * 0.6,
              1e-12);
}

TEST(ShapeModelFile, ShippedDefaultLoadsAndGivesMaterials) {
  const ShapeModelFile model = load_shape_model_file(default_shape_model_path());
  const body::BodyModel body = body::load_body(body::default_body_path());
  EXPECT_TRUE(model.fit.has_value());
  EXPECT_NO_THROW(material_for_beta(model, body, random_beta(4)));
}

}  // namespace
}  // namespace sflsh::reduced
