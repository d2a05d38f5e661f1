// sflsh material curve (material show joins this group: one static add_*_command per subcommand)
#include "commands.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/material/curves.hpp>
#include <sflsh/material/skin_material.hpp>

#include <chrono>
#include <cmath>
#include <map>
#include <memory>

namespace sflsh::app {

namespace {

// ---------------------------------------------------------------------------------------------------
// material curve

struct CurveOptions {
  material::SkinMaterial skin;
  std::string fung_scale = "tangent_over_saturation";
  std::string out;
};

const std::map<std::string, material::FungScale>& fung_scale_names() {
  static const std::map<std::string, material::FungScale> names = {
      {"tangent_over_saturation", material::FungScale::kTangentOverSaturation},
      {"tangent_times_saturation", material::FungScale::kTangentTimesSaturation},
      {"none", material::FungScale::kNone}};
  return names;
}

nlohmann::json material_json(const material::SkinMaterial& skin, const std::string& fung_scale) {
  const material::OrthotropicConstants k = material::small_strain_constants(skin);
  nlohmann::json j = {{"young_tangent_pa", skin.young_tangent},
                      {"young_normal_pa", skin.young_normal},
                      {"poisson", skin.poisson},
                      {"saturation", skin.saturation},
                      {"fung_scale", fung_scale},
                      {"normal", {0.0, 0.0, 1.0}}};
  // FEBio "Fung-ortho-compressible" parameters with the same small-strain response (docs/material.md).
  j["febio_fung_ortho_compressible"] = {{"E1", k.E1},    {"E2", k.E2},    {"E3", k.E3},
                                        {"G12", k.G12},  {"G23", k.G23},  {"G31", k.G31},
                                        {"v12", k.nu12}, {"v23", k.nu23}, {"v31", k.nu31}};
  if (std::isfinite(k.c)) j["febio_fung_ortho_compressible"]["c"] = k.c;  // JSON has no ∞: absent when off
  return j;
}

void run_curve(CurveOptions opt, const Invocation& invocation) {
  const auto t0 = std::chrono::steady_clock::now();
  opt.skin.fung_scale = fung_scale_names().at(opt.fung_scale);
  material::validate(opt.skin, {"--young-tangent", "--young-normal", "--poisson", "--saturation"});
  const std::vector<material::MaterialCurve> curves = material::material_curves(opt.skin);

  RunFolder run(opt.out);
  material::write_curves_csv(run.stage("curves.csv"), curves);
  std::string png = "curves.png";
  try {
    material::plot_curves_png(
        run.stage("curves.png"), curves,
        fmt::format("Y_t = {:g} Pa, Y_n = {:g} Pa, nu = {:g}, saturation = {:g}", opt.skin.young_tangent,
                    opt.skin.young_normal, opt.skin.poisson, opt.skin.saturation));
  } catch (const Error& e) {  // the plot is a convenience: the CSV never depends on a display
    logger()->warn("skipped curves.png: {}", e.what());
    png.clear();
  }

  nlohmann::json summary = summary_header("material curve", invocation.argc, invocation.argv);
  summary["material"] = material_json(opt.skin, opt.fung_scale);
  summary["csv"] = "curves.csv";
  summary["csv_columns"] = {"test", "strain", "stress"};
  summary["units"] = {{"strain", "stretch - 1 (uniaxial), shear gamma (shear)"}, {"stress", "Cauchy stress [Pa]"}};
  summary["plot"] = png.empty() ? nlohmann::json(nullptr) : nlohmann::json(png);
  nlohmann::json tests = nlohmann::json::array();
  for (const material::MaterialCurve& curve : curves) {
    tests.push_back({{"test", std::string(material::curve_test_name(curve.test))},
                     {"samples", curve.points.size()},
                     {"strain_min", curve.points.front().strain},
                     {"strain_max", curve.points.back().strain},
                     {"stress_at_strain_min_pa", curve.points.front().stress},
                     {"stress_at_strain_max_pa", curve.points.back().stress}});
  }
  summary["tests"] = tests;
  write_summary(run, summary, seconds_since(t0), {.wall_time_s = true});
  run.commit();
  for (const material::MaterialCurve& curve : curves)
    logger()->info("{:<17} stress at strain {:+.2f}: {:.6g} Pa", material::curve_test_name(curve.test),
                   curve.points.back().strain, curve.points.back().stress);
  logger()->info("wrote {}/curves.csv{}", opt.out, png.empty() ? "" : " and curves.png");
}

void add_curve_command(CLI::App& group, const Invocation& invocation) {
  auto opt = std::make_shared<CurveOptions>();
  CLI::App* cmd = group.add_subcommand(
      "curve", "Homogeneous stress-strain curves (uniaxial tangent/normal, shear) -> curves.csv, curves.png");
  cmd->add_option("--young-tangent", opt->skin.young_tangent, "Tangential Young modulus Y_t [Pa]")->required();
  cmd->add_option("--young-normal", opt->skin.young_normal, "Normal Young modulus Y_n [Pa]")->required();
  cmd->add_option("--poisson", opt->skin.poisson, "Poisson ratio, in (-1, 0.5)")->capture_default_str();
  cmd->add_option("--saturation", opt->skin.saturation, "Fung saturation s > 0")->capture_default_str();
  cmd->add_option("--fung-scale", opt->fung_scale,
                  "Fung scale c: tangent_over_saturation (c = Y_t/s), tangent_times_saturation (c = s*Y_t), none")
      ->check(CLI::IsMember({"tangent_over_saturation", "tangent_times_saturation", "none"}))
      ->capture_default_str();
  cmd->add_option("--out", opt->out, "Output folder")->required();
  cmd->callback([opt, invocation] { run_curve(*opt, invocation); });
}

}  // namespace

void register_material_commands(CLI::App& app, const Invocation& invocation) {
  CLI::App* material =
      app.add_subcommand("material", "The skin material: constitutive curves and heterogeneous fields");
  material->require_subcommand(1);
  add_curve_command(*material, invocation);
  add_material_show_command(*material, invocation);
}

}  // namespace sflsh::app
