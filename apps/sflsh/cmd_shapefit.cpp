// sflsh shapefit: the shape regression of SFLSH eqs. 1, 4, 5 on material files, without simulation
// (reduced/shape_regression.hpp, docs/fit.md "sflsh shapefit").
#include "commands.hpp"
#include "layer_setup.hpp"

#include <sflsh/body/subjects.hpp>
#include <sflsh/core/atomic_file.hpp>
#include <sflsh/core/chart.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/material/layer_material.hpp>
#include <sflsh/material/material_file.hpp>
#include <sflsh/meshing/layer_cache.hpp>
#include <sflsh/meshing/region.hpp>
#include <sflsh/reduced/shape_model_file.hpp>
#include <sflsh/reduced/shape_regression.hpp>

#include <algorithm>
#include <chrono>
#include <sstream>

namespace sflsh::app {
namespace {

struct ShapefitOptions {
  SubjectOptions subject;  ///< only the body (--body)
  std::string materials;   ///< a folder (every *.toml) or comma-separated files
  std::string regularizer = "local";
  std::string lambdas = "auto";
  std::string lambda_rule = "one-se";
  std::string mesh = "coarse";
  std::string mesher = "cgal";
  std::string region = "torso,upper_arms,thighs";
  std::string cache;
  std::string out;
};

/// One train subject: its material file and shape.
struct TrainSubject {
  material::MaterialFile file;
  body::Betas beta;
};

std::vector<std::filesystem::path> material_paths(const std::string& spec) {
  std::vector<std::filesystem::path> paths;
  if (std::filesystem::is_directory(spec)) {
    for (const auto& entry : std::filesystem::directory_iterator(spec))
      if (entry.is_regular_file() && entry.path().extension() == ".toml") paths.push_back(entry.path());
    std::sort(paths.begin(), paths.end());
    require(!paths.empty(), "--materials {}: the folder holds no *.toml material files", spec);
  } else {
    std::stringstream list(spec);
    for (std::string item; std::getline(list, item, ',');)
      if (!item.empty()) paths.emplace_back(item);
  }
  require(paths.size() >= 2,
          "--materials {}: {} material file(s); the fit and its leave-one-out cross-validation need 2 or more", spec,
          paths.size());
  return paths;
}

/// β from the file's `betas`, else from its `subject` in the shipped subject tables.
body::Betas subject_shape(const material::MaterialFile& file) {
  if (file.betas) return Eigen::Map<const body::Betas>(file.betas->data());
  for (const body::Subject& s : body::default_subjects())
    if (s.name == file.subject) return s.beta;
  throw_error(
      "{}: subject: '{}' is not a known subject (data/subjects.toml, data/open_body_subjects.toml) and the "
      "file has no 'betas' = [10 numbers] giving its shape",
      file.source, file.subject);
}

/// Every file is for `model`, at the first file's control points, with its bounds, ν and s.
void check_same_layout(const TrainSubject& first, const TrainSubject& other) {
  const material::MaterialFile& a = first.file;
  const material::MaterialFile& b = other.file;
  require(b.control_points.size() == a.control_points.size(),
          "{}: control_point: {} control points, but {} has {} (every file needs the same control points)", b.source,
          b.control_points.size(), a.source, a.control_points.size());
  for (std::size_t i = 0; i < a.control_points.size(); ++i) {
    const material::MaterialControlPoint& p = b.control_points[i];
    require(p.vertex == a.control_points[i].vertex,
            "{}:{}: vertex of control_point #{} is {}, but {} has {} there (every file needs the same control points "
            "in the same order)",
            b.source, p.line, i, p.vertex, a.source, a.control_points[i].vertex);
  }
  for (int c = 0; c < material::kNumKappa; ++c)
    require(b.bounds[c].min == a.bounds[c].min && b.bounds[c].max == a.bounds[c].max,
            "{}: bounds: '{}' = [{}, {}] differs from {}'s [{}, {}] (the bounds' maxima normalize κ, so every file "
            "needs the same)",
            b.source, material::kKappaNames[static_cast<std::size_t>(c)], b.bounds[c].min, b.bounds[c].max, a.source,
            a.bounds[c].min, a.bounds[c].max);
  require(b.poisson == a.poisson, "{}: poisson = {} differs from {}'s {}", b.source, b.poisson, a.source, a.poisson);
  require(b.saturation == a.saturation, "{}: saturation = {} differs from {}'s {}", b.source, b.saturation, a.source,
          a.saturation);
}

std::vector<TrainSubject> load_train_subjects(const std::string& spec, const body::BodyModel& model) {
  std::vector<TrainSubject> subjects;
  for (const std::filesystem::path& path : material_paths(spec)) {
    TrainSubject s;
    s.file = material::load_material_file(path);
    material::check_against_body(s.file, model);
    s.beta = subject_shape(s.file);
    if (!subjects.empty()) check_same_layout(subjects.front(), s);
    subjects.push_back(std::move(s));
  }
  return subjects;
}

std::vector<double> parse_lambdas(const std::string& text) {
  std::vector<double> out;
  std::stringstream list(text);
  for (std::string item; std::getline(list, item, ',');) {
    if (item.empty()) continue;
    std::size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    require(used == item.size() && std::isfinite(value) && value >= 0.0,
            "--lambdas: '{}' is not a number ≥ 0 (expected auto or a comma-separated list such as 0.01,0.1,1)", item);
    out.push_back(value);
  }
  require(!out.empty(), "--lambdas: expected auto or a comma-separated list of λ ≥ 0");
  return out;
}

std::string cell(double v) { return fmt::format("{:.9g}", v); }

/// cross_validation.csv, lambda_sweep.csv and lambda_sweep.png of the sweep.
void write_sweep(RunFolder& run, const reduced::ShapeLambdaSweep& sweep, const std::vector<TrainSubject>& subjects,
                 reduced::Regularizer regularizer) {
  std::ostringstream cv, curve;
  // rms_error: RMS over the N × 3 normalized κ entries (κ / κ_max, dimensionless) of the left-out subject.
  cv << "lambda,left_out,rms_error\n";
  curve << "lambda,rms_error,standard_error,folds,chosen\n";
  chart::Series mean, lower, upper;
  mean.label = fmt::format("{} (mean over left-out subjects)", reduced::regularizer_key(regularizer));
  mean.line = chart::Line::solid;
  lower.label = "mean - standard error";
  upper.label = "mean + standard error";
  lower.marker = upper.marker = chart::Marker::none;
  lower.line = upper.line = chart::Line::dashed;
  for (std::size_t k = 0; k < sweep.scores.size(); ++k) {
    const reduced::LambdaScore& score = sweep.scores[k];
    for (std::size_t s = 0; s < subjects.size(); ++s)
      cv << cell(score.lambda) << "," << subjects[s].file.subject << "," << cell(score.fold_errors[s]) << "\n";
    const double m = reduced::mean_of_finite(score.fold_errors);
    const double se = reduced::standard_error_of_mean(score.fold_errors);
    curve << cell(score.lambda) << "," << cell(m) << "," << cell(se) << "," << score.fold_errors.size() << ","
          << (score.lambda == sweep.choice.lambda ? 1 : 0) << "\n";
    if (score.lambda <= 0.0) continue;  // a log axis has no 0
    mean.x.push_back(score.lambda);
    mean.y.push_back(m);
    lower.x.push_back(score.lambda);
    lower.y.push_back(m - se);
    upper.x.push_back(score.lambda);
    upper.y.push_back(m + se);
  }
  write_text_atomically(run.stage("cross_validation.csv"), cv.str());
  write_text_atomically(run.stage("lambda_sweep.csv"), curve.str());
  chart::Chart chart;
  chart.title = "Leave-one-subject-out error of the shape regression";
  chart.x_label = "lambda";
  chart.y_label = "RMS error of normalized kappa";
  chart.log_x = true;
  if (!mean.x.empty()) {
    chart.series = {mean, lower, upper};
    chart::write_chart_png(run.stage("lambda_sweep.png"), chart);
  }
}

void run_shapefit(const ShapefitOptions& opt, const Invocation& invocation) {
  const auto t0 = std::chrono::steady_clock::now();
  const reduced::Regularizer regularizer_kind = reduced::parse_regularizer(opt.regularizer, "--regularizer");
  const reduced::LambdaRule rule = reduced::parse_lambda_rule(opt.lambda_rule, "--lambda-rule");
  const bool auto_lambdas = opt.lambdas == "auto";
  const std::vector<double> lambdas = auto_lambdas ? reduced::default_lambda_grid() : parse_lambdas(opt.lambdas);
  const body::BodyModel model = load_selected_body(opt.subject);
  const std::vector<TrainSubject> subjects = load_train_subjects(opt.materials, model);
  const material::MaterialFile& first = subjects.front().file;

  reduced::ShapeRegressionData data;
  for (const TrainSubject& s : subjects) {
    data.betas.push_back(s.beta);
    data.kappa.push_back(material::normalize(s.file.kappa(), s.file.bounds));  // κ̂ = κ / κ_max (SFLSH §4)
  }
  meshing::LayerMeshOptions mesh_options;
  mesh_options.mesher = meshing::parse_mesher(opt.mesher);
  mesh_options.size = meshing::parse_size_preset(opt.mesh);
  mesh_options.region_names = meshing::parse_region_names(opt.region);
  reduced::ShapeRegularizer regularizer;
  regularizer.kind = regularizer_kind;
  if (regularizer_kind == reduced::Regularizer::local) {
    const meshing::LayerMesh mesh = meshing::cached_layer_mesh(
        model, mesh_options, opt.cache.empty() ? meshing::default_cache_dir() : std::filesystem::path(opt.cache));
    const material::BiharmonicBasis basis = material::layer_basis(model, mesh, first.vertices());
    regularizer.metric = reduced::layer_shape_metric(model, mesh, basis.phi);  // Q_i, eq. 4
  }

  const reduced::ShapeLambdaSweep sweep =
      reduced::sweep_shape_regression(data, regularizer, lambdas, auto_lambdas, rule);
  if (regularizer_kind != reduced::Regularizer::none && !sweep.bracketed)
    logger()->warn(
        "shapefit: the cross-validation error does not rise on both sides of its least λ = {:g} over λ = "
        "{:g} … {:g}; λ = {:g} is at the edge of what the data tell apart",
        sweep.choice.least_lambda, sweep.scores.front().lambda, sweep.scores.back().lambda, sweep.choice.lambda);
  const reduced::ShapeElasticity fitted = reduced::fit_shape_regression(data, regularizer, sweep.choice.lambda);

  reduced::ShapeModelFile shape_model =
      reduced::make_shape_model_file(fitted, model, first.vertices(), first.bounds, first.poisson, first.saturation);
  shape_model.region = meshing::region_key(mesh_options.region_names);
  shape_model.mesh = meshing::size_preset_name(mesh_options.size);
  reduced::ShapeModelFit fit;
  fit.regularizer = regularizer_kind;
  fit.lambda = sweep.choice.lambda;
  for (const TrainSubject& s : subjects) fit.subjects.push_back(s.file.subject);
  shape_model.fit = fit;

  RunFolder run(opt.out);
  reduced::save_shape_model_file(
      run.stage("shape_model.toml"), shape_model,
      fmt::format("Fitted by sflsh shapefit ({} regularizer, λ = {:g} by leave-one-subject-out cross-validation, {} "
                  "rule) on {} material files",
                  reduced::regularizer_key(regularizer_kind), sweep.choice.lambda, reduced::lambda_rule_name(rule),
                  subjects.size()));
  write_sweep(run, sweep, subjects, regularizer_kind);

  nlohmann::json summary = summary_header("shapefit", invocation.argc, invocation.argv);
  summary["regularizer"] = reduced::regularizer_key(regularizer_kind);
  summary["lambda"] = sweep.choice.lambda;
  summary["lambda_rule"] = reduced::lambda_rule_name(rule);
  summary["least_lambda"] = sweep.choice.least_lambda;
  summary["least_cv_error"] = sweep.choice.least_error;
  summary["standard_error"] = sweep.choice.standard_error;
  summary["threshold"] = sweep.choice.threshold;
  summary["bracketed"] = sweep.bracketed;
  summary["grid_extensions"] = sweep.extensions;
  nlohmann::json errors = nlohmann::json::array();
  for (std::size_t k = 0; k < sweep.scores.size(); ++k)
    errors.push_back({{"lambda", sweep.scores[k].lambda},
                      {"rms_error", sweep.choice.mean_errors[k]},
                      {"standard_error", reduced::standard_error_of_mean(sweep.scores[k].fold_errors)}});
  summary["cv_errors"] = errors;
  nlohmann::json train = nlohmann::json::object();
  for (std::size_t s = 0; s < subjects.size(); ++s)
    train[subjects[s].file.subject] = reduced::shape_prediction_error(fitted, data.betas[s], data.kappa[s]);
  summary["train_rms_error"] = train;
  summary["error_unit"] = "normalized kappa (kappa / kappa_max, dimensionless), RMS over control points x 3";
  summary["subjects"] = fit.subjects;
  summary["control_points"] = data.num_controls();
  summary["mesh"] = shape_model.mesh;
  summary["mesher"] = opt.mesher;
  summary["region"] = shape_model.region;
  std::vector<std::string> files = {"shape_model.toml", "cross_validation.csv", "lambda_sweep.csv"};
  if (std::filesystem::exists(run.stage("lambda_sweep.png"))) files.push_back("lambda_sweep.png");
  summary["files"] = files;
  write_summary(run, summary, seconds_since(t0), {.wall_time_s = true});
  run.commit();
  logger()->info("shapefit: {} subjects, {} control points, {} regularizer, λ = {:g} → {}", subjects.size(),
                 data.num_controls(), reduced::regularizer_key(regularizer_kind), sweep.choice.lambda, opt.out);
}

}  // namespace

void register_shapefit_commands(CLI::App& app, const Invocation& invocation) {
  auto opt = std::make_shared<ShapefitOptions>();
  CLI::App* cmd = app.add_subcommand(
      "shapefit",
      "Fit the shape model κ(β) = Aᵀβ + b (SFLSH eqs. 1, 4, 5) to material files of several subjects, λ by "
      "leave-one-subject-out cross-validation, without simulating");
  add_body_option(*cmd, opt->subject);
  cmd->add_option("--materials", opt->materials,
                  "A folder (every *.toml) or comma-separated material files, one per train subject (as `sflsh "
                  "material show` writes them: same control points, β from 'betas' or the subject's name)")
      ->required();
  cmd->add_option("--regularizer", opt->regularizer,
                  "local (the paper's Q_i of eq. 4) | l2 (Q_i = I) | none (minimum-norm least squares)")
      ->check(CLI::IsMember({"local", "l2", "none"}))
      ->capture_default_str();
  cmd->add_option("--lambdas", opt->lambdas,
                  "auto (half decades 1e-6 … 1e6, extended until the CV error rises on both sides of its minimum) "
                  "or a comma-separated list")
      ->capture_default_str();
  cmd->add_option("--lambda-rule", opt->lambda_rule,
                  "one-se (largest λ within one standard error of the least CV error) | min (the least)")
      ->check(CLI::IsMember({"one-se", "one-standard-error", "min", "minimum"}))
      ->capture_default_str();
  add_mesh_option(*cmd, opt->mesh, true);  // the layer whose φ_i and areas define Q_i
  add_mesher_option(*cmd, opt->mesher);
  cmd->add_option("--region", opt->region, "Comma-separated parts of the layer: torso, upper_arms, thighs, …")
      ->capture_default_str();
  cmd->add_option("--cache", opt->cache, "Cache folder for template meshes (default $SFLSH_CACHE or ~/.cache/sflsh)");
  cmd->add_option("--out", opt->out, "Output folder")->required();
  cmd->callback([opt, invocation] { run_shapefit(*opt, invocation); });
}

}  // namespace sflsh::app
