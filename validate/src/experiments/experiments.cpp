// The experiment pipeline of `sflsh validate` (experiments.hpp): ground truth → reduced cases → fits →
// evaluations → reports (report.cpp).
#include "fit_chains.hpp"
#include "report.hpp"

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/progress.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/core/scoped_seconds.hpp>
#include <sflsh/core/summary.hpp>
#include <sflsh/meshing/layer_cache.hpp>
#include <sflsh/meshing/region.hpp>
#include <sflsh/reduced/elasticity_fit.hpp>
#include <sflsh/reduced/lambda_choice.hpp>
#include <sflsh/validate/dyna_file.hpp>
#include <sflsh/validate/dynamics_metrics.hpp>
#include <sflsh/validate/experiments.hpp>
#include <sflsh/validate/ground_truth.hpp>
#include <sflsh/validate/pose_fit.hpp>

#include <algorithm>
#include <chrono>
#include <functional>
#include <map>
#include <optional>
#include <set>

namespace sflsh::validate {

namespace {

using reduced::FitKind;
using reduced::Regularizer;

double default_thickness_max(meshing::SizePreset size) {
  // The largest uniform thickness every subject's retarget keeps valid (docs/meshing.md).
  switch (size) {
    case meshing::SizePreset::coarse:
      return 0.6;
    case meshing::SizePreset::medium:
      return 0.8;
    case meshing::SizePreset::fine:
      return 0.9;
  }
  return 0.6;
}

std::string case_key(const std::string& subject, const std::string& motion) { return subject + "_" + motion; }

/// The hidden material of the synthetic truth: the built-in one, or the shape model of `--truth-model`.
TrueMaterial true_material(const ValidateConfig& config) {
  return config.truth_model.empty() ? TrueMaterial() : TrueMaterial::from_shape_model(config.truth_model);
}

/// The ground truth of every case, computed (round robin over ranks) or loaded from state/groundtruth.
std::map<std::string, GroundTruthCase> compute_ground_truth(
    const ValidateConfig& config, const std::map<std::string, std::unique_ptr<reduced::DynamicsCase>>& cases,
    const std::map<std::string, body::Motion>& motions, reduced::ParameterizationCache& parameterizations,
    const model::BodyLayerOptions& layer_options, const material::ParameterBounds& bounds,
    const std::filesystem::path& state, const reduced::SimulationPool& pool) {
  std::map<std::string, GroundTruthCase> truth;
  GroundTruthOptions gto;
  gto.bounds = bounds;
  gto.truth = true_material(config);
  const std::string fingerprint = gto.truth.fingerprint();
  std::vector<std::string> keys;
  for (const auto& [key, c] : cases) keys.push_back(key);
  Progress progress("ground truth (full space)", keys.size(), config.progress && pool.rank() == 0);
  for (std::size_t k = 0; k < keys.size(); ++k) {
    if (static_cast<int>(k) % pool.ranks() != pool.rank()) continue;
    const std::filesystem::path file = state / "groundtruth" / (keys[k] + ".npz");
    GroundTruthCase c;
    const bool cached = load_ground_truth_case(file, c);
    if (cached && c.truth != fingerprint)
      logger()->info("ground truth {}: cached with another true material ({}); recomputing", keys[k], c.truth);
    if (!cached || c.truth != fingerprint) {
      const reduced::DynamicsCase& dc = *cases.at(keys[k]);
      c = simulate_ground_truth(dc.layer(), motions.at(dc.motion()), dc.subject(), parameterizations.get(1),
                                layer_options, gto);
      save_ground_truth_case(file, c);
    }
    progress.advance();
  }
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (initialized && pool.ranks() > 1) MPI_Barrier(MPI_COMM_WORLD);
  for (const std::string& key : keys) {
    GroundTruthCase c;
    require(load_ground_truth_case(state / "groundtruth" / (key + ".npz"), c), "validate: ground truth {} is missing",
            key);
    truth.emplace(key, std::move(c));
  }
  return truth;
}

std::vector<const GroundTruthCase*> truth_pointers(const std::map<std::string, GroundTruthCase>& truth) {
  std::vector<const GroundTruthCase*> out;
  for (const auto& [key, c] : truth) out.push_back(&c);
  return out;
}

/// What both commands share: the body, subjects, motions, bounds and one reduced case per (subject, motion).
struct Setup {
  body::BodyModel model;
  std::map<std::string, body::Betas> beta_of;
  std::vector<std::string> all_subjects, all_motions;
  model::BodyLayerOptions layer_options;
  material::ParameterBounds bounds;
  std::map<std::string, body::Motion> motions;
  std::map<std::string, std::unique_ptr<reduced::DynamicsCase>> cases;
};

/// The DYNA registrations of the train subjects as ground truth: β and poses fitted, σ* on the region.
struct DynaTruth {
  std::vector<std::string> subjects;  ///< train subjects (file subject ids)
  std::map<std::string, body::Betas> beta;
  std::map<std::string, body::Motion> motion;  ///< key "<subject>_<motion>": fitted poses
  std::map<std::string, std::vector<RowMatrixX3d>> frames;
  std::map<std::string, double> mean_rms;  ///< pose-fit RMS per sequence [m]
};

DynaTruth load_dyna_truth(const ValidateConfig& config, const body::BodyModel& model) {
  DynaTruth t;
  std::vector<std::string> motions = config.train_motions;
  motions.insert(motions.end(), config.test_motions.begin(), config.test_motions.end());
  std::map<std::string, std::pair<const DynaFile*, std::string>> where;  // key → file
  std::vector<std::unique_ptr<DynaFile>> files;
  for (const auto& path : config.dyna) {
    files.push_back(std::make_unique<DynaFile>(path));
    files.back()->require_vertices(model);
    for (const std::string& key : files.back()->keys()) where.emplace(key, std::make_pair(files.back().get(), key));
  }
  // Subject ids: the key minus "_<motion>" for a motion we use (DYNA ids are digits, but names such as
  // OPEN_TRAIN_2 contain '_' themselves, so splitting at the first '_' is not enough).
  std::set<std::string> ids;
  for (const auto& [key, entry] : where)
    for (const std::string& m : motions)
      if (key.size() > m.size() + 1 && key.compare(key.size() - m.size() - 1, std::string::npos, "_" + m) == 0)
        ids.insert(key.substr(0, key.size() - m.size() - 1));
  const bool explicit_subjects = config.preset_subjects_overridden;
  for (const std::string& id :
       explicit_subjects ? std::set<std::string>(config.train_subjects.begin(), config.train_subjects.end()) : ids) {
    bool complete = true;
    for (const std::string& m : motions) complete = complete && where.count(id + "_" + m);
    if (!complete) {
      require(!explicit_subjects, "validate: DYNA subject {} lacks one of the motions ({} files given)", id,
              config.dyna.size());
      logger()->info("validate: DYNA subject {} skipped (not every train and test motion is recorded)", id);
      continue;
    }
    t.subjects.push_back(id);
  }
  require(!t.subjects.empty(), "validate: no DYNA subject has every train and test motion");
  PoseFitOptions po;  // the default rigidity-weighted fit over the layer's soft region (docs/validate.md)
  po.soft_vertices = soft_region_vertices(model);
  for (const std::string& id : t.subjects) {
    std::optional<body::Betas> beta;
    for (const std::string& m : motions) {
      const auto& [file, key] = where.at(id + "_" + m);
      DynaSequence seq = file->read(key, config.frames);  // only the frames used are read
      const PoseFitResult fit = fit_motion(model, seq.frames, seq.fps, beta, po);
      if (!beta) beta = fit.beta;  // β from the subject's first sequence, then shared
      logger()->info("validate: DYNA {}: poses fitted (mean RMS {:.2f} mm, {} unconverged frames)", key,
                     1e3 * fit.mean_rms, fit.unconverged_frames);
      t.mean_rms[id + "_" + m] = fit.mean_rms;
      body::Motion motion = fit.motion;
      motion.name = m;
      t.motion.emplace(id + "_" + m, std::move(motion));
      t.frames.emplace(id + "_" + m, std::move(seq.frames));
    }
    t.beta[id] = *beta;
  }
  return t;
}

void prepare(const ValidateConfig& config, Setup& s, DynaTruth* dyna = nullptr) {
  s.model = body::load_body(config.body_path.empty() ? body::default_body_path() : config.body_path);
  if (!config.truth_model.empty()) {  // a bad truth model fails before any layer is built
    require(config.dyna.empty(), "--truth-model: the ground truth comes from the DYNA files given; drop one of them");
    const TrueMaterial truth = true_material(config);
    const reduced::ShapeModelFile& m = *truth.shape_model();
    require(m.body == s.model.name, "{}: body: the truth model is for body '{}', but the run uses body '{}'", m.source,
            m.body, s.model.name);
    reduced::check_layer_match(m, meshing::region_key(meshing::default_region_names()),
                               meshing::size_preset_name(config.mesh), "--truth-model");
  }
  const std::vector<body::Subject> subjects = body::default_subjects();
  if (dyna) {
    *dyna = load_dyna_truth(config, s.model);
    s.all_subjects = dyna->subjects;
    for (const std::string& id : dyna->subjects) s.beta_of[id] = dyna->beta.at(id);
    for (const std::string& name : config.test_subjects) {
      s.all_subjects.push_back(name);
      s.beta_of[name] = body::find_subject(subjects, name).beta;
    }
  }
  if (!dyna) {
    s.all_subjects = config.train_subjects;
    s.all_subjects.insert(s.all_subjects.end(), config.test_subjects.begin(), config.test_subjects.end());
    for (const std::string& name : s.all_subjects) s.beta_of[name] = body::find_subject(subjects, name).beta;
  }
  s.all_motions = config.train_motions;
  s.all_motions.insert(s.all_motions.end(), config.test_motions.begin(), config.test_motions.end());
  s.layer_options.size = config.mesh;
  s.layer_options.cache_dir = config.cache_dir;
  s.bounds.thickness.max = config.thickness_max > 0.0 ? config.thickness_max : default_thickness_max(config.mesh);
  material::validate(s.bounds);
  for (const std::string& m : s.all_motions) s.motions.emplace(m, body::make_procedural_motion(m, 60.0, config.frames));
  Progress progress("subject layers", s.all_subjects.size() * s.all_motions.size(), config.progress);
  for (const std::string& name : s.all_subjects)
    for (const std::string& m : s.all_motions) {
      // DYNA subjects move as their fitted poses; everyone else along the procedural motion.
      const std::string key = case_key(name, m);
      const body::Motion& motion = dyna && dyna->motion.count(key) ? dyna->motion.at(key) : s.motions.at(m);
      s.cases.emplace(
          key, std::make_unique<reduced::DynamicsCase>(s.model, name, s.beta_of.at(name), motion, s.layer_options));
      progress.advance();
    }
}

void check_config(const ValidateConfig& config) {
  require(!config.train_subjects.empty() || !config.dyna.empty(), "validate: no train subjects");
  require(!config.train_motions.empty() && !config.test_motions.empty(),
          "validate: train and test motions are required");
  require(!config.stages.empty(), "validate: no control-point stages");
  for (const std::string tag : {"l2", "ours"}) {
    for (double l : config.lambdas_for(tag))
      require(l > 0.0 && std::isfinite(l), "validate: λ ({}) must be positive, got {}", tag, l);
    require(!config.lambdas_for(tag).empty(), "validate: no λ values for {}", tag);
  }
}

/// σ* of the DYNA registrations on the layer's region vertices [mm], one case per sequence.
std::map<std::string, GroundTruthCase> dyna_ground_truth(const DynaTruth& dyna, const Setup& setup,
                                                         const std::vector<int>& region) {
  std::map<std::string, GroundTruthCase> truth;
  for (const auto& [key, frames] : dyna.frames) {
    const reduced::DynamicsCase& c = *setup.cases.at(key);
    const DynamicsResult d = dynamics_metrics(setup.model, c.beta(), dyna.motion.at(key), frames, region);
    GroundTruthCase g;
    g.subject = c.subject();
    g.motion = c.motion();
    g.beta = c.beta();
    g.fps = dyna.motion.at(key).fps;
    g.sigma_normal.resize(static_cast<Eigen::Index>(region.size()));
    g.sigma_tangent.resize(static_cast<Eigen::Index>(region.size()));
    for (std::size_t r = 0; r < region.size(); ++r) {
      g.sigma_normal[static_cast<Eigen::Index>(r)] = 1e3 * d.sigma_normal[region[r]];
      g.sigma_tangent[static_cast<Eigen::Index>(r)] = 1e3 * d.sigma_tangent[region[r]];
    }
    truth.emplace(key, std::move(g));
  }
  return truth;
}

nlohmann::json dyna_summary(const DynaTruth& dyna) {
  nlohmann::json j;
  for (const std::string& id : dyna.subjects) {
    const body::Betas& b = dyna.beta.at(id);
    j["subjects"][id]["beta"] = std::vector<double>(b.data(), b.data() + b.size());
  }
  for (const auto& [key, rms] : dyna.mean_rms) j["pose_fit_mean_rms_mm"][key] = 1e3 * rms;
  return j;
}

const std::vector<std::pair<Regularizer, std::string>> kRegularizers{{Regularizer::l2, "l2"},
                                                                     {Regularizer::local, "ours"}};

/// The fits' specifications and targets of one study: its settings, subjects' β, cases, σ* and checkpoints.
struct FitSpecs {
  const ValidateConfig& config;
  const Setup& setup;
  const std::map<std::string, GroundTruthCase>& truth;
  std::filesystem::path state;

