// The experiment pipeline of `sflsh validate` (experiments.hpp): ground truth → reduced cases → fits →
// evaluations → reports (report.cpp).
#include <sflsh/validate/experiments.hpp>

#include <sflsh/body/body_io.hpp>
#include <sflsh/body/subjects.hpp>
#include <sflsh/core/error.hpp>
#include <sflsh/core/log.hpp>
#include <sflsh/core/run_folder.hpp>
#include <sflsh/meshing/layer_cache.hpp>
#include <sflsh/reduced/elasticity_fit.hpp>
#include <sflsh/validate/ground_truth.hpp>

#include "report.hpp"

#include <sflsh/core/progress.hpp>
#include <sflsh/core/summary.hpp>

#include <chrono>
#include <map>
#include <set>

namespace sflsh::validate {

namespace {

using reduced::FitKind;
using reduced::Regularizer;

double default_thickness_max(meshing::SizePreset size) {
  // The largest uniform thickness every subject's retarget keeps valid (docs/meshing.md).
  switch (size) {
    case meshing::SizePreset::coarse: return 0.6;
    case meshing::SizePreset::medium: return 0.8;
    case meshing::SizePreset::fine: return 0.9;
  }
  return 0.6;
}

std::string case_key(const std::string& subject, const std::string& motion) { return subject + "_" + motion; }

/// The ground truth of every case, computed (round robin over ranks) or loaded from state/groundtruth.
std::map<std::string, GroundTruthCase> compute_ground_truth(
    const ValidateConfig& config, const std::map<std::string, std::unique_ptr<reduced::DynamicsCase>>& cases,
    const std::map<std::string, body::Motion>& motions, reduced::ParameterizationCache& parameterizations,
    const fullspace::BodyLayerOptions& layer_options, const material::ParameterBounds& bounds,
    const std::filesystem::path& state, const reduced::SimulationPool& pool) {
  std::map<std::string, GroundTruthCase> truth;
  GroundTruthOptions gto;
  gto.bounds = bounds;
  std::vector<std::string> keys;
  for (const auto& [key, c] : cases) keys.push_back(key);
  Progress progress("ground truth (full space)", keys.size(), config.progress && pool.rank() == 0);
  for (std::size_t k = 0; k < keys.size(); ++k) {
    if (static_cast<int>(k) % pool.ranks() != pool.rank()) continue;
    const std::filesystem::path file = state / "groundtruth" / (keys[k] + ".npz");
    GroundTruthCase c;
    if (!load_ground_truth_case(file, c)) {
      const reduced::DynamicsCase& dc = *cases.at(keys[k]);
      c = simulate_ground_truth(dc.layer(), motions.at(dc.motion()), dc.subject(), parameterizations.get(1), layer_options, gto);
      save_ground_truth_case(file, c);
    }
    progress.advance();
  }
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (initialized && pool.ranks() > 1) MPI_Barrier(MPI_COMM_WORLD);
  for (const std::string& key : keys) {
    GroundTruthCase c;
    require(load_ground_truth_case(state / "groundtruth" / (key + ".npz"), c), "validate: ground truth {} is missing", key);
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
  fullspace::BodyLayerOptions layer_options;
  material::ParameterBounds bounds;
  std::map<std::string, body::Motion> motions;
  std::map<std::string, std::unique_ptr<reduced::DynamicsCase>> cases;
};

void prepare(const ValidateConfig& config, Setup& s) {
  s.model = body::load_body(body::default_body_path());
  const std::vector<body::Subject> subjects = body::default_subjects();
  s.all_subjects = config.train_subjects;
  s.all_subjects.insert(s.all_subjects.end(), config.test_subjects.begin(), config.test_subjects.end());
  for (const std::string& name : s.all_subjects) s.beta_of[name] = body::find_subject(subjects, name).beta;
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
      s.cases.emplace(case_key(name, m),
                      std::make_unique<reduced::DynamicsCase>(s.model, name, s.beta_of.at(name), s.motions.at(m), s.layer_options));
      progress.advance();
    }
}

}  // namespace

nlohmann::json run_validation(const ValidateConfig& config, const std::filesystem::path& out_dir, const nlohmann::json& header) {
  const auto start = std::chrono::steady_clock::now();
  require(!config.train_subjects.empty(), "validate: no train subjects");
  require(config.train_subjects.size() >= 2 || !config.cross_validation,
          "validate: leave-one-out cross-validation needs at least 2 train subjects");
  require(!config.train_motions.empty() && !config.test_motions.empty(), "validate: train and test motions are required");
  require(!config.stages.empty(), "validate: no control-point stages");
  for (double l : config.lambdas) require(l > 0.0 && std::isfinite(l), "validate: λ must be positive, got {}", l);
  require(!config.lambdas.empty(), "validate: no λ values");
  RunFolder run(out_dir);
  const std::filesystem::path state = out_dir / "state";
  std::filesystem::create_directories(state / "groundtruth");
  std::filesystem::create_directories(state / "fits");

  Setup setup;
  prepare(config, setup);
  const body::BodyModel& model = setup.model;
  const std::map<std::string, body::Betas>& beta_of = setup.beta_of;
  const std::vector<std::string>& all_subjects = setup.all_subjects;
  const std::vector<std::string>& all_motions = setup.all_motions;
  const fullspace::BodyLayerOptions& layer_options = setup.layer_options;
  const material::ParameterBounds& bounds = setup.bounds;
  const std::map<std::string, body::Motion>& motions = setup.motions;
  const std::map<std::string, std::unique_ptr<reduced::DynamicsCase>>& cases = setup.cases;
  const reduced::DynamicsCase& first = *cases.at(case_key(all_subjects.front(), all_motions.front()));
  reduced::ParameterizationCache parameterizations(first.layer());

  // Ground truth (full space), one cached case per (subject, motion), shared among ranks.
  reduced::SimulationPool pool(config.threads);
  const std::map<std::string, GroundTruthCase> truth =
      compute_ground_truth(config, cases, motions, parameterizations, layer_options, bounds, state, pool);
  if (pool.rank() == 0) write_ground_truth_files(run, model, *first.layer().mesh, truth_pointers(truth), bounds);

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

  auto targets_of = [&](const std::vector<std::string>& subject_list, const std::vector<std::string>& motion_list) {
    std::vector<reduced::FitTarget> t;
    for (std::size_t s = 0; s < subject_list.size(); ++s)
      for (const std::string& m : motion_list) {
        const std::string key = case_key(subject_list[s], m);
        t.push_back({cases.at(key).get(), static_cast<int>(s), truth.at(key).sigma()});
      }
    return t;
  };
  auto betas_of = [&](const std::vector<std::string>& subject_list) {
    std::vector<body::Betas> b;
    for (const std::string& s : subject_list) b.push_back(beta_of.at(s));
    return b;
  };
  auto spec_of = [&](const std::string& name, FitKind kind, Regularizer reg, double lambda,
                     const std::vector<std::string>& subject_list) {
    reduced::FitSpec spec;
    spec.name = name;
    spec.kind = kind;
    spec.regularizer = reg;
    spec.lambda = lambda;
    spec.betas = betas_of(subject_list);
    spec.stages = config.stages;
    spec.iterations = config.iterations;
    spec.checkpoint = state / "fits" / (name + ".json");
    return spec;
  };

  Report report;
  report.config = config;
  report.bounds = bounds;
  report.model = &model;
  report.parameterization = &parameterizations.get(config.stages.back());
  report.truth = &truth;

  // Independent fits: the optimal targets (SFLSH §3).
  for (const std::string& s : config.train_subjects)
    report.fits.emplace("independent/" + s, reduced::fit_elasticity(context, targets_of({s}, config.train_motions),
                                                                     spec_of("independent_" + s, FitKind::independent,
                                                                             Regularizer::l2, 0.0, {s})));
  // Leave-one-out cross-validation and the λ sweep (SFLSH §6.2, Fig. 5).
  const std::vector<std::pair<Regularizer, std::string>> regs{{Regularizer::l2, "l2"}, {Regularizer::local, "ours"}};
  std::map<std::string, double> best_lambda;
  for (const auto& [reg, tag] : regs) {
    best_lambda[tag] = config.lambdas.front();
    if (!config.cross_validation) continue;
    for (double lambda : config.lambdas)
      for (const std::string& left_out : config.train_subjects) {
        std::vector<std::string> rest;
        for (const std::string& s : config.train_subjects)
          if (s != left_out) rest.push_back(s);
        const std::string name = fmt::format("cv_{}_lambda{:g}_without_{}", tag, lambda, left_out);
        report.fits.emplace(fmt::format("cv/{}/{:g}/{}", tag, lambda, left_out),
                            reduced::fit_elasticity(context, targets_of(rest, config.train_motions),
                                                    spec_of(name, FitKind::shape, reg, lambda, rest)));
      }
  }
  // Evaluate everything fitted so far, then pick λ per regularizer by the cross-validation error.
  report.evaluate(pool, reduced_model, context.reduced, cases);
  if (config.cross_validation)
    for (const auto& [reg, tag] : regs) best_lambda[tag] = report.best_lambda(tag);
  // Full optimizations on every train subject (SFLSH §6.3) and their generalization (§6.4).
  for (const auto& [reg, tag] : regs)
    report.fits.emplace("full/" + tag, reduced::fit_elasticity(context, targets_of(config.train_subjects, config.train_motions),
                                                               spec_of("full_" + tag, FitKind::shape, reg, best_lambda.at(tag),
                                                                       config.train_subjects)));
  report.evaluate(pool, reduced_model, context.reduced, cases);
  report.best = best_lambda;

  nlohmann::json summary = header;
  summary["config"] = config.to_json();
  summary["bounds"] = {{"thickness", {bounds.thickness.min, bounds.thickness.max}},
                       {"young_tangent", {bounds.young_tangent.min, bounds.young_tangent.max}},
                       {"young_normal", {bounds.young_normal.min, bounds.young_normal.max}}};
  summary["reduced_model"] = {{"point_handles", config.point_handles},
                              {"coordinates", reduced_model.subspace.num_dofs()},
                              {"cubature", reduced_model.cubature.size()}};
  summary["simulations"] = pool.simulations();
  summary["simulation_seconds"] = pool.seconds();
  summary["ranks"] = pool.ranks();
  summary["threads"] = pool.threads();
  if (pool.rank() == 0) {
    report.write(run, summary);
    summary["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    write_json(run.stage("summary.json"), summary);
    run.commit();
  }
  return summary;
}

nlohmann::json run_ground_truth(const ValidateConfig& config, const std::filesystem::path& out_dir, const nlohmann::json& header) {
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
    summary["cases"].push_back({{"key", key}, {"subject", c.subject}, {"motion", c.motion}, {"frames", c.posed.size()},
                                {"sigma_mean_mm", c.mean_sigma()}, {"seconds", c.seconds}});
  if (pool.rank() == 0) {
    write_ground_truth_files(run, setup.model, *first.layer().mesh, truth_pointers(truth), setup.bounds);
    summary["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    write_json(run.stage("summary.json"), summary);
    run.commit();
  }
  return summary;
}

}  // namespace sflsh::validate