  std::vector<reduced::FitTarget> targets(const std::vector<std::string>& subjects,
                                          const std::vector<std::string>& motions) const {
    std::vector<reduced::FitTarget> t;
    for (std::size_t s = 0; s < subjects.size(); ++s)
      for (const std::string& m : motions) {
        const std::string key = case_key(subjects[s], m);
        t.push_back({setup.cases.at(key).get(), static_cast<int>(s), truth.at(key).sigma()});
      }
    return t;
  }

  reduced::FitSpec spec(const std::string& name, FitKind kind, Regularizer reg, double lambda,
                        const std::vector<std::string>& subjects) const {
    reduced::FitSpec spec;
    spec.name = name;
    spec.kind = kind;
    spec.regularizer = reg;
    spec.lambda = lambda;
    for (const std::string& s : subjects) spec.betas.push_back(setup.beta_of.at(s));
    spec.stages = config.stages;
    spec.iterations = config.iterations;
    spec.loss_rtol = config.loss_rtol;
    spec.checkpoint = state / "fits" / (name + ".json");
    spec.jacobian =
        config.jacobian == "fd" ? reduced::JacobianMethod::finite_differences : reduced::JacobianMethod::sensitivities;
    spec.thickness_differences = config.jacobian == "hybrid";
    return spec;
  }
};

/// Independent fits (the optimal targets, SFLSH §3), then leave-one-out cross-validation and the λ sweep (§6.2,
/// Fig. 5): one chain per (regularizer, left-out subject), λ from the largest down; with the warm start each smaller
/// λ continues from the previous one's result at the last stage (a regularization path).
/// The leave-one-out fit of regularizer `tag` at λ without subject `left_out`; `warm` continues from the previous fit
/// of its chain (FitRunner), `from` (when given) from that fit's result directly.
ChainFit leave_one_out_fit(const FitSpecs& specs, Regularizer reg, const std::string& tag, double lambda,
                           const std::string& left_out, bool warm, const reduced::FitResult* from = nullptr) {
  const ValidateConfig& config = specs.config;
  std::vector<std::string> rest;
  for (const std::string& s : config.train_subjects)
    if (s != left_out) rest.push_back(s);
  reduced::FitSpec spec =
      specs.spec(fmt::format("cv_{}_lambda{:g}_without_{}", tag, lambda, left_out), FitKind::shape, reg, lambda, rest);
  if ((warm || from) && config.warm_iterations > 0) spec.iterations = config.warm_iterations;
  if (from) {
    spec.warm_start = from->p;
    spec.warm_start_from = from->name;
  }
  return {fmt::format("cv/{}/{:g}/{}", tag, lambda, left_out), std::move(spec),
          specs.targets(rest, config.train_motions), warm};
}

/// Independent fits (the optimal targets, SFLSH §3), then leave-one-out cross-validation and the λ sweep (§6.2,
/// Fig. 5): one chain per (regularizer, left-out subject), λ from the largest down; with the warm start each smaller
/// λ continues from the previous one's result at the last stage (a regularization path).
std::vector<FitChain> independent_and_leave_one_out_chains(const FitSpecs& specs) {
  const ValidateConfig& config = specs.config;
  std::vector<FitChain> chains;
  for (const std::string& s : config.train_subjects)
    chains.push_back(
        {{"independent/" + s, specs.spec("independent_" + s, FitKind::independent, Regularizer::l2, 0.0, {s}),
          specs.targets({s}, config.train_motions), false}});
  if (!config.cross_validation) return chains;
  for (const auto& [reg, tag] : kRegularizers) {
    std::vector<double> sweep = config.lambdas_for(tag);
    std::sort(sweep.begin(), sweep.end(), std::greater<>());
    for (const std::string& left_out : config.train_subjects) {
      FitChain chain;
      for (double lambda : sweep)
        chain.push_back(
            leave_one_out_fit(specs, reg, tag, lambda, left_out, config.lambda_warm_start && !chain.empty()));
      chains.push_back(std::move(chain));
    }
  }
  return chains;
}

/// The automatic extension of the λ grids (config.lambda_extensions, reduced/lambda_choice.hpp): while a
/// regularizer's cross-validation error is least at an end of its grid, the λ half a decade beyond that end gets its
/// leave-one-out fits (below the grid continuing from the fits at its smallest λ when the sweep is warm-started, above
/// it from the start, as the sweep's chains do) and `evaluate` scores them. `config` (the one `specs` and `report`
/// read) gets the grown grids. Returns the λs added per regularizer.
std::map<std::string, std::vector<double>> extend_lambda_grids(ValidateConfig& config, const FitSpecs& specs,
                                                               const FitRunner& runner, Report& report,
                                                               const std::function<void()>& evaluate) {
  std::map<std::string, std::vector<double>> added;
  for (int round = 0; round < config.lambda_extensions; ++round) {
    std::vector<FitChain> chains;
    for (const auto& [reg, tag] : kRegularizers) {
      const std::optional<double> lambda = reduced::lambda_beyond_grid(report.lambda_scores(tag));
      if (!lambda) continue;
      std::vector<double> grid = config.lambdas_for(tag);
      std::sort(grid.begin(), grid.end());
      const bool below = *lambda < grid.front();
      for (const std::string& left_out : config.train_subjects) {
        const reduced::FitResult* from =
            below && config.lambda_warm_start
                ? &report.fits.at(fmt::format("cv/{}/{:g}/{}", tag, grid.front(), left_out))
                : nullptr;
        chains.push_back({leave_one_out_fit(specs, reg, tag, *lambda, left_out, false, from)});
      }
      grid.push_back(*lambda);
      std::sort(grid.begin(), grid.end());
      config.lambdas_of[tag] = grid;
      added[tag].push_back(*lambda);
      logger()->info("validate: the CV error of {} is least at an end of its grid; adding λ = {:g}", tag, *lambda);
    }
    if (chains.empty()) break;
    runner.run(fmt::format("λ grid extension {}", round + 1), chains, report.fits);
    report.config.lambdas_of = config.lambdas_of;
    evaluate();
  }
  return added;
}

/// The full optimizations on every train subject (SFLSH §6.3), one per regularizer at its chosen λ.
std::vector<FitChain> full_fit_chains(const FitSpecs& specs, const std::map<std::string, double>& best_lambda) {
  const ValidateConfig& config = specs.config;
  std::vector<FitChain> chains;
  for (const auto& [reg, tag] : kRegularizers)
    chains.push_back(
        {{"full/" + tag, specs.spec("full_" + tag, FitKind::shape, reg, best_lambda.at(tag), config.train_subjects),
          specs.targets(config.train_subjects, config.train_motions), false}});
  return chains;
}

Report make_report(const ValidateConfig& config, const Setup& setup,
                   const std::map<std::string, GroundTruthCase>& truth,
                   const reduced::LayerParameterization& parameterization, const model::BodyLayer& layer) {
  Report report;
  report.config = config;
  report.bounds = setup.bounds;
  report.model = &setup.model;
  report.parameterization = &parameterization;
  report.truth = &truth;
  report.betas = setup.beta_of;
  report.poisson = layer.material.poisson;
  report.saturation = layer.material.saturation;
  report.region = layer.mesh->region;
  return report;
}

/// λ per regularizer by the config's rule from the leave-one-out errors, into `best` and report.choices.
void choose_lambdas(Report& report, std::map<std::string, double>& best) {
  for (const auto& [reg, tag] : kRegularizers) {
    const LambdaChoice choice = report.choose_lambda(tag);
    best[tag] = choice.lambda;
    report.choices[tag] = choice;
    logger()->info("validate: λ ({}) = {:g} by the {} rule (least CV error {:.3f} ± {:.3f} mm at λ = {:g})", tag,
                   choice.lambda, lambda_rule_name(report.config.lambda_rule), choice.least_error,
                   choice.standard_error, choice.least_lambda);
  }
}

}  // namespace

nlohmann::json run_validation(const ValidateConfig& requested, const std::filesystem::path& out_dir,
                              const nlohmann::json& header) {
  const auto start = std::chrono::steady_clock::now();
  ValidateConfig config = requested;  // with DYNA files, the train subjects become the files' subject ids
  check_config(config);
  RunFolder run(out_dir);
  const std::filesystem::path state = out_dir / "state";
  std::filesystem::create_directories(state / "groundtruth");
  std::filesystem::create_directories(state / "fits");

  Setup setup;
  DynaTruth dyna;
  const bool from_dyna = !config.dyna.empty();
  prepare(config, setup, from_dyna ? &dyna : nullptr);
  if (from_dyna) config.train_subjects = dyna.subjects;
  require(config.train_subjects.size() >= 2 || !config.cross_validation,
          "validate: leave-one-out cross-validation needs at least 2 train subjects, have {}",
          config.train_subjects.size());
  const body::BodyModel& model = setup.model;
  const std::vector<std::string>& all_subjects = setup.all_subjects;
  const std::vector<std::string>& all_motions = setup.all_motions;
  const model::BodyLayerOptions& layer_options = setup.layer_options;
  const material::ParameterBounds& bounds = setup.bounds;
  const std::map<std::string, body::Motion>& motions = setup.motions;
  const std::map<std::string, std::unique_ptr<reduced::DynamicsCase>>& cases = setup.cases;
  const reduced::DynamicsCase& first = *cases.at(case_key(all_subjects.front(), all_motions.front()));
  reduced::ParameterizationCache parameterizations(first.layer());

  // Ground truth (full space), one cached case per (subject, motion), shared among ranks.
  reduced::SimulationPool pool(config.threads);
  std::map<std::string, GroundTruthCase> truth;
  if (from_dyna) {
    truth = dyna_ground_truth(dyna, setup, first.layer().mesh->region_surface.vertices);
  } else {
    truth = compute_ground_truth(config, cases, motions, parameterizations, layer_options, bounds, state, pool);
    if (pool.rank() == 0)
      write_ground_truth_files(run, model, *first.layer().mesh, truth_pointers(truth), bounds, true_material(config));
  }

  // The reduced model (template discretization shared by every subject).
  reduced::ReducedModelOptions ro;
  ro.point_handles = config.point_handles;
  ro.cubature = config.cubature;
  ro.cache_dir = config.cache_dir;
  const reduced::ReducedModel reduced_model = reduced::build_reduced_model(first.layer(), ro);
  reduced::FitContext context;
  context.body = &model;
  context.model = &reduced_model;
  context.bounds = bounds;
  context.pool = &pool;
  context.parameterization = [&](int n) -> const reduced::LayerParameterization& { return parameterizations.get(n); };
  context.progress = config.progress;

  const FitSpecs specs{config, setup, truth, state};
  Report report = make_report(config, setup, truth, parameterizations.get(config.stages.back()), first.layer());
  report.true_parameters = !from_dyna;

  // The fits run as chains (fit_chains.hpp), shared among fit groups of MPI ranks with --fit-groups.
  const FitRunner runner(context, config.fit_groups, config.threads);
  // Independent fits: the optimal targets (SFLSH §3).
  std::map<std::string, double> best_lambda;
  for (const auto& [reg, tag] : kRegularizers) best_lambda[tag] = config.lambdas_for(tag).front();
  runner.run("independent and leave-one-out fits", independent_and_leave_one_out_chains(specs), report.fits);
  // Evaluate everything fitted so far, then pick λ per regularizer from the cross-validation errors.
  const auto evaluate = [&] { report.evaluate(pool, reduced_model, context.reduced, cases); };
  evaluate();
  std::map<std::string, std::vector<double>> lambdas_added;
  if (config.cross_validation) {
    lambdas_added = extend_lambda_grids(config, specs, runner, report, evaluate);
    choose_lambdas(report, best_lambda);
  }
  // Full optimizations on every train subject (SFLSH §6.3) and their generalization (§6.4).
  runner.run("full fits", full_fit_chains(specs, best_lambda), report.fits);
  evaluate();
  report.best = best_lambda;

  nlohmann::json summary = header;
  summary["config"] = config.to_json();  // with the grids as extended
  summary["lambdas_added"] = nlohmann::json::object();
  for (const auto& [tag, added] : lambdas_added) summary["lambdas_added"][tag] = added;
  summary["bounds"] = {{"thickness", {bounds.thickness.min, bounds.thickness.max}},
                       {"young_tangent", {bounds.young_tangent.min, bounds.young_tangent.max}},
                       {"young_normal", {bounds.young_normal.min, bounds.young_normal.max}}};
  summary["reduced_model"] = {{"point_handles", config.point_handles},
                              {"coordinates", reduced_model.subspace.num_dofs()},
                              {"cubature", reduced_model.cubature.size()}};
  if (from_dyna) summary["dyna"] = dyna_summary(dyna);
  summary["simulations"] = pool.simulations() + runner.group_simulations();
  // The work per rank: Σ / max is the speed-up P ranks on P free cores would see (docs/fit.md, fit groups).
  summary["rank_task_cpu_seconds"] = runner.rank_task_cpu_seconds();
  summary["simulation_seconds"] = pool.seconds();
  summary["ranks"] = pool.ranks();
  summary["threads"] = pool.threads();
  if (pool.rank() == 0) {
    report.write(run, summary);
    write_summary(run, summary, seconds_since(start), {.seconds = true});
    run.commit();
  }
  return summary;
}

nlohmann::json run_ground_truth(const ValidateConfig& config, const std::filesystem::path& out_dir,
                                const nlohmann::json& header) {
  const auto start = std::chrono::steady_clock::now();
  require(!config.train_subjects.empty() || !config.test_subjects.empty(), "groundtruth: no subjects");
  require(!config.train_motions.empty() || !config.test_motions.empty(), "groundtruth: no motions");
  RunFolder run(out_dir);
  const std::filesystem::path state = out_dir / "state";
  std::filesystem::create_directories(state / "groundtruth");
  Setup setup;
  prepare(config, setup);
  const reduced::DynamicsCase& first = *setup.cases.begin()->second;
  reduced::ParameterizationCache parameterizations(first.layer());
  const reduced::SimulationPool pool(config.threads);
  const std::map<std::string, GroundTruthCase> truth = compute_ground_truth(
      config, setup.cases, setup.motions, parameterizations, setup.layer_options, setup.bounds, state, pool);
  nlohmann::json summary = header;
  summary["config"] = config.to_json();
  for (const auto& [key, c] : truth)
    summary["cases"].push_back({{"key", key},
                                {"subject", c.subject},
                                {"motion", c.motion},
                                {"frames", c.posed.size()},
                                {"sigma_mean_mm", c.mean_sigma()},
                                {"seconds", c.seconds}});
  if (pool.rank() == 0) {
    write_ground_truth_files(run, setup.model, *first.layer().mesh, truth_pointers(truth), setup.bounds,
                             true_material(config));
    write_summary(run, summary, seconds_since(start), {.seconds = true});
    run.commit();
  }
  return summary;
}

}  // namespace sflsh::validate
